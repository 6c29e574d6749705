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

// Whether triangle t of the grid is one that face f shares a corner with:
// by vertex, or for an obstacle (whose corners are no vertices of the
// piece; a locked rim vertex keeps its position bit for bit) by position.
// f: a new face as drop_contacts lays it out among the grid's made faces.
TETISO_HD inline bool shares_corner(const ContactTriangle& f, const ContactTriangle& t) {
    for (int c = 0; c < 3; ++c) {
        if (t.obstacle()) {
            const Vec at = f.corner(c);
            if (same(at, t.corner(0)) || same(at, t.corner(1)) || same(at, t.corner(2))) return true;
        } else if (f.id[c] >= 0 && (f.id[c] == t.id[0] || f.id[c] == t.id[1] || f.id[c] == t.id[2])) {
            return true;
        }
    }
    return false;
}

// A chosen operation's query of the grid (contact.hpp) and its margin: the
// box of its new faces and of u, the margin a few ulps of its largest
// coordinate.
struct ChosenQuery {
    ContactQuery query;
    double margin;
};
TETISO_HD inline ChosenQuery chosen_query(const ContactGridView& g, Vec at_u, const ContactTriangle* faces, i32 count) {
    Box box{at_u, at_u};
    for (i32 j = 0; j < count; ++j)
        for (int c = 0; c < 3; ++c) box.add(faces[j].corner(c));
    const double reach = std::max({std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z), std::abs(box.hi.x),
                                   std::abs(box.hi.y), std::abs(box.hi.z)});
    const double margin = kContactUlps * std::numeric_limits<float>::epsilon() * reach;
    return {contact_query(g, box, margin), margin};
}

// Whether new face `index` of chosen operation e met triangle t (of the
// round) already before the operation, through a face it replaces.
TETISO_HD inline bool had_met(const RoundView& m, const OpsView& ops, i32 e, i32 index, const ContactTriangle& t) {
    bool met = false;
    i32 at = 0;
    for_each_new_face(m, ops, e, [&](const NewFace& f) {
        if (at++ != index) return;
        for (int o = 0; o < f.olds && !met; ++o)
            met = triangles_meet(f.old[o][0], f.old[o][1], f.old[o][2], t.corner(0), t.corner(1), t.corner(2));
    });
    return met;
}

// The test of the chosen operations (see the top), one item of one
// operation's query at a time: list[k] is the operation, made[first_face[k]
// .. first_face[k + 1]) its new faces and made_box their boxes, queries[k]
// its query.
struct ContactJudge {
    RoundView m;
    OpsView ops;
    ContactGridView g;
    const i32* list;
    const u32* first_face;
    const ContactTriangle* made;
    const FloatBox* made_box;
    const ChosenQuery* queries;

    // Calls visit(j, entry) for every pair of a new face j of operation k
    // (made[j]) and triangle `entry` of the grid (g.triangles[entry]) that
    // the face must stay clear of and whose boxes come within the margin,
    // until visit returns false; whether none did.
    template <class Visit>
    TETISO_HD bool for_each_pair_with(i32 k, i32 entry, const Visit& visit) const {
        const i32 e = list[k];
        const i32 u = m.edges.v0[e], w = m.edges.v1[e];
        const ContactTriangle& t = g.triangles[entry];
        if (t.made()) {
            if (t.op == e || !chosen_before(ops, m.edges, t.op, e)) return true;
        } else if (!t.obstacle()) {
            // A face of the round the operation rewrites: a collapse's every
            // face at u or w, a flip's two faces at both u and w.
            const bool at_u = t.id[0] == u || t.id[1] == u || t.id[2] == u;
            const bool at_w = t.id[0] == w || t.id[1] == w || t.id[2] == w;
            if (ops.kind[e] == kFlip ? at_u && at_w : at_u || at_w) return true;
        }
        if (!t.obstacle() && g.vertex_piece && g.vertex_piece[t.vertex()] != g.vertex_piece[u]) return true;
        const Box tb = g.boxes[entry].box();
        const double margin = queries[k].margin;
        for (u32 j = first_face[k], end = first_face[k + 1]; j < end; ++j) {
            if (made_box[j].box().apart(tb, margin) || shares_corner(made[j], t)) continue;
            if (!visit(j, entry)) return false;
        }
        return true;
    }

    // The same for every triangle of item `item` of operation k's query.
    template <class Visit>
    TETISO_HD bool for_each_pair(i32 k, i64 item, const Visit& visit) const {
        return for_each_entry_of_item(g, queries[k].query, item,
                                      [&](i32 entry) { return for_each_pair_with(k, entry, visit); });
    }

