// Contact, judged once the round's operations are chosen (rounds.hpp): a
// chosen operation whose new faces would meet a face they share no corner
// with is dropped from the round. Judged there, not with the other legality
// tests (legality.hpp), for two reasons. It is the costliest test, and the
// choice tests many operations for each one it takes (the device's dry runs
// test every one). And the other tests see the round's start only, whereas
// two operations chosen together, apart in the surface (path length >= 2)
// but close in space (two sheets of a fold), could push their new faces
// through each other: here each is also set against the new faces of the
// chosen operations before it (higher priority, then higher ends, the
// choice's order).
//
// The round's faces, the obstacles (ReduceOptions::obstacles) and the new
// faces of every chosen operation go into one grid (contact.hpp). An
// operation is kept when each of its new faces stays clear of
//  - every face of the round near it, other than those it replaces and those
//    sharing a corner with it (there legality.hpp's cones and
//    clear_of_neighbours judge), unless a face it replaces met that face
//    already (a contact the input had is no new one: where extraction left
//    coincident vertices, cleaning them up must stay possible);
//  - every obstacle, other than at a corner it shares by position;
//  - every new face of a chosen operation before it that shares no corner
//    with it.
// A verdict reads the chosen set, never another verdict, so the dropped set
// is the same on every backend and thread count. A dropped collapse's
// samples go back to the faces they were on (its test had moved them onto
// faces that now stay as they were); a dropped operation is not refused:
// the next round tests it again. The faces of a batch's pieces are judged
// against their own piece's only (batch.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "../hd.hpp"
#include "contact.hpp"
#include "criterion.hpp"
#include "round_view.hpp"

