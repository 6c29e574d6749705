// Legality of one operation: the tests a collapse or a flip must pass to keep
// the surface homeomorphic to the input, consistently oriented, free of new
// degenerate faces and contacts, and within the error bound (reduce.hpp's
// guarantees). All must hold, else the operation is dropped:
//  - link condition: the common neighbours of u and w are exactly the
//    opposite vertices (two inside, one on the border);
//  - no new edge joins two locked vertices (a piece across an interface may
//    create the same edge, and seaming would give it 3 or 4 triangles), and
//    no face whose corners are all locked changes;
//  - every vertex keeps at least 3 neighbours (2 on the border), so no
//    component drops below a tetrahedron; a border loop keeps 3 edges;
//  - every surviving face of the two leaves keeps its orientation (normal
//    turns by at most max_normal_turn, or stays on the side of the leaf's
//    mean normal where it had none) and keeps a non-zero area; the smallest
//    angle over the new faces is at least min(min_angle, the smallest angle
//    over the old faces), so collapses that remove a degenerate face stay
//    possible but none makes the worst angle of its region worse (a face
//    with no normal of its own before and after, geometry.hpp, is held to
//    an area float resolves instead). Faces
//    that do not move (around a survivor that stays put) are not judged,
//    and a valence-3 removal's one new face has no turn test;
//  - no new contact: faces that share a corner meet nowhere else, among the
//    new faces and between them and the faces around their outer corners
//    (see Cones below); contacts the replaced faces had already do not count
//    (contact with faces that share no corner is judged once the round's
//    operations are chosen: contact_filter.hpp);
//  - error: the samples of every face of both leaves are re-measured against
//    the new faces (error_bound.hpp); each must lie within max_error of one
//    of them (less its own bound from earlier calls), and goes to it. The new
//    faces get the largest sample bound of the fan (plus, on the border, the
//    old bounds and the border polyline's departure), the bound that the
//    next call (a seam's reduction) starts from.
#pragma once

#include <algorithm>
#include <utility>

#include "../hd.hpp"
#include "../tile.hpp"
#include "criterion.hpp"
#include "error_bound.hpp"
#include "round_view.hpp"

