// The surface being reduced and the adjacency every round rebuilds from it
// (reduce.hpp; paper, section "Isosurface reduction and seaming"): the
// surface's flat arrays; each vertex's fan of triangles in order around it;
// one record per undirected edge; one record per triangle of what the tests
// read of it. Each step is a per-element function (one vertex, edge or
// triangle) called by a build function that is written once against the
// execution backends (exec_host.hpp, exec_cuda.cuh).
#pragma once

#include <cstddef>
#include <sstream>
#include <string>

#include "../hd.hpp"
#include "geometry.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::reduction {

// Positions are interleaved (xyz[3v..3v+2]): the tests read a vertex's three
// coordinates together, from vertices scattered over the arrays, so one
// cache line serves where three did.
struct SurfaceView {
    float* xyz;
    EdgeKey* key; // sorted ascending, unique: vertex order is key order
    u8* flags;
    i32* tri;
    // Per triangle: bound on the distance between this triangle and the
    // input surface it stands for (see error_bound.hpp).
    float* err;
    i32 nv, nt;

    TETISO_HD Vec pos(i32 v) const {
        const float* p = xyz + 3 * static_cast<std::size_t>(v);
        return {p[0], p[1], p[2]};
    }
    TETISO_HD bool locked(i32 v) const { return (flags[v] & kLocked) != 0; }
};

template <class Exec>
struct Surface {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<float> xyz;
    Array<EdgeKey> key;
    Array<u8> flags;
    Array<i32> tri;
    Array<float> err;
    i32 nv = 0, nt = 0;

    SurfaceView view() { return {xyz.data(), key.data(), flags.data(), tri.data(), err.data(), nv, nt}; }
};

// ---------------------------------------------------------------------------
// Fans. For vertex v, slots off[v] .. off[v+1] list its triangles in
// counter-clockwise order (seen from the side the normals point to); in the
// triangle of slot s the corners run v, next[s], prev[s], and the triangle of
// slot s+1 is the one across edge (v, prev[s]). A border vertex's fan is a
// path starting at the triangle whose edge (v, next) is a border edge; an
// interior vertex's fan is a cycle starting at its smallest triangle index.

struct FansView {
    const i32 *off, *face, *next, *prev;
    const u8* border;

    TETISO_HD i32 k(i32 v) const { return off[v + 1] - off[v]; }
    // Neighbours: k of them for an interior vertex, k + 1 on the border.
    TETISO_HD i32 nn(i32 v) const { return k(v) + border[v]; }
    // Neighbour j < nn(v): next of each slot, then, on the border, prev of
    // the last slot (read from next/prev rather than a copy of them: one
    // array less to write every round).
    TETISO_HD i32 nbr(i32 v, i32 j) const {
        const i32 slot = off[v] + j;
        return slot < off[v + 1] ? next[slot] : prev[slot - 1];
    }
};

enum FanProblem : u8 { kFanOk = 0, kEdgeCount, kEdgeDirection, kVertexFans, kFanTooLarge };

// What order_fan finds wrong at a vertex, when the round validates its input.
struct FanFinding {
    u8* problem;
    i32* other; // the neighbour on the faulty edge; null unless validating
    i32* count; // that edge's triangles
};

template <class Exec>
struct Fans {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<i32> off, face, next, prev;
    Array<u8> border, problem;
    Array<i32> problem_other, problem_count;
    Array<i32> corner, count; // build_fans's grouping of the corners
    Array<i32> large_scratch; // 6 per corner, only where a fan has more than kSmallFan faces
    i32 faulty = -1;          // the vertex an input's check found faulty, for a batch to name its piece

    FansView view() const { return {off.data(), face.data(), next.data(), prev.data(), border.data()}; }
};

// Fans up to this size are ordered in arrays on the stack (a thread's
// registers and local memory on the GPU); larger ones (rare: a valence of 48
// and more) in `large`, 6 entries per corner from the vertex's first slot.
constexpr i32 kSmallFan = 48;