namespace tetiso::reduction {

// A new face of an operation: its corners' vertices (-1 for a collapse's new
// vertex), their positions, its unit normal (quality()'s; zero when
// degenerate), and the face or faces it replaces, for "met already".
struct NewFace {
    i32 id[3];
    Vec at[3];
    Vec n;
    Vec old[2][3];
    int olds;
};

// visit(face) for every new face of chosen operation e, in a fixed order.
template <class Visit>
TETISO_HD void for_each_new_face(const RoundView& m, const OpsView& ops, i32 e, const Visit& visit) {
    if (ops.kind[e] == kFlip) {
        // f1 = (u, w, c), f2 = (w, u, d) become (c, u, d) and (d, w, c), as
        // propose_flip judged them.
        const EdgeSlots r = slots(m, e, false);
        const Vec pu = m.s.pos(r.u), pw = m.s.pos(r.w), pc = m.s.pos(r.c), pd = m.s.pos(r.d);
        NewFace f{{r.c, r.u, r.d}, {pc, pu, pd}, {0, 0, 0}, {{pu, pw, pc}, {pw, pu, pd}}, 2};
        quality(pc, pu, pd, &f.n);
        visit(f);
        f = NewFace{{r.d, r.w, r.c}, {pd, pw, pc}, {0, 0, 0}, {{pu, pw, pc}, {pw, pu, pd}}, 2};
        quality(pd, pw, pc, &f.n);
        visit(f);
        return;
    }
    const EdgeSlots r = slots(m, e);
    const Vec p{ops.px[e], ops.py[e], ops.pz[e]};
    for_each_leaf_face(r, [&](i32 slot, bool removed) {
        if (removed) return;
        const i32 ia = m.fans.next[slot], ib = m.fans.prev[slot];
        const i32 end = slot < r.ou + r.ku ? r.u : r.w;
        const Vec a = m.s.pos(ia), b = m.s.pos(ib);
        NewFace f{{-1, ia, ib}, {p, a, b}, {0, 0, 0}, {{m.s.pos(end), a, b}, {}}, 1};
        quality(p, a, b, &f.n);
        visit(f);
    });
}

TETISO_HD inline i32 new_face_count(const RoundView& m, const OpsView& ops, i32 e) {
    i32 count = 0;
    for_each_new_face(m, ops, e, [&](const NewFace&) { ++count; });
    return count;
}

// Whether chosen operation a comes before chosen operation b.
TETISO_HD inline bool chosen_before(const OpsView& ops, const EdgesView& edges, i32 a, i32 b) {
    if (ops.priority[a] != ops.priority[b]) return ops.priority[a] > ops.priority[b];
    if (edges.v0[a] != edges.v0[b]) return edges.v0[a] > edges.v0[b];
    return edges.v1[a] > edges.v1[b];
}

TETISO_HD inline bool same(Vec a, Vec b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Whether triangle e of the grid is one that face f shares a corner with:
// by vertex, or for an obstacle (whose corners are no vertices of the
// piece; a locked rim vertex keeps its position bit for bit) by position.
TETISO_HD inline bool shares_corner(const NewFace& f, const ContactTriangle& t) {
    for (int c = 0; c < 3; ++c) {
        if (t.obstacle()) {
            if (same(f.at[c], t.corner(0)) || same(f.at[c], t.corner(1)) || same(f.at[c], t.corner(2))) return true;
        } else if (f.id[c] >= 0 && (f.id[c] == t.id[0] || f.id[c] == t.id[1] || f.id[c] == t.id[2])) {
            return true;
        }
    }
    return false;
}

// Whether chosen operation e's new faces stay clear (see the top).
TETISO_HD inline bool clear_of_contact(const RoundView& m, const OpsView& ops, const ContactGridView& g, i32 e) {
    if (!g.on) return true;
    const i32 u = m.edges.v0[e], w = m.edges.v1[e];
    const bool flip = ops.kind[e] == kFlip;
    const i32 piece = g.vertex_piece ? g.vertex_piece[u] : 0;
    Box box{m.s.pos(u), m.s.pos(u)};
    for_each_new_face(m, ops, e, [&](const NewFace& f) {
        for (const Vec& q : f.at) box.add(q);
    });
    const double reach = std::max({std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z), std::abs(box.hi.x),
                                   std::abs(box.hi.y), std::abs(box.hi.z)});
    const double margin = kContactUlps * std::numeric_limits<float>::epsilon() * reach;
    // A face of the round the operation rewrites: a collapse's every face
    // at u or w, a flip's two faces at both u and w.
    const auto replaced = [&](const ContactTriangle& t) {
        const bool at_u = t.id[0] == u || t.id[1] == u || t.id[2] == u;
        const bool at_w = t.id[0] == w || t.id[1] == w || t.id[2] == w;
        return flip ? at_u && at_w : at_u || at_w;
    };
    // The triangles near the box are gathered, a few dozen at a time, and
    // each new face is then set against them: a face's corners and box are
    // made once per batch rather than once per triangle.
    constexpr int kBatch = 64;
    i32 near[kBatch];
    int count = 0;
    const auto clear = [&] {
        bool ok = true;
        for_each_new_face(m, ops, e, [&](const NewFace& f) {
            if (!ok) return;
            const Box fb = box_of(f.at[0], f.at[1], f.at[2]);
            for (int j = 0; j < count && ok; ++j) {
                const ContactTriangle& t = g.triangles[near[j]];
                if (fb.apart(g.boxes[near[j]].box(), margin) || shares_corner(f, t)) continue;
                const Vec px = t.corner(0), py = t.corner(1), pz = t.corner(2);
                if (!triangles_meet(f.at[0], f.at[1], f.at[2], f.n, px, py, pz)) continue;
                bool had_met = false;
                for (int o = 0; o < f.olds && !t.made() && !had_met; ++o)
                    had_met = triangles_meet(f.old[o][0], f.old[o][1], f.old[o][2], px, py, pz);
                ok = had_met;
            }
        });
        count = 0;
        return ok;
    };
    return for_each_triangle_near(g, box, margin, [&](i32 k) {
        const ContactTriangle& t = g.triangles[k];
        if (t.made()) {
            if (t.op == e || !chosen_before(ops, m.edges, t.op, e)) return true;
        } else if (!t.obstacle() && replaced(t)) {
            return true;
        }
        if (!t.obstacle() && g.vertex_piece && g.vertex_piece[t.id[0]] != piece) return true;
        if (count == kBatch && !clear()) return false;
        near[count++] = k;
        return true;
    }) && clear();
}

template <class Exec>
struct ContactFilter {
    template <class T>
    using Array = typename Exec::template Array<T>;
    ContactGrid<Exec> grid;
    Array<i32> chosen;
    Array<u32> first_face;
};

// The faces beside the piece that its new faces must stay clear of, for
// every round (ReduceOptions::obstacles).
template <class Exec>
void load_obstacles(Exec& exec, const std::vector<float>& obstacles, ContactFilter<Exec>& cf) {
    cf.grid.obstacles = static_cast<i32>(obstacles.size() / 9);
    exec.upload(obstacles, cf.grid.obstacle);
}

// Drops the chosen operations (chosen[e] set, among ne edges) that fail
// clear_of_contact; owner: the samples' owners (null without samples).
template <class Exec>
void drop_contacts(Exec& exec, ContactFilter<Exec>& cf, const RoundView& m, const OpsView& ops, i32 ne, u8* chosen,
                   i32* owner, const i32* vertex_piece) {
    const i32 count = exec.filter(ne, [=] TETISO_HD(i64 e) { return chosen[e] != 0; }, cf.chosen);
    if (count == 0) return;
    const i32* list = cf.chosen.data();
    const u64 faces = exec.exclusive_sum(
        count, [=] TETISO_HD(i64 k) { return static_cast<u32>(new_face_count(m, ops, list[k])); }, cf.first_face);
    cf.grid.made.resize(static_cast<std::size_t>(faces));
    ContactTriangle* made = cf.grid.made.data();
    const u32* first = cf.first_face.data();
    exec.for_each(count, [=] TETISO_HD(i64 k) {
        const i32 e = list[k];
        u32 at = first[k];
        for_each_new_face(m, ops, e, [&](const NewFace& f) {
            // A collapse's new vertex last, so that corner 0 is a vertex
            // of the piece (the grid reads its piece there).
            const int shift = f.id[0] < 0 ? 1 : 0;
            ContactTriangle& t = made[at++];
            for (int c = 0; c < 3; ++c) {
                const int from = (c + shift) % 3;
                t.id[c] = f.id[from] < 0 ? -3 : f.id[from];
                t.at[3 * c] = static_cast<float>(f.at[from].x);
                t.at[3 * c + 1] = static_cast<float>(f.at[from].y);
                t.at[3 * c + 2] = static_cast<float>(f.at[from].z);
            }
            t.op = e;
        });
    });
    build_contact_grid(exec, m.s, vertex_piece, static_cast<i32>(faces), cf.grid);
    const ContactGridView g = cf.grid.view();
    exec.for_each(count, [=] TETISO_HD(i64 k) {
        const i32 e = list[k];
        if (clear_of_contact(m, ops, g, e)) return;
        chosen[e] = 0;
        if (!owner || ops.kind[e] == kFlip) return; // a flip's samples move after this
        for_each_leaf_face(slots(m, e), [&](i32 slot, bool) {
            const i32 t = m.face(slot);
            for (i32 sample = m.geo[t].samples_begin; sample < m.geo[t].samples_end; ++sample) owner[sample] = t;
        });
    }, Exec::Grain::kTests);
}

} // namespace tetiso::reduction
