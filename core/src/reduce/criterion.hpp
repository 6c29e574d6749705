// The criterion Φ of the paper (section "Isosurface reduction and seaming")
// and the placement of a collapsed vertex, for one edge at a time: which
// collapse branch applies and the operation's priority (classify), then Φ
// and the position once the selection reaches it (place_collapse).
//
// Classification uses lengths and valences only. Φ, the position and the
// legality tests wait for the selection and run only for the operations it
// reaches unblocked: in a round about one edge in twenty collapses and most
// are blocked by a chosen neighbour, so computing Φ for all of them was most
// of a round (Φ is computed for several times fewer edges). The priority
// ranks shorter edges, relative to the other edges of their faces, first:
// unlike Φ it is known before Φ is, and it gave fewer triangles and a
// larger mean smallest angle than ranking by Φ, at a smaller Hausdorff
// distance on the paper surface and the same error bound. Flips, the lowest class, are proposed
// after all collapses are chosen, for the edges they left clear.
//
// Φ: for an interior edge (u, w) with faces f1 (running u → w) and f2 and unit
// normals n1, n2, the leaf of each end is traversed from f1 away from f2; the
// faces met while their normal is at least as close to n1 as to n2 form part
// 1, all later faces part 2; Φ_j = min over parts s of min over the normals n
// of part s of n_s · n. The traversal keeps part 1 contiguous, so a leaf
// folded along a line through the edge ("bent" leaf) scores 1 while a ridge
// across the edge does not. t = (2/π) atan(Φ_w / Φ_u),
// Φ = Φ_u t + Φ_w (1 - t), and the collapsed vertex is placed at
// t u + (1 - t) w: when w's leaf is the flatter one, t > 1/2 and the vertex
// stays near u — the less flat end (a corner, a crease) is preserved, and Φ,
// which leans to the less flat end's value as well, is a smooth minimum.
// Degenerate faces have no normal and are skipped.
//
// Branches:
//  - pinned ends: a locked vertex, or a border vertex on an interior edge, is
//    pinned; the other end collapses into it (p = the pinned end, exactly) and
//    Φ is that of the moving end's leaf, the only one whose faces change.
//    Two pinned ends: no collapse.
//  - border edges: one face; each leaf is one part measured against it, and
//    the border polyline gives a 1D criterion, the cosine of the turn at each
//    end; both enter Φ_j as a minimum. The collapsed vertex stays on segment
//    (u, w), i.e. on the border. An interior edge between two border
//    vertices never collapses (it would pinch the surface).
//  - very short edges (shorter than short_edge_ratio times the mean of the
//    other edges of the two faces, or of length 0, as marching tetrahedra
//    produce where the surface passes through a mesh node), the two
//    shorter edges of a degenerate face (a cap) and the shortest edge of a
//    face whose smallest angle is under min_angle, where it is within the
//    artefact scale of geometry.hpp: collapsed whatever Φ is, with first
//    priority.
//  - every other collapse needs Φ > Φ*; among them the shorter edge (against
//    the mean of its faces' other edges) goes first.
//  - valence-3 vertices: an interior free vertex with three neighbours is
//    removed (collapsed into its neighbour of smallest key; the three faces
//    become one), whatever Φ is; the legality and error tests still apply.
//  - flips (legality.hpp): an interior edge that is not collapsed is flipped
//    when its faces are nearly coplanar and the flip raises their smaller
//    minimum angle by 20 % — the long edge between two narrow triangles.
//    Lowest priority.
#pragma once

#include <algorithm>

#include "../hd.hpp"
#include "round_view.hpp"