// Orders the fan of vertex v from its corners (triangle * 3 + corner, in
// triangle order; slots off[v] .. off[v+1]). validate: check that every edge
// at v has at most two triangles, run once each way, and that they form one
// fan; otherwise (later rounds, whose operations keep the surface manifold)
// only the fan's being one path or cycle is checked. Records the first
// problem found, kFanTooLarge for a large fan with no `large` scratch given.
TETISO_HD inline void order_fan(const i32* tri, const i32* off, const i32* corner, i32 v, bool validate,
                                i32* large, i32* face, i32* next, i32* prev, u8* border, FanFinding finding) {
    const i32 o = off[v];
    const i32 k = off[v + 1] - o;
    finding.problem[v] = kFanOk;
    border[v] = 0;
    if (k == 0) return;
    i32 small[6 * kSmallFan];
    i32* t = small;
    if (k > kSmallFan) {
        if (!large) {
            finding.problem[v] = kFanTooLarge;
            return;
        }
        t = large + 6 * static_cast<std::size_t>(o);
    }
    i32 *a = t + k, *b = a + k, *order = b + k, *succ = order + k, *pred = succ + k;
    for (i32 i = 0; i < k; ++i) {
        const i32 c = corner[o + i];
        const i32 tr = c / 3, r = c % 3;
        t[i] = tr;
        a[i] = tri[3 * tr + (r + 1) % 3];
        b[i] = tri[3 * tr + (r + 2) % 3];
    }
    auto fail = [&](FanProblem what, i32 other, i32 n) {
        finding.problem[v] = what;
        if (!validate) return;
        finding.other[v] = other;
        finding.count[v] = n;
    };
    // Each neighbour u: edge (v,u) in at most 2 triangles, once each way.
    for (i32 i = 0; i < k && validate; ++i) {
        for (const i32 u : {a[i], b[i]}) {
            i32 ca = 0, cb = 0;
            for (i32 j = 0; j < k; ++j) {
                ca += a[j] == u;
                cb += b[j] == u;
            }
            if (ca + cb > 2) return fail(kEdgeCount, u, ca + cb);
            if (ca > 1 || cb > 1) return fail(kEdgeDirection, u, 2);
        }
    }
    // succ[i]: the slot after slot i around v (its next is i's prev), -1
    // at the end of a path; a slot that follows no other starts a path (a
    // border edge (v, a)). Matches are unique in a valid fan (the check
    // above, or the operations keeping the surface manifold), so the first
    // one found is the one: one search per slot.
    for (i32 i = 0; i < k; ++i) pred[i] = 0;
    for (i32 i = 0; i < k; ++i) {
        succ[i] = -1;
        for (i32 j = 0; j < k; ++j)
            if (a[j] == b[i]) {
                succ[i] = j;
                pred[j] = 1;
                break;
            }
    }
    i32 start = -1, starts = 0;
    for (i32 i = 0; i < k; ++i)
        if (!pred[i]) {
            ++starts;
            start = i;
        }
    if (starts > 1) return fail(kVertexFans, -1, 0);
    if (starts == 0) {
        start = 0;
        for (i32 i = 1; i < k; ++i)
            if (t[i] < t[start]) start = i;
    }
    order[0] = start;
    for (i32 step = 1; step < k; ++step) {
        const i32 found = succ[order[step - 1]];
        if (found < 0 || found == start) return fail(kVertexFans, -1, 0);
        order[step] = found;
    }
    for (i32 step = 0; step < k; ++step) {
        const i32 slot = o + step;
        face[slot] = t[order[step]];
        next[slot] = a[order[step]];
        prev[slot] = b[order[step]];
    }
    border[v] = starts == 1;
}

// order_fan at every vertex, or (only_large) at those it found too large
// for the stack, with scratch `large`.
template <class Exec>
void order_fans(Exec& exec, const i32* tri, i32 nv, bool validate, i32* large, bool only_large, Fans<Exec>& fans,
                FanFinding finding) {
    const i32 *off = fans.off.data(), *corner = fans.corner.data();
    i32 *face = fans.face.data(), *next = fans.next.data(), *prev = fans.prev.data();
    u8* border = fans.border.data();
    const u8* problem = fans.problem.data();
    exec.for_each(nv, [=] TETISO_HD(i64 v) {
        if (only_large && problem[v] != kFanTooLarge) return;
        order_fan(tri, off, corner, static_cast<i32>(v), validate, large, face, next, prev, border, finding);
    });
}

inline std::string key_text(EdgeKey key) { return std::to_string(key); }