    // Whether new face j of operation k (made[j]) meets triangle `entry` of
    // the grid, and did not through a face it replaces.
    TETISO_HD bool new_contact(i32 k, u32 j, i32 entry) const {
        const ContactTriangle& t = g.triangles[entry];
        const Vec f0 = made[j].corner(0), f1 = made[j].corner(1), f2 = made[j].corner(2);
        Vec n;
        quality(f0, f1, f2, &n);
        if (!triangles_meet(f0, f1, f2, n, t.corner(0), t.corner(1), t.corner(2))) return false;
        return t.made() || !had_met(m, ops, list[k], static_cast<i32>(j - first_face[k]), t);
    }

    // Whether item `item` of operation k's query finds none of its new faces
    // in contact with a face it must stay clear of.
    TETISO_HD bool clear_item(i32 k, i64 item) const {
        return for_each_pair(k, item, [&](u32 j, i32 entry) { return !new_contact(k, j, entry); });
    }
};

// On the device, the pairs an operation's items find wait in this many
// places per operation for the exact tests (in the reduction of the N = 100
// paper surface, 0.09 % of the operations found more, 3.5 % more than 32);
// an item whose pair finds no place tests its pairs itself.
constexpr i32 kContactPairsPerOp = 64;
// On the device a thread reads at most this many entries of an item (a
// bucket, the large triangles, or every triangle).
constexpr i32 kContactChunk = 16;

struct ContactPair {
    i32 entry;
    u32 face;
};