namespace tetiso::reduction {

// ---------------------------------------------------------------------------
// Cones. Faces that share a corner must meet nowhere else: the normal tests
// of a collapse see only the faces it replaces, and where the surface passes
// close to a mesh node its sheets nearly touch, so that a collapse turning
// each face by little can still push a fan through the sheet beside it (4
// self-intersections, all between faces sharing a corner, in the paper
// field's surface on a 491 K-tetrahedron TetGen mesh before this test).
// Whether a vertex's faces meet only along shared edges is a property of its
// fan alone: when all their normals lie within 90° of one direction m, seen
// along m each face turns the same way about the vertex, and the fan is
// embedded exactly when the faces turn once around it. An operation replaces
// the faces of a run of the fan, between two of its edges, by faces between
// the same two edges; if these also face m, each turns by less than a half
// turn, so the run turns as far as before and the fan stays embedded. That
// holds for any number of operations in a round that touch one fan (their
// runs are disjoint), and needs for each new face only the cone of each of
// its corners, not the faces around them, whose cache misses cost the first
// version of this test a third of the reduction. A vertex's cone is flat
// when all its faces lie more than kConeMargin inside the hemisphere around
// their mean normal and, on the border, the fan turns less than once; where
// it is not (degenerate faces, sharp corners), and at the border neighbours
// of a border edge's collapse (whose run ends at a border edge that moves),
// the faces around the vertex are tested one by one instead, by a collapse
// that owns the vertex for the round (owned_corners).
constexpr double kConeMargin = 1e-3;

TETISO_HD inline Cone cone_of(const SurfaceView& s, const FansView& fans, const FaceGeometry* geometry, i32 v) {
    Cone c{0, 0, 0, 0, 0};
    const i32 begin = fans.off[v], end = fans.off[v + 1];
    Vec m{0, 0, 0};
    for (i32 slot = begin; slot < end; ++slot) {
        const FaceGeometry& g = geometry[fans.face[slot]];
        if (!g.valid()) return c;
        m = m + g.n();
    }
    const double len = norm(m);
    if (!(len > 0)) return c;
    m = (1.0 / len) * m;
    c.x = static_cast<float>(m.x);
    c.y = static_cast<float>(m.y);
    c.z = static_cast<float>(m.z);
    const Vec stored{c.x, c.y, c.z};
    for (i32 slot = begin; slot < end; ++slot)
        if (!(dot(geometry[fans.face[slot]].n(), stored) > 2 * kConeMargin)) return c;
    // A border fan must also turn less than once around the vertex, else it
    // could wind over itself (stacked like a ramp) while every face faces m:
    // its faces, in fan order, hold the direction of its first edge only in
    // the first face's angle.
    if (fans.border[v]) {
        const Vec pv = s.pos(v);
        Vec ray = s.pos(fans.next[begin]) - pv; // the first face's first side
        ray = ray - dot(ray, stored) * stored;
        const Vec across = cross(stored, ray);
        int holding = 0;
        for (i32 slot = begin; slot < end; ++slot)
            holding += holds_ray(s.pos(fans.next[slot]) - pv, s.pos(fans.prev[slot]) - pv, ray, across, slot == begin);
        if (holding != 1) return c;
    }
    c.flat = 1;
    return c;
}

template <class Exec>
void build_cones(Exec& exec, const SurfaceView& s, const FansView& fans, const FaceGeometry* geometry,
                 typename Exec::template Array<Cone>& cones) {
    cones.resize(static_cast<std::size_t>(s.nv));
    Cone* c = cones.data();
    exec.for_each(s.nv, [=] TETISO_HD(i64 v) { c[v] = cone_of(s, fans, geometry, static_cast<i32>(v)); });
    // Few cones are not flat: their neighbours are marked from them, so that
    // most collapses learn that they own no corner from their two ends.
    exec.for_each(s.nv, [=] TETISO_HD(i64 vi) {
        const i32 v = static_cast<i32>(vi);
        if (c[v].flat) return;
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) hd::atomic_store(&c[fans.nbr(v, j)].beside_sharp, u16{1});
    });
}

// Whether new face normal n lies in the cone of v's fan: then the faces
// replaced at v are replaced by faces on the same side, and v's fan stays
// embedded.
TETISO_HD inline bool inside_cone(const RoundView& m, i32 v, Vec n) {
    const Cone& c = m.cones[v];
    return c.flat && dot(n, {c.x, c.y, c.z}) > kConeMargin;
}

// The most corners an operation may own (owned_corners); one that would own
// more waits for a later round.
constexpr int kMaxOwned = 12;

// The corners whose fans a collapse of (u, w) tests face by face: its outer
// corners whose cone is not flat, and on a border edge the border neighbours
// of its ends. A chosen collapse owns them for the round: they join its ends
// in every conflict (two operations conflict when the vertices of one lie
// within path length 1 of the other's), so that no other operation of the
// round changes a fan the test read face by face; the cones keep every other
// fan embedded whatever the round does. Without this, 15 K of the 26 K
// corners so tested in the reduction of the N = 100 paper surface had a fan
// that another chosen operation changed in the same round. Returns the
// count, or -1 when there are more than kMaxOwned.
TETISO_HD inline int owned_corners(const FansView& fans, const Cone* cones, i32 u, i32 w, bool border_edge, i32* out) {
    if (!border_edge && !cones[u].beside_sharp && !cones[w].beside_sharp) return 0;
    int n = 0;
    auto add = [&](i32 v) {
        for (int k = 0; k < n; ++k)
            if (out[k] == v) return true;
        if (n == kMaxOwned) return false;
        out[n++] = v;
        return true;
    };
    for (const i32 end : {u, w})
        for (i32 j = 0, m = fans.nn(end); j < m; ++j) {
            const i32 v = fans.nbr(end, j);
            if (v != u && v != w && !cones[v].flat && !add(v)) return -1;
        }
    if (border_edge)
        for (const auto& [end, other] : {std::pair<i32, i32>{u, w}, std::pair<i32, i32>{w, u}}) {
            const i32 first = fans.nbr(end, 0), last = fans.nbr(end, fans.k(end));
            if (!add(first == other ? last : first)) return -1;
        }
    return n;
}