// validate: check every edge and vertex (the input: throws tetiso::Error
// naming the first faulty edge or vertex); later rounds only order (the
// operations keep the surface manifold; a fault there is an internal error).
template <class Exec>
void build_fans(Exec& exec, Surface<Exec>& s, bool validate, Fans<Exec>& fans) {
    const i32 nv = s.nv, nt = s.nt;
    const i32* tri = s.tri.data();
    exec.group_by_key(3 * static_cast<i64>(nt), nv, [=] TETISO_HD(i64 c) { return tri[c]; }, fans.off, fans.corner,
                      fans.count);
    const std::size_t corners = 3 * static_cast<std::size_t>(nt);
    fans.face.resize(corners);
    fans.next.resize(corners);
    fans.prev.resize(corners);
    fans.border.resize(static_cast<std::size_t>(nv));
    fans.problem.resize(static_cast<std::size_t>(nv));
    if (validate) {
        exec.assign(fans.problem_other, nv, i32{-1});
        exec.assign(fans.problem_count, nv, i32{0});
    }
    const FanFinding finding{fans.problem.data(), validate ? fans.problem_other.data() : nullptr,
                             validate ? fans.problem_count.data() : nullptr};
    order_fans(exec, tri, nv, validate, nullptr, false, fans, finding);
    const u8* problem = fans.problem.data();
    // Every round asks once (a fan too large for the stack is a problem too).
    if (exec.count(nv, [=] TETISO_HD(i64 v) { return problem[v] != kFanOk; }) == 0) return;
    if (exec.count(nv, [=] TETISO_HD(i64 v) { return problem[v] == kFanTooLarge; }) > 0) {
        fans.large_scratch.resize(6 * corners);
        order_fans(exec, tri, nv, validate, fans.large_scratch.data(), true, fans, finding);
        if (exec.count(nv, [=] TETISO_HD(i64 v) { return problem[v] != kFanOk; }) == 0) return;
    }

    // The first faulty vertex, as a serial check would report it.
    typename Exec::template Array<i32> faulty;
    exec.filter(nv, [=] TETISO_HD(i64 v) { return problem[v] != kFanOk; }, faulty);
    const i32 v = exec.get(faulty, 0);
    fans.faulty = v;
    const u8 what = exec.get(fans.problem, v);
    if (!validate)
        throw InternalError("tetiso::reduce: vertex (key " + key_text(exec.get(s.key, v)) + ") became non-manifold");
    const i32 u = exec.get(fans.problem_other, v);
    std::ostringstream m;
    m << "tetiso::reduce: the input is not an oriented 2-manifold: ";
    const auto edge = [&] {
        return "edge (key " + key_text(exec.get(s.key, std::min(u, v))) + ", key " +
               key_text(exec.get(s.key, std::max(u, v))) + ")";
    };
    if (what == kEdgeCount) m << edge() << " has " << exec.get(fans.problem_count, v) << " triangles";
    else if (what == kEdgeDirection)
        m << edge() << " is run in the same direction by both of its triangles (inconsistent orientation)";
    else m << "vertex (key " << key_text(exec.get(s.key, v)) << ") is non-manifold: its triangles form more than one fan";
    throw Error(m.str());
}

// ---------------------------------------------------------------------------
// Edges. Edge e joins v0[e] < v1[e], and v1 is neighbour s0[e] of v0.
// Everything else about it is read from v0's fan (faces()): f1 is the
// triangle that runs v0 → v1, f2 the one that runs v1 → v0 (-1 on the
// border, at most one of them), c and d their third corners (-1 with them).
// Each edge is written by its smaller end alone. The record is kept to what
// the fan cannot give cheaply: every array here is written once per round and
// read by every step after it, and with every core of a node busy a round's
// memory traffic is what slows a task. Storing the faces, opposite
// corners and v0's slot in v1's ring as well (eight arrays, 32 bytes per
// edge) made the edge table the largest thing a round wrote.

struct EdgeFaces {
    i32 f1, f2, c, d;
};

struct EdgesView {
    const i32 *v0, *v1, *s0;
    // The edges vertex v owns are first[v] .. first[v + 1]: build_edges
    // writes them grouped by v0, in ascending v0.
    const i32* first;
    i32 count;