// The k with first[k] <= item < first[k + 1], among count ranges.
TETISO_HD inline i32 range_of(const u32* first, i32 count, i64 item) {
    i32 lo = 0, hi = count - 1;
    while (lo < hi) {
        const i32 mid = lo + (hi - lo + 1) / 2;
        if (static_cast<i64>(first[mid]) <= item) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

template <class Exec>
struct ContactFilter {
    template <class T>
    using Array = typename Exec::template Array<T>;
    ContactGrid<Exec> grid;
    Array<i32> chosen;
    Array<u32> first_face, first_item, first_chunk;
    Array<ChosenQuery> queries;
    Array<u8> dropped;
    Array<i32> overflowed;
    Array<i32> pair_count;
    Array<u32> first_pair;
    Array<ContactPair> pairs;
    Array<i64> overflow_count, overflow_items;
};

// The faces beside the piece that its new faces must stay clear of, for
// every round (ReduceOptions::obstacles).
template <class Exec>
void load_obstacles(Exec& exec, const std::vector<float>& obstacles, ContactFilter<Exec>& cf) {
    cf.grid.obstacles = static_cast<i32>(obstacles.size() / 9);
    exec.upload(obstacles, cf.grid.obstacle);
}

// Drops the chosen operations (chosen[e] set, among ne edges) that fail
// ContactJudge; owner: the samples' owners (null without samples).
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
            // In for_each_new_face's order, so that the tests round as they
            // would on the face itself.
            ContactTriangle& t = made[at++];
            for (int c = 0; c < 3; ++c) {
                t.id[c] = f.id[c] < 0 ? -3 : f.id[c];
                t.at[3 * c] = static_cast<float>(f.at[c].x);
                t.at[3 * c + 1] = static_cast<float>(f.at[c].y);
                t.at[3 * c + 2] = static_cast<float>(f.at[c].z);
            }
            t.op = e;
        });
    });
    build_contact_grid(exec, m.s, vertex_piece, static_cast<i32>(faces), cf.grid);
    const ContactGridView g = cf.grid.view();
    if (!g.on) return;
    cf.queries.resize(static_cast<std::size_t>(count));
    cf.dropped.resize(static_cast<std::size_t>(count));
    ChosenQuery* queries = cf.queries.data();
    u8* dropped = cf.dropped.data();
    // build_contact_grid boxed the made faces after the round's and the
    // obstacles.
    const FloatBox* made_box = cf.grid.box.data() + m.s.nt + cf.grid.obstacles;
    const ContactJudge judge{m, ops, g, list, first, made, made_box, queries};
    exec.for_each(count, [=] TETISO_HD(i64 k) {
        queries[k] = chosen_query(g, m.s.pos(m.edges.v0[list[k]]), made + first[k],
                                  static_cast<i32>(first[k + 1] - first[k]));
        dropped[k] = 0;
    });
    if constexpr (Exec::kHost) {
        exec.for_each(count, [=](i64 k) {
            for (i64 item = 0, items = queries[k].query.items(); item < items; ++item)
                if (!judge.clear_item(static_cast<i32>(k), item)) {
                    dropped[k] = 1;
                    return;
                }
        }, Exec::Grain::kTests);
    } else {
        // On the device the entries of every item (a bucket) of every query
        // are read in chunks of kContactChunk, a thread each, and every exact
        // test of a face against a triangle is a thread of its own. A thread
        // per operation left a warp waiting, most of its threads done, on the
        // few whose buckets held the most; a thread per item did too (2.7 of
        // a warp's 32 threads at work, Nsight Compute), most buckets holding
        // none or one; so an empty bucket takes no thread. The exact tests,
        // a few per operation, ran a thread or two of a warp at a time where
        // they ran beside the reading of the buckets.
        const u64 items = exec.exclusive_sum(
            count, [=] TETISO_HD(i64 k) { return static_cast<u32>(queries[k].query.items()); }, cf.first_item);
        const u32* first_item = cf.first_item.data();
        const auto span_of = [=] TETISO_HD(i64 item, i32& k) {
            k = range_of(first_item, count, item);
            return item_span(g, queries[k].query, item - first_item[k]);
        };
        const u64 chunks = exec.exclusive_sum(static_cast<i64>(items), [=] TETISO_HD(i64 item) {
            i32 k;
            const ItemSpan span = span_of(item, k);
            return static_cast<u32>((span.end - span.begin + kContactChunk - 1) / kContactChunk);
        }, cf.first_chunk);
        const u32* first_chunk = cf.first_chunk.data();
        exec.assign(cf.pair_count, count, i32{0});
        exec.assign(cf.overflow_count, 1, i64{0});
        exec.assign(cf.overflowed, static_cast<i64>(items), i32{0});
        cf.pairs.resize(static_cast<std::size_t>(count) * kContactPairsPerOp);
        cf.overflow_items.resize(static_cast<std::size_t>(items));
        i32* pair_count = cf.pair_count.data();
        ContactPair* pairs = cf.pairs.data();
        i32* overflowed = cf.overflowed.data();
        i64 *overflow_count = cf.overflow_count.data(), *overflow_items = cf.overflow_items.data();
        // Place p of operation k at p * count + k: a warp's threads then
        // write the p-th pairs of 32 operations. An item one of whose pairs
        // finds no place is listed, once, to test its pairs itself.
        exec.for_each(static_cast<i64>(chunks), [=] TETISO_HD(i64 chunk) {
            const i64 item = range_of(first_chunk, static_cast<i32>(items), chunk);
            i32 k;
            const ItemSpan span = span_of(item, k);
            const ContactQuery& q = queries[k].query;
            const i32 begin = span.begin + static_cast<i32>(chunk - first_chunk[item]) * kContactChunk;
            const i32 end = std::min(span.end, begin + kContactChunk);
            for (i32 entry = begin; entry < end; ++entry) {
                if (!entry_read(g, q, span, entry)) continue;
                const bool placed = judge.for_each_pair_with(k, entry, [&](u32 j, i32 at_entry) {
                    const i32 at = hd::atomic_add(pair_count + k, 1);
                    if (at >= kContactPairsPerOp) return false;
                    pairs[static_cast<i64>(at) * count + k] = ContactPair{at_entry, j};
                    return true;
                });
                if (!placed) {
                    if (hd::atomic_add(overflowed + item, 1) == 0)
                        overflow_items[hd::atomic_add(overflow_count, i64{1})] = item;
                    return;
                }
            }
        });
        // A thread per pair found: most operations find a few, so a thread
        // per place (kContactPairsPerOp an operation) left most threads
        // with nothing to test. An operation's pairs are its places below
        // its count (at most kContactPairsPerOp).
        const u64 found = exec.exclusive_sum(
            count, [=] TETISO_HD(i64 k) {
                return static_cast<u32>(pair_count[k] < kContactPairsPerOp ? pair_count[k] : kContactPairsPerOp);
            },
            cf.first_pair);
        const u32* first_pair = cf.first_pair.data();
        exec.for_each(static_cast<i64>(found), [=] TETISO_HD(i64 at) {
            const i32 k = range_of(first_pair, count, at);
            const ContactPair pair = pairs[(at - first_pair[k]) * count + k];
            if (judge.new_contact(k, pair.face, pair.entry)) hd::atomic_store(dropped + k, u8{1});
        });
        exec.for_each_of(overflow_count, static_cast<i64>(items), [=] TETISO_HD(i64 listed) {
            const i64 item = overflow_items[listed];
            const i32 k = range_of(first_item, count, item);
            if (!judge.clear_item(k, item - first_item[k])) hd::atomic_store(dropped + k, u8{1});
        });
    }
    exec.for_each(count, [=] TETISO_HD(i64 k) {
        if (!dropped[k]) return;
        const i32 e = list[k];
        chosen[e] = 0;
        if (!owner || ops.kind[e] == kFlip) return; // a flip's samples move after this
        for_each_leaf_face(slots(m, e), [&](i32 slot, bool) {
            const i32 t = m.face(slot);
            for (i32 sample = m.geo[t].samples_begin; sample < m.geo[t].samples_end; ++sample) owner[sample] = t;
        });
    });
}

} // namespace tetiso::reduction