namespace tetiso::reduction {

// A priority is 32 bits: class, score, then a few bits of a hash that
// varies with the round (equal priorities fall to the vertex keys, see
// selection.hpp). 32 rather than 64 bits halve the radix sort's passes,
// which streamed more memory per round than any other step.
constexpr int kPriorityScoreBits = 22;
constexpr int kPriorityHashBits = 8;
constexpr u32 kClassFlip = 0, kClassCollapse = 1, kClassValence3 = 2, kClassShort = 3;

TETISO_HD inline u32 make_priority(u32 cls, double score, u64 hash) {
    score = std::clamp(score, 0.0, 1.0);
    const u32 scale = (u32{1} << kPriorityScoreBits) - 1;
    const auto s = static_cast<u32>(score * static_cast<double>(scale));
    return (cls << (kPriorityScoreBits + kPriorityHashBits)) | (s << kPriorityHashBits) |
           static_cast<u32>(hash & ((u64{1} << kPriorityHashBits) - 1));
}

TETISO_HD inline u32 priority_class(u32 priority) { return priority >> (kPriorityScoreBits + kPriorityHashBits); }

// Breaks ties in priority; changes with the round so that an edge that loses
// a tie once does not lose it every round.
TETISO_HD inline u64 tie_hash(const RoundView& m, i32 e) {
    return mix64(m.s.key[m.edges.v0[e]] * 0x9e3779b97f4a7c15ULL ^
                 mix64(m.s.key[m.edges.v1[e]] + static_cast<u64>(m.round)));
}

// Φ_j of the leaf of a vertex (fan offset o, size k) for an interior edge
// whose faces sit in slots s1 and s2: traversal from s1 in direction dir
// (away from s2); on a border vertex the faces beyond s2 join part 2.
TETISO_HD inline double leaf_phi(const RoundView& m, i32 o, i32 k, bool path, i32 s1, i32 s2, int dir, Vec n1, Vec n2) {
    double phi = 1.0;
    bool part1 = true;
    i32 j = s1;
    for (i32 step = 0; step < k; ++step) {
        if (j == s2) break;
        const FaceGeometry& g = m.geo[m.face(o + j)];
        if (g.valid()) {
            const Vec n = g.n();
            const double d1 = dot(n, n1), d2 = dot(n, n2);
            if (part1 && d1 < d2) part1 = false;
            phi = std::min(phi, part1 ? d1 : d2);
        }
        j += dir;
        if (!path) j = j < 0 ? j + k : (j >= k ? j - k : j);
        else if (j < 0 || j >= k) break;
    }
    if (path)
        for (j = s2 - dir; j >= 0 && j < k; j -= dir) {
            const FaceGeometry& g = m.geo[m.face(o + j)];
            if (g.valid()) phi = std::min(phi, dot(g.n(), n2));
        }
    return phi;
}

// Φ_j of a border edge's end: its leaf against the edge's one face.
TETISO_HD inline double leaf_phi_border(const RoundView& m, i32 o, i32 k, Vec n) {
    double phi = 1.0;
    for (i32 j = 0; j < k; ++j) {
        const FaceGeometry& g = m.geo[m.face(o + j)];
        if (g.valid()) phi = std::min(phi, dot(n, g.n()));
    }
    return phi;
}

// Which ends are pinned (kept where they are): a locked vertex, or a border
// vertex on an interior edge. False when the edge cannot collapse at all (an
// interior edge between two border vertices would pinch the surface; two
// pinned ends cannot meet).
TETISO_HD inline bool pins(const RoundView& m, const EdgeSlots& r, bool& pin_u, bool& pin_w) {
    const bool border_edge = r.f1 < 0 || r.f2 < 0;
    const bool bu = m.border(r.u), bw = m.border(r.w);
    if (!border_edge && bu && bw) return false;
    pin_u = m.s.locked(r.u) || (!border_edge && bu);
    pin_w = m.s.locked(r.w) || (!border_edge && bw);
    return !(pin_u && pin_w);
}

// The edge's length and the mean length of the other edges of its faces (0
// when it has no opposite vertex).
TETISO_HD inline void lengths(const RoundView& m, const EdgeSlots& r, double& len, double& local) {
    const Vec pu = m.s.pos(r.u), pw = m.s.pos(r.w);
    len = norm(pw - pu);
    local = 0.0;
    int local_n = 0;
    for (const i32 o : {r.c, r.d})
        if (o >= 0) {
            const Vec po = m.s.pos(o);
            local += norm(po - pu) + norm(po - pw);
            local_n += 2;
        }
    local = local_n ? local / local_n : 0.0;
}

// A complete collapse: the survivor keep, moved to p.
TETISO_HD inline bool set_collapse(const OpsView& ops, i32 i, Vec p, i32 keep) {
    ops.kind[i] = kCollapse;
    ops.px[i] = static_cast<float>(p.x);
    ops.py[i] = static_cast<float>(p.y);
    ops.pz[i] = static_cast<float>(p.z);
    ops.survivor[i] = keep;
    return true;
}

// The cheap part of a collapse's proposal: its branch and priority
// (kPending, or a complete kCollapse for a valence-3 vertex), or kNone when
// no collapse is possible (a flip may still be, see propose_flip).
TETISO_HD inline void classify(const RoundView& m, i32 e, const OpsView& ops) {
    ops.kind[e] = kNone;
    const EdgeSlots r = slots(m, e, false);
    const u64 hash = tie_hash(m, e);
    const i32 u = r.u, w = r.w;
    bool pin_u = false, pin_w = false;
    if (!pins(m, r, pin_u, pin_w)) return;

    // Valence-3 branch: complete here, its position is the survivor's.
    for (const i32 mover : {w, u}) {
        const i32 keep = mover == w ? u : w;
        if (m.border(mover) || m.s.locked(mover) || m.fans.k(mover) != 3) continue;
        i32 smallest = m.fans.nbr(mover, 0);
        for (i32 j = 1; j < 3; ++j) smallest = std::min(smallest, m.fans.nbr(mover, j));
        if (smallest != keep) continue;
        ops.priority[e] = make_priority(kClassValence3, 1.0, hash);
        set_collapse(ops, e, m.s.pos(keep), keep);
        return;
    }

    double len, local;
    lengths(m, r, len, local);
    bool short_edge = len == 0.0 || len <= m.p.short_ratio * local;
    // A degenerate face (a cap: one corner on the opposite side) goes by
    // collapsing one of its two shorter edges; a near-degenerate one (its
    // smallest angle under min_angle) by collapsing its shortest where that
    // is within the artefact scale (geometry.hpp), whatever Φ says of it:
    // inside the cluster of crossings around a node on the level an edge is
    // not short against its faces' other edges when those are needles too,
    // and Φ, read from the needles' normals, refuses it. Longer edges keep
    // Φ's judgement: collapsing them against it pushed fans through sheets
    // nearby that share no corner with them, which legality does not test.
    for (const auto& [f, o] : {std::pair<i32, i32>{r.f1, r.c}, std::pair<i32, i32>{r.f2, r.d}}) {
        if (short_edge || f < 0) continue;
        if (!m.geo[f].valid()) {
            const Vec po = m.s.pos(o), pu = m.s.pos(u), pw = m.s.pos(w);
            short_edge = len < std::max(norm(po - pu), norm(po - pw));
        } else if (m.geo[f].q < m.p.q_min) {
            const Vec po = m.s.pos(o), pu = m.s.pos(u), pw = m.s.pos(w);
            short_edge = len <= std::min(norm(po - pu), norm(po - pw)) && within_artefact_scale(pu, pw);
        }
    }
    // Shorter edges, relative to their faces' other edges, go first.
    ops.kind[e] = kPending;
    ops.priority[e] = short_edge ? make_priority(kClassShort, local > 0 ? 1.0 - len / local : 1.0, hash)
                                 : make_priority(kClassCollapse, local > 0 ? local / (len + local) : 1.0, hash);
}

// Φ and the position of a kPending collapse. A short edge collapses whatever
// Φ is; any other needs Φ > Φ* (else kind becomes kNone and this returns
// false).
TETISO_HD inline bool place_collapse(const RoundView& m, const EdgeSlots& r, const OpsView& ops, i32 i) {
    const i32 u = r.u, w = r.w;
    const bool border_edge = r.f1 < 0 || r.f2 < 0;
    const bool bu = m.border(u), bw = m.border(w);
    bool pin_u = false, pin_w = false;
    pins(m, r, pin_u, pin_w);
    const bool short_edge = priority_class(ops.priority[i]) == kClassShort;
    const Vec pu = m.s.pos(u), pw = m.s.pos(w);
    const double len = norm(pw - pu);

    double phi_u = -1.0, phi_w = -1.0;
    if (border_edge) {
        const i32 f = r.f1 >= 0 ? r.f1 : r.f2;
        if (m.geo[f].valid()) {
            phi_u = leaf_phi_border(m, r.ou, r.ku, m.geo[f].n());
            phi_w = leaf_phi_border(m, r.ow, r.kw, m.geo[f].n());
        }
        // 1D criterion along the border polyline.
        if (len > 0) {
            const Vec dir = (1.0 / len) * (pw - pu);
            const Vec du = pu - m.s.pos(m.border_other(u, w)), dw = m.s.pos(m.border_other(w, u)) - pw;
            const double lu = norm(du), lw = norm(dw);
            if (lu > 0) phi_u = std::min(phi_u, dot(du, dir) / lu);
            if (lw > 0) phi_w = std::min(phi_w, dot(dw, dir) / lw);
        }
    } else {
        const bool v1 = m.geo[r.f1].valid(), v2 = m.geo[r.f2].valid();
        if (v1 || v2) {
            const Vec n1 = v1 ? m.geo[r.f1].n() : m.geo[r.f2].n();
            const Vec n2 = v2 ? m.geo[r.f2].n() : n1;
            // In u's fan f2 precedes f1: traverse forward; in w's, backward.
            if (!pin_u) phi_u = leaf_phi(m, r.ou, r.ku, bu, r.uf1, r.uf2, +1, n1, n2);
            if (!pin_w) phi_w = leaf_phi(m, r.ow, r.kw, bw, r.wf1, r.wf2, -1, n1, n2);
        }
    }

    Vec p;
    i32 keep;
    double phi;
    if (pin_u || pin_w) {
        keep = pin_u ? u : w;
        p = m.s.pos(keep);
        phi = pin_u ? phi_w : phi_u;
    } else if (phi_u > 0 && phi_w > 0) {
        const double t = (2.0 / hd::kPi) * hd::atan(phi_w / phi_u);
        phi = phi_u * t + phi_w * (1.0 - t);
        keep = t >= 0.5 ? u : w;
        p = len == 0.0 ? pu : t * pu + (1.0 - t) * pw;
    } else {
        // A leaf folds back (a corner, a spike): Φ gives no position. A short
        // edge still collapses, into the folded end so the corner stays, or to
        // its midpoint when both ends fold (a tiny move).
        phi = std::min(phi_u, phi_w);
        keep = phi_u <= 0 || phi_w > 0 ? u : w;
        p = phi_u <= 0 && phi_w <= 0 ? (len == 0.0 ? pu : 0.5 * (pu + pw)) : m.s.pos(keep);
    }
    if (!short_edge && !(phi > m.p.phi)) {
        ops.kind[i] = kNone;
        return false;
    }
    return set_collapse(ops, i, p, keep);
}

} // namespace tetiso::reduction