    TETISO_HD EdgeFaces faces(const FansView& fans, i32 e) const {
        const i32 v = v0[e], j = s0[e];
        const i32 o = fans.off[v], k = fans.k(v);
        // f1 = (v, u, c) sits in slot j, f2 = (u, v, d) in the slot before.
        const i32 before = j > 0 ? o + j - 1 : (fans.border[v] ? -1 : o + k - 1);
        EdgeFaces r;
        r.f1 = j < k ? fans.face[o + j] : -1;
        r.c = j < k ? fans.prev[o + j] : -1;
        r.f2 = before >= 0 ? fans.face[before] : -1;
        r.d = before >= 0 ? fans.next[before] : -1;
        return r;
    }
    // A border edge has one face: v1 is v0's last neighbour (no f1), or its
    // first on the border (no f2).
    TETISO_HD bool border(const FansView& fans, i32 e) const {
        const i32 v = v0[e], j = s0[e];
        return j == fans.k(v) || (j == 0 && fans.border[v]);
    }
};

template <class Exec>
struct Edges {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<i32> v0, v1, s0, first, count;
    i32 n = 0;

    EdgesView view() const { return {v0.data(), v1.data(), s0.data(), first.data(), n}; }
};

template <class Exec>
void build_edges(Exec& exec, const FansView& fans, i32 nv, Edges<Exec>& edges) {
    edges.count.resize(static_cast<std::size_t>(nv));
    i32* count = edges.count.data();
    exec.for_each(nv, [=] TETISO_HD(i64 vi) {
        const i32 v = static_cast<i32>(vi);
        i32 c = 0;
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) c += fans.nbr(v, j) > v;
        count[v] = c;
    });
    edges.n = exec.exclusive_scan(edges.count, nv, edges.first);
    const auto ne = static_cast<std::size_t>(edges.n);
    edges.v0.resize(ne);
    edges.v1.resize(ne);
    edges.s0.resize(ne);
    const i32* first = edges.first.data();
    i32 *v0 = edges.v0.data(), *v1 = edges.v1.data(), *s0 = edges.s0.data();
    exec.for_each(nv, [=] TETISO_HD(i64 vi) {
        const i32 v = static_cast<i32>(vi);
        i32 e = first[v];
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) {
            const i32 u = fans.nbr(v, j);
            if (u < v) continue;
            v0[e] = v;
            v1[e] = u;
            s0[e] = j;
            ++e;
        }
    });
}

// ---------------------------------------------------------------------------
// Per-triangle record of what a legality test reads of each face of a leaf:
// unit normal (zero when the triangle is degenerate), quality (sine of its
// smallest angle), error bound (a copy of the surface's) and the range of
// its error samples (written by the round's sort of the samples). One 32-byte
// record, so a test's first touch of a face is one cache miss where separate
// arrays for the geometry, the bounds and the sample offsets cost three.
struct FaceGeometry {
    float nx, ny, nz, q;
    float err;
    i32 samples_begin, samples_end; // samples [begin, end) of the round's sorted samples
    i32 is_resolved;                // resolved(): the normal means something
    TETISO_HD Vec n() const { return {nx, ny, nz}; }
    TETISO_HD bool valid() const { return is_resolved != 0; }
};
static_assert(sizeof(FaceGeometry) == 32, "one record per cache half-line");

TETISO_HD inline FaceGeometry face_geometry(const SurfaceView& s, i32 t) {
    Vec n;
    const Vec a = s.pos(s.tri[3 * t]), b = s.pos(s.tri[3 * t + 1]), c = s.pos(s.tri[3 * t + 2]);
    double height;
    const double q = quality(a, b, c, &n, &height);
    return {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z), static_cast<float>(q),
            s.err[t], 0, 0, resolved(a, b, c, q, height) ? 1 : 0};
}

template <class Exec>
void build_geometry(Exec& exec, const SurfaceView& s, typename Exec::template Array<FaceGeometry>& geometry) {
    geometry.resize(static_cast<std::size_t>(s.nt));
    FaceGeometry* g = geometry.data();
    exec.for_each(s.nt, [=] TETISO_HD(i64 t) { g[t] = face_geometry(s, static_cast<i32>(t)); });
}

} // namespace tetiso::reduction