// A tested operation: chosen, or refused (no possible operation), or legal
// but blocked by a corner it would own that another chosen one claimed.
enum class Verdict : u8 { kIllegal, kBlocked, kLegal };

// ---------------------------------------------------------------------------
// Contact between faces that share a corner or an edge.

// A triangle for the contact tests: corners (vertex, position), unit normal
// (zero when degenerate).
struct Corners {
    i32 id[3];
    Vec at[3];
    Vec n;
};

// Whether two faces that share a corner or an edge (by vertex, or by
// position where a mesh node made two vertices coincide) meet anywhere else.
// Faces with nothing in common, or degenerate ones, are not judged.
TETISO_HD inline bool touch(const Corners& f, const Corners& g) {
    if (norm2(f.n) == 0 || norm2(g.n) == 0) return false;
    int fi[3], gi[3], shared = 0;
    for (int i = 0; i < 3 && shared < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (f.id[i] == g.id[j]) {
                fi[shared] = i;
                gi[shared++] = j;
                break;
            }
    if (shared == 0)
        for (int i = 0; i < 3 && !shared; ++i)
            for (int j = 0; j < 3 && !shared; ++j)
                if (f.at[i].x == g.at[j].x && f.at[i].y == g.at[j].y && f.at[i].z == g.at[j].z) {
                    fi[0] = i;
                    gi[0] = j;
                    shared = 1;
                }
    if (shared == 0) return false;
    if (shared == 3) return true;
    if (shared == 2) {
        const int f3 = 3 - fi[0] - fi[1], g3 = 3 - gi[0] - gi[1];
        return overlap_at_edge(f.at[fi[0]], f.at[fi[1]], f.at[f3], f.n, g.at[g3]);
    }
    const int f1 = (fi[0] + 1) % 3, f2 = (fi[0] + 2) % 3, g1 = (gi[0] + 1) % 3, g2 = (gi[0] + 2) % 3;
    return overlap_at_corner(f.at[fi[0]], f.at[f1], f.at[f2], f.n, g.at[g1], g.at[g2], g.n);
}

// New face f of a collapse, and the face it replaces.
TETISO_HD inline Corners new_face(const NewFan& fan, int f) {
    return {{-1, fan.ia[f], fan.ib[f]}, {fan.p, fan.a(f), fan.b(f)}, fan.n[f]};
}
TETISO_HD inline Corners old_face(const RoundView& m, const NewFan& fan, int f) {
    Corners c{{fan.end[f], fan.ia[f], fan.ib[f]}, {m.s.pos(fan.end[f]), fan.a(f), fan.b(f)}, {0, 0, 0}};
    quality(c.at[0], c.at[1], c.at[2], &c.n);
    return c;
}

// Whether the new faces around p meet only along their shared edges: seen
// along the mean of their normals, each turns the same way about p and
// together they turn once around it (less, when p is on the border). That is
// counted on a ray along the first side of the first face (of the chain, on
// the border): the half-open angles [a, b) of the faces must hold it once. A
// closed fan turning k times holds every ray k times; an open one turning
// more than once holds its first side twice.
template <class Tile>
TETISO_HD bool fan_at_p_embedded(const Tile& tile, const NewFan& fan) {
    Vec m{0, 0, 0};
    for (int f = 0; f < fan.count; ++f) m = m + fan.n[f];
    const double len = norm(m);
    if (!(len > 0)) return false;
    m = (1.0 / len) * m;
    if (tile_any(tile, fan.count, [&](int f) { return !(dot(fan.n[f], m) > kConeMargin); })) return false;
    // On the border: the face whose first side no face ends on.
    int first = tile_first(tile, fan.count, [&](int f) {
        for (int g = 0; g < fan.count; ++g)
            if (fan.ib[g] == fan.ia[f]) return false;
        return true;
    });
    const bool open = first < fan.count;
    if (!open) first = 0;
    Vec ray = fan.a(first) - fan.p;
    ray = ray - dot(ray, m) * m;
    const Vec across = cross(m, ray);
    // Each side is measured the same way in both faces that hold it, so that
    // rounding cannot count the first side twice or not at all; on the
    // border, the first side is the first face's own.
    const int holding = tile_sum(tile, fan.count, [&](int f) {
        return holds_ray(fan.a(f) - fan.p, fan.b(f) - fan.p, ray, across, open && f == first) ? 1 : 0;
    });
    return holding == 1;
}

// The exact test at outer corner v, for a cone that does not settle it: each
// face around v that the collapse leaves as it is, against each new face at
// v.
TETISO_HD inline bool ring_clear(const RoundView& m, i32 u, i32 w, const NewFan& fan, i32 v) {
    int at_v[2], n_at_v = 0;
    for (int f = 0; f < fan.count && n_at_v < 2; ++f)
        if (fan.ia[f] == v || fan.ib[f] == v) at_v[n_at_v++] = f;
    const Vec pv = m.s.pos(v);
    const i32 begin = m.fans.off[v], end = m.fans.off[v + 1];
    for (i32 slot = begin; slot < end; ++slot) {
        const i32 x = m.fans.next[slot];
        const i32 y = m.fans.prev[slot];
        if (x == u || x == w || y == u || y == w) continue; // a face the collapse replaces
        const Vec px = m.s.pos(x), py = m.s.pos(y);
        for (int j = 0; j < n_at_v; ++j) {
            const int h = at_v[j];
            if (norm2(fan.n[h]) == 0) continue;
            const i32 o = fan.ia[h] == v ? fan.ib[h] : fan.ia[h];
            const Vec po = fan.ia[h] == v ? fan.b(h) : fan.a(h);
            bool overlap;
            if (x == o || y == o) {
                // Across the edge (v, o): only a face folded flat onto h.
                const Vec third = x == o ? py : px;
                overlap = overlap_at_edge(pv, po, fan.p, fan.n[h], third) &&
                          !overlap_at_edge(pv, po, m.s.pos(fan.end[h]), old_face(m, fan, h).n, third);
            } else {
                if (apart(pv, fan.n[h], px, py)) continue;
                Vec ng;
                if (!(quality(pv, px, py, &ng) > 0)) continue;
                overlap = overlap_at_corner(pv, fan.p, po, fan.n[h], px, py, ng) &&
                          !touch(old_face(m, fan, h), Corners{{v, x, y}, {pv, px, py}, ng});
            }
            if (overlap) return false;
        }
    }
    return true;
}

// Whether the faces a collapse of (u, w) makes come into contact with no
// face that shares a corner with them, other than along that corner or edge:
// the new ones among themselves (the fan around p), and the faces around
// their outer corners (by cones where they settle it). Where a fan is tested
// face by face, a contact the replaced faces had already is no new one:
// extraction leaves faces that touch along a line where the surface passes
// through a mesh node, and cleaning those up must stay possible. Faces that
// share no corner are not tested.
template <class Tile>
TETISO_HD bool clear_of_neighbours(const Tile& tile, const RoundView& m, i32 u, i32 w, bool border_edge,
                                   const NewFan& fan) {
    const int faces = fan.count;
    if (!fan_at_p_embedded(tile, fan) && tile_any(tile, faces * faces, [&](int k) {
            const int f = k / faces, g = k % faces;
            return g > f && norm2(fan.n[f]) != 0 && !apart(fan.p, fan.n[f], fan.a(g), fan.b(g)) &&
                   touch(new_face(fan, f), new_face(fan, g)) && !touch(old_face(m, fan, f), old_face(m, fan, g));
        }))
        return false;
    // Each outer corner v: a[f] of one new face and b[g] of another (on the
    // border, the ends of the chain have one). Reading only v's cone settles
    // it; the ring is read where the cone does not. The corners tested face
    // by face are those the collapse owns for the round (owned_corners): no
    // other operation of the round changes their fans. Elsewhere a new face
    // outside its corner's cone is refused (rare: 11 corners in the
    // reduction of the N = 100 paper surface), as the cone argument needs
    // every operation at that corner to keep to it.
    const i32 moved_a = border_edge ? m.border_other(u, w) : -1, moved_b = border_edge ? m.border_other(w, u) : -1;
    return !tile_any(tile, 2 * faces, [&](int k) {
        const int f = k >> 1;
        const i32 v = k & 1 ? fan.ib[f] : fan.ia[f];
        if (v == moved_a || v == moved_b || !m.cones[v].flat) return !ring_clear(m, u, w, fan, v);
        return !inside_cone(m, v, fan.n[f]);
    });
}

// ---------------------------------------------------------------------------
// Collapses.

// Where a legal collapse's samples go: kept until the collapse knows it
// owns its corners (a test that fails half way must leave the owners as
// they were). Past kMax the placements are computed again when written.
struct Placements {
#ifdef __CUDA_ARCH__
    static constexpr int kMax = 64; // local memory is reserved for every thread the GPU can hold
#else
    static constexpr int kMax = 256;
#endif
    i32 sample[kMax], triangle[kMax];
    int count = 0;
    bool overflow = false;
    TETISO_HD void add(i32 s, i32 t) {
        if (count < kMax) {
            sample[count] = s;
            triangle[count++] = t;
        } else {
            overflow = true;
        }
    }
};

// The tests of a placed collapse that read connectivity alone (the link
// condition, locked vertices, valences, border loops): cheap, and most
// collapses that fail, fail here.
TETISO_HD inline bool connectivity_allows(const RoundView& m, const EdgeSlots& r, const OpsView& ops, i32 i) {
    const i32 u = r.u, w = r.w, c = r.c, d = r.d;
    const bool border_edge = r.f1 < 0 || r.f2 < 0;
    // Link condition.
    const i32 nu = m.fans.nn(u), nw = m.fans.nn(w);
    i32 common = 0;
    for (i32 a = 0; a < nu; ++a) {
        const i32 x = m.fans.nbr(u, a);
        if (x == w) continue;
        for (i32 b = 0; b < nw; ++b)
            if (m.fans.nbr(w, b) == x) {
                if (x != c && x != d) return false;
                ++common;
            }
    }
    if (common != (border_edge ? 1 : 2)) return false;
    // No new edge between two locked vertices: the piece across the
    // interface (or, after a seam, the rest of the piece around the reduced
    // region) may hold the same edge, and once merged by key it would have
    // three or four triangles. A collapse joins the survivor to the other
    // end's neighbours; only a locked survivor can do harm.
    const i32 keep = ops.survivor[i], gone = keep == u ? w : u;
    if (m.s.locked(keep))
        for (i32 j = 0, n = m.fans.nn(gone); j < n; ++j) {
            const i32 x = m.fans.nbr(gone, j);
            if (x != keep && x != c && x != d && m.s.locked(x)) return false;
        }
    // Valences, border loops (of 3 edges: both ends' other border
    // neighbour the same).
    if (nu + nw - 2 - common < ((m.border(u) || m.border(w)) ? 2 : 3)) return false;
    for (const i32 o : {c, d})
        if (o >= 0 && m.fans.nn(o) - 1 < (m.border(o) ? 2 : 3)) return false;
    return !border_edge || m.border_other(u, w) != m.border_other(w, u);
}

// The tests of collapse i that follow connectivity_allows (known: already
// passed on this state), run by a tile of threads together (tile.hpp; the
// host's a single thread), the new faces kept in `fan`, which the tile
// shares. owns(border_edge): whether the corners the collapse would own are
// its to take, asked last, of a collapse that passed every other test.
// deferred: where the samples are placed later, one by one
// (place_on_own_face), this takes the bound they start from and the test
// places none (nor writes the new faces' bound); null to place them here,
// which only a single thread does (a tile's dry runs always defer them).
template <class Tile, class Owns>
TETISO_HD bool legal_collapse(const Tile& tile, const RoundView& m, const EdgeSlots& r, const OpsView& ops, i32 i,
                              i32* owner, const Owns& owns, double* deferred, NewFan& fan, bool connectivity_known) {
    const i32 u = r.u, w = r.w;
    const bool border_edge = r.f1 < 0 || r.f2 < 0;
    if (!connectivity_known && !connectivity_allows(m, r, ops, i)) return false;
    const Vec p{ops.px[i], ops.py[i], ops.pz[i]};
    const Vec pu = m.s.pos(u), pw = m.s.pos(w);
    double increment = 0.0;
    if (border_edge) {
        const i32 up = m.border_other(u, w), wn = m.border_other(w, u);
        const Vec a = m.s.pos(up), b = m.s.pos(wn);
        for (const Vec q : {pu, pw})
            increment =
                std::max(increment, std::min(point_segment_distance(q, a, p), point_segment_distance(q, p, b)));
    }

    // Old faces of both leaves (for_each_leaf_face's): error bound, worst
    // quality, mean normal, folded in that order by every thread of the tile.
    double err_old = 0.0, q_worst = 1.0;
    Vec nsum{0, 0, 0};
    tile_fold(tile, r.ku + r.kw, [&](int t) { return leaf_visited(r, t); },
              [&](int t) { return m.geo[m.face(leaf_slot(r, t))]; },
              [&](const FaceGeometry& g) {
                  err_old = std::max(err_old, static_cast<double>(g.err));
                  q_worst = std::min(q_worst, static_cast<double>(g.q));
                  if (g.valid()) nsum = nsum + g.n();
              });
    const double q_floor = std::min(m.p.q_min, q_worst);
    // A valence-3 vertex's three faces become the one across their outer
    // corners, whose area vector is the sum of theirs (an identity, for any
    // position of the vertex): on average it turns from none of them,
    // however far it turns from the one whose place it takes. That turn
    // measured the height of the vertex above the new face, which is the
    // error test's to judge, and it kept 38 valence-3 vertices in tiny
    // clusters where the surface passes near a mesh node, each blocking the
    // collapse of a needle's short edge (the link condition fails through
    // it) in the N = 100 paper surface.
    const bool removes_valence3 = priority_class(ops.priority[i]) == kClassValence3;
    // New faces: (p, next, prev) for every other face of both leaves, in
    // their order.
    if (tile.rank() == 0) {
        fan.p = p;
        fan.xyz = m.s.xyz;
    }
    bool spoiled = false;
    const auto kept = [&](int t) { return !leaf_removed(r, t); };
    const int faces = tile_enumerate(tile, r.ku + r.kw, kept, [&](int t, int place) {
        const i32 slot = leaf_slot(r, t);
        const i32 ia = m.fans.next[slot];
        const i32 ib = m.fans.prev[slot];
        const Vec a = m.s.pos(ia), b = m.s.pos(ib);
        Vec n;
        const double q_new = quality(p, a, b, &n);
        const FaceGeometry& g = m.geo[m.face(slot)];
        const i32 end = slot < r.ou + r.ku ? u : w;
        // A face of the survivor's leaf, where the survivor stays put (a
        // pinned end, a valence-3 removal), does not change and is not
        // judged. Judged, it failed the quality floor whenever it was its
        // region's worst face: its quality, recomputed from its corners in
        // another order, came out a few units in the last place below the
        // stored one. That refused most collapses next to a needle, and the
        // needle stayed (several times more triangles below 1° in the paper
        // surface's reduction).
        const Vec pe = m.s.pos(end);
        const bool moves = p.x != pe.x || p.y != pe.y || p.z != pe.z;
        // No face with a normal of its own (valid) becomes degenerate or
        // turns; one whose normal is rounding's may become degenerate, its
        // own short edge will remove it, and must face the leaves' way only
        // once the collapse gives it a normal of its own. A face that has no
        // normal of its own before and after (an artefact of the node
        // clearance, geometry.hpp) is held to an area that float resolves
        // rather than to the quality floor: when it was its region's worst
        // face, every way of moving a corner of the cluster made it a little
        // thinner, and the floor refused them all (the needles along the
        // border of the paper surface, where a node on a cube face meets the
        // level).
        const bool below_floor = q_new < q_floor && !(!g.valid() && resolvable_artefact(p, a, b));
        const bool spoils = moves && (below_floor || (!(q_new > 0) && g.valid()) ||
                                      (g.valid() ? q_new > 0 && !removes_valence3 && dot(n, g.n()) < m.p.cos_turn
                                                 : resolved(p, a, b) && dot(n, nsum) < 0));
        if (place < NewFan::kMax) {
            fan.n[place] = n;
            fan.ia[place] = ia;
            fan.ib[place] = ib;
            fan.end[place] = end;
            fan.tri[place] = m.face(slot);
        }
        return spoils;
    }, &spoiled);
    if (spoiled || faces > NewFan::kMax) return false;
    if (tile.rank() == 0) fan.count = faces;
    tile.sync(); // the fan is the tile's
    if (!m.samples.on) {
        if (!clear_of_neighbours(tile, m, u, w, border_edge, fan) || !owns(border_edge)) return false;
        if (tile.rank() == 0) ops.err[i] = static_cast<float>(err_old + increment);
        return true;
    }
    // On the border the polyline's 1D departure adds to the bounds it
    // replaces (the samples see only the 2D one).
    double worst = border_edge ? err_old + increment : 0.0;
    if (worst > m.p.max_error) return false;
    if (deferred) {
        if (!clear_of_neighbours(tile, m, u, w, border_edge, fan) || !owns(border_edge)) return false;
        *deferred = worst;
        return true;
    }
    if constexpr (Tile::kSize == 1) {
        // The placements wait until every sample has found a face: a test
        // that fails half way must leave the owners as they were.
        Placements placed;
        if (!place_samples(m, r, fan, worst, [&](i32 sample, i32 t) { placed.add(sample, t); })) return false;
        if (!clear_of_neighbours(tile, m, u, w, border_edge, fan) || !owns(border_edge)) return false;
        if (owner) {
            if (!placed.overflow) {
                for (int k = 0; k < placed.count; ++k) owner[placed.sample[k]] = placed.triangle[k];
            } else {
                double again = border_edge ? err_old + increment : 0.0;
                place_samples(m, r, fan, again, [&](i32 sample, i32 t) { owner[sample] = t; });
            }
        }
        ops.err[i] = static_cast<float>(worst);
        return true;
    } else {
        return false; // not reached: see deferred
    }
}

// Whether operation e is possible: a kPending collapse gets its Φ and
// position first (kNone when Φ is not above Φ*), then the legality tests
// run. A flip was tested when proposed. owner: where to move the samples of
// a legal collapse (its caller chooses every operation this finds legal);
// null when there are no samples. free_corners(owned, n): whether the
// corners the collapse would own are its to take (n = -1: too many); asked
// only of a legal collapse, which is blocked when they are not, its samples
// left where they were.
// deferred: see legal_collapse.
template <class FreeCorners>
TETISO_HD Verdict legal(const RoundView& m, i32 e, const OpsView& ops, i32* owner, const FreeCorners& free_corners,
                        double* deferred = nullptr) {
    if (ops.kind[e] == kFlip) return Verdict::kLegal;
    const EdgeSlots r = slots(m, e);
    if (ops.kind[e] == kPending && !place_collapse(m, r, ops, e)) return Verdict::kIllegal;
    bool blocked = false;
    NewFan fan;
    if (legal_collapse(SequentialTile{}, m, r, ops, e, owner, [&](bool border_edge) {
            i32 owned[kMaxOwned];
            const int n = owned_corners(m.fans, m.cones, r.u, r.w, border_edge, owned);
            blocked = !free_corners(owned, n);
            return !blocked;
        }, deferred, fan, false))
        return Verdict::kLegal;
    return blocked ? Verdict::kBlocked : Verdict::kIllegal;
}

// A dry run's tests of collapse e after connectivity_allows passed on this
// state (dry_run_all's second stage), by a tile of threads, its corners taken
// as free: legal or illegal.
template <class Tile>
TETISO_HD Verdict legal_geometry(const Tile& tile, const RoundView& m, i32 e, const OpsView& ops, NewFan& fan,
                                 double* deferred) {
    if (ops.kind[e] == kFlip) return Verdict::kLegal;
    return legal_collapse(tile, m, slots(m, e), ops, e, nullptr, [](bool) { return true; }, deferred, fan, true)
               ? Verdict::kLegal
               : Verdict::kIllegal;
}

// ---------------------------------------------------------------------------
// Flips.

// A flip for an interior edge with no collapse: kFlip when it gains and
// passes every test (it needs no test at selection).
TETISO_HD inline bool propose_flip(const RoundView& m, i32 e, const OpsView& ops) {
    const EdgeSlots r = slots(m, e, false);
    if (!(m.p.flips && r.f1 >= 0 && r.f2 >= 0)) return false;
    const i32 u = r.u, w = r.w, c = r.c, d = r.d;
    const FaceGeometry &g1 = m.geo[r.f1], &g2 = m.geo[r.f2];
    const double q_old = std::min(g1.q, g2.q);
    if (q_old >= 0.5 || c == d) return false; // no triangle with an angle below 30°: nothing to gain
    if (!g1.valid() && !g2.valid()) return false;
    const Vec pu = m.s.pos(u), pw = m.s.pos(w), pc = m.s.pos(c), pd = m.s.pos(d);
    // f1 = (u, w, c), f2 = (w, u, d) → g1 = (c, u, d), g2 = (d, w, c).
    Vec n1, n2;
    const double q1 = quality(pc, pu, pd, &n1), q2 = quality(pd, pw, pc, &n2);
    const double q_new = std::min(q1, q2);
    if (!(q_new > 1.2 * q_old) || q_new < std::min(m.p.q_min, q_old)) return false;
    const Vec m1 = g1.valid() ? g1.n() : g2.n();
    const Vec m2 = g2.valid() ? g2.n() : m1;
    if (dot(m1, m2) < m.p.cos_flip || dot(n1, n2) < m.p.cos_flip) return false;
    for (const Vec mm : {m1, m2})
        for (const Vec n : {n1, n2})
            if (dot(mm, n) < m.p.cos_flip) return false;
    if (m.fans.nn(u) - 1 < (m.border(u) ? 2 : 3) || m.fans.nn(w) - 1 < (m.border(w) ? 2 : 3)) return false;
    for (i32 j = 0, n = m.fans.nn(c); j < n; ++j)
        if (m.fans.nbr(c, j) == d) return false;
    // No new locked-locked edge (see connectivity_allows); and, as with a
    // collapse (which changes only faces around the vertex that moves), no
    // change to a face whose corners are all locked: a seam's reduction holds
    // the faces around its region's rim only for the legality tests to read
    // (reduce_near), and they must come back as they were.
    const bool locked_edge = m.s.locked(u) && m.s.locked(w);
    if ((m.s.locked(c) && m.s.locked(d)) || (locked_edge && (m.s.locked(c) || m.s.locked(d)))) return false;
    // No face pushed through its neighbours (see Cones); where a cone does
    // not settle it the flip, an improvement only, is not made.
    if (!inside_cone(m, u, n1) || !inside_cone(m, c, n1) || !inside_cone(m, d, n1) || !inside_cone(m, w, n2) ||
        !inside_cone(m, c, n2) || !inside_cone(m, d, n2))
        return false;
    // Error: the gap between the two diagonals.
    const Vec axis = cross(pw - pu, pd - pc);
    const double axis_len = norm(axis);
    if (!(axis_len > 0)) return false;
    const double gap = std::abs(dot(pc - pu, axis)) / axis_len;
    double err_new = std::max(g1.err, g2.err) + gap;
    if (m.samples.on) {
        err_new = 0.0;
        if (!place_flip_samples(m, r, err_new, [](i32, i32) {})) return false;
    }
    ops.kind[e] = kFlip;
    ops.priority[e] = make_priority(kClassFlip, q_new - q_old, tie_hash(m, e));
    ops.err[e] = static_cast<float>(err_new);
    return true;
}

} // namespace tetiso::reduction
