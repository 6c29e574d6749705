// What the per-element functions of one reduction round read and write: the
// round's options, its operations, and a view (plain pointers, valid on the
// host or on the device) of every array the round built. A kernel or an
// OpenMP loop captures a RoundView by value and calls the functions of
// criterion.hpp, legality.hpp and error_bound.hpp with it.
#pragma once

#include "adjacency.hpp"
#include "geometry.hpp"

namespace tetiso::reduction {

struct Params {
    double phi;
    double q_min;     // sin(min_angle)
    double cos_turn;  // cos(max_normal_turn)
    double cos_flip;  // cos(flip_max_dihedral)
    double max_error; // <= 0: none
    double short_ratio;
    bool flips;
};

// kPending: a collapse whose branch and priority are known but whose Φ and
// position wait until the selection reaches it (criterion.hpp).
// kQuiet: skipped, its answer unchanged since a round that found none.
enum OpKind : u8 { kNone = 0, kCollapse = 1, kFlip = 2, kPending = 3, kQuiet = 4 };

// One operation per edge.
struct OpsView {
    u8* kind;
    u32* priority;
    float *px, *py, *pz, *err; // a collapse's new position; the new faces' error bound
    i32* survivor;             // a collapse's vertex that stays
};

// A vertex's cone (legality.hpp): the mean normal of its faces, and whether
// all of them face it.
struct Cone {
    float x, y, z; // unit mean normal
    u16 flat;
    u16 beside_sharp; // a neighbour's cone is not flat
};

// An error sample (error_bound.hpp): a raw vertex, or the first corner of a
// triangle sample, whose other two corners lie in far_point.
struct SamplePoint {
    float x, y, z, base;
};

struct SamplesView {
    const SamplePoint* point; // one per sample, in the order of their owners (face records' ranges)
    const i32* far;           // per sample: index of its far corners' pair, -1 for a raw vertex; null if none has any
    const SamplePoint* far_point;
    bool on; // there is an error bound (and samples)

    TETISO_HD const SamplePoint* far_corners(i32 sample) const {
        return far == nullptr || far[sample] < 0 ? nullptr : far_point + 2 * static_cast<std::size_t>(far[sample]);
    }
};

struct RoundView {
    SurfaceView s;
    FansView fans;
    EdgesView edges;
    const FaceGeometry* geo;
    const Cone* cones;
    SamplesView samples;
    Params p;
    int round;

    TETISO_HD bool border(i32 v) const { return fans.border[v] != 0; }
    TETISO_HD i32 face(i32 slot) const { return fans.face[slot]; }
    // The other border neighbour of border vertex v on border edge (v, x).
    TETISO_HD i32 border_other(i32 v, i32 x) const {
        const i32 first = fans.nbr(v, 0), last = fans.nbr(v, fans.k(v));
        return first == x ? last : first;
    }
};

// The slots, in the fans of both ends, of the faces of an edge.
struct EdgeSlots {
    i32 u, w, f1, f2;
    i32 ou, ku, uf1, uf2; // u's fan offset, size, slot of f1 / f2 (-1: none)
    i32 ow, kw, wf1, wf2; // wf1, wf2: -1 unless slots() was asked for them
    i32 c, d;             // opposite vertices (-1: none)
};

// with_w_slots: also find f1 and f2 in w's fan (a scan of its ring), which
// only Φ and the legality tests read.
TETISO_HD inline EdgeSlots slots(const RoundView& m, i32 e, bool with_w_slots = true) {
    EdgeSlots r;
    r.u = m.edges.v0[e];
    r.w = m.edges.v1[e];
    const EdgeFaces f = m.edges.faces(m.fans, e);
    r.f1 = f.f1;
    r.f2 = f.f2;
    r.c = f.c;
    r.d = f.d;
    r.ou = m.fans.off[r.u];
    r.ku = m.fans.k(r.u);
    r.ow = m.fans.off[r.w];
    r.kw = m.fans.k(r.w);
    const i32 j = m.edges.s0[e];
    r.uf1 = j < r.ku ? j : -1;
    r.uf2 = j > 0 ? j - 1 : (m.border(r.u) ? -1 : r.ku - 1);
    r.wf1 = r.wf2 = -1;
    if (!with_w_slots) return r;
    // mi: where u sits in w's ring (neighbours are distinct in a manifold
    // fan, so the first match is the one).
    i32 mi = 0;
    for (const i32 n = m.fans.nn(r.w); mi < n && m.fans.nbr(r.w, mi) != r.u; ++mi) {
    }
    r.wf2 = mi < r.kw ? mi : -1;
    r.wf1 = mi > 0 ? mi - 1 : (m.border(r.w) ? -1 : r.kw - 1);
    return r;
}

// The faces of both leaves of a collapse by index t < r.ku + r.kw: u's t-th,
// then w's (t - r.ku)-th. leaf_removed: the face is f1 or f2, which the
// collapse deletes; every other face becomes a new face, in this order.
TETISO_HD inline i32 leaf_slot(const EdgeSlots& r, int t) { return t < r.ku ? r.ou + t : r.ow + (t - r.ku); }
TETISO_HD inline bool leaf_removed(const EdgeSlots& r, int t) {
    return t < r.ku ? t == r.uf1 || t == r.uf2 : t - r.ku == r.wf1 || t - r.ku == r.wf2;
}
// Whether for_each_leaf_face visits leaf face t: every face once, w's f1 and
// f2 left out (already seen from u).
TETISO_HD inline bool leaf_visited(const EdgeSlots& r, int t) { return t < r.ku || !leaf_removed(r, t); }

// Calls f(slot, removed) for every face of both leaves of a collapse, once
// each: u's fan, then w's without f1 and f2.
template <class F>
TETISO_HD void for_each_leaf_face(const EdgeSlots& r, const F& f) {
    for (int t = 0; t < r.ku + r.kw; ++t)
        if (leaf_visited(r, t)) f(leaf_slot(r, t), leaf_removed(r, t));
}

// The faces a collapse makes: (p, a(f), b(f)), which replace triangle tri[f]
// (the same index: apply rewrites triangles in place). A test's largest
// record: on the stack of the thread that runs the test, or, in the GPU's
// dry runs, in the shared memory of the tile that runs it (dry_run.hpp;
// a thread's local memory, which the driver reserves for every thread the
// device can hold, is slow to read back). The other corners
// are vertices of the surface, read from its positions where needed rather
// than kept: what a test keeps in local memory it reads back from there,
// and the positions are shared by every test in the caches.
struct NewFan {
    static constexpr int kMax = 96;
    Vec p;
    const float* xyz; // the surface's positions
    Vec n[kMax];      // unit normal, zero when degenerate
    i32 ia[kMax], ib[kMax], tri[kMax];
    i32 end[kMax]; // the end, u or w, whose place p takes in this face
    int count = 0;
    TETISO_HD Vec a(int f) const { return position(ia[f]); }
    TETISO_HD Vec b(int f) const { return position(ib[f]); }

private:
    TETISO_HD Vec position(i32 v) const {
        const float* q = xyz + 3 * static_cast<std::size_t>(v);
        return {q[0], q[1], q[2]};
    }
};

} // namespace tetiso::reduction
