// Isosurface reduction: rounds of parallel edge collapse and edge flip driven
// by the Φ criterion of the paper (section "Isosurface reduction and
// seaming"), with the branches the paper names but does not describe designed
// here: very short edges, valence-3 vertices, border edges, flips of long
// edges between narrow triangles, plus legality tests that keep the surface
// homeomorphic to the input and an error bound that keeps it close.
//
// One round, each step a data-parallel pass over flat arrays (vertex, edge or
// triangle index → values), so that it maps onto Thrust primitives:
//   1. fans:      vertex → its triangles in counter-clockwise order (counting
//                 sort of the corners, then a per-vertex ordering that also
//                 validates manifoldness and orientation);
//   2. edges:     one record per undirected edge, owned by its smaller end;
//   3. normals:   unit normal and quality (sine of the smallest angle) of
//                 every triangle;
//   4. evaluate:  per edge, Φ, the operation (collapse and where to, or flip),
//                 its legality, error and priority;
//   5. select:    an independent set — no two chosen operations closer than
//                 path length 2 — by local maxima of the priority, gathered
//                 over vertices and then over their 1-rings, a few passes;
//   6. apply:     the chosen operations touch disjoint triangles and vertices;
//   7. compact:   drop removed vertices and triangles, keeping their order (so
//                 vertex keys stay sorted).
// Every per-element computation depends on that element's inputs only and no
// floating-point value is ever summed across elements, so the output is the
// same for any thread count.
#include "tetiso/reduce.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "tetiso/error.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace tetiso {
namespace {

using i32 = std::int32_t;
using i64 = std::int64_t;
using u64 = std::uint64_t;
using u8 = std::uint8_t;

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------
// Parallel primitives. Everything above them is written per element.

int resolve_threads(int threads) {
#ifdef _OPENMP
    if (threads == 0) return omp_get_max_threads();
#endif
    return threads < 1 ? 1 : threads;
}

template <class Function>
void parallel_for(int threads, i64 n, const Function& function) {
#ifdef _OPENMP
    if (threads > 1 && n > 2048) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (i64 i = 0; i < n; ++i) function(i);
        return;
    }
#endif
    (void)threads;
    for (i64 i = 0; i < n; ++i) function(i);
}

// offsets[i] = sum of counts[0..i), offsets has counts.size() + 1 entries.
// Integer sums: the result is exact and the same in any order.
void exclusive_scan(const std::vector<i32>& counts, std::vector<i32>& offsets) {
    offsets.resize(counts.size() + 1);
    i64 sum = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
        offsets[i] = static_cast<i32>(sum);
        sum += counts[i];
    }
    if (sum > std::numeric_limits<i32>::max()) throw Error("tetiso::reduce: mesh too large for 32-bit indices");
    offsets[counts.size()] = static_cast<i32>(sum);
}

// ---------------------------------------------------------------------------
// Small geometry in double precision (coordinates are stored as float).

struct Vec {
    double x, y, z;
};
inline Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec operator*(double s, Vec a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm2(Vec a) { return dot(a, a); }
inline double norm(Vec a) { return std::sqrt(dot(a, a)); }

// Sine of the smallest angle of triangle (a, b, c): twice the area over the
// product of the two longer sides. 0 for a degenerate triangle.
inline double quality(Vec a, Vec b, Vec c, Vec* normal_out = nullptr) {
    const Vec ab = b - a, bc = c - b, ca = a - c;
    const Vec n = cross(ab, c - a);
    const double area2 = norm(n);
    if (normal_out) *normal_out = area2 > 0 ? (1.0 / area2) * n : Vec{0, 0, 0};
    double l0 = norm2(ab), l1 = norm2(bc), l2 = norm2(ca);
    // Drop the shortest side.
    const double shortest = std::min(l0, std::min(l1, l2));
    double product;
    if (shortest == l0) product = l1 * l2;
    else if (shortest == l1) product = l0 * l2;
    else product = l0 * l1;
    return product > 0 ? area2 / std::sqrt(product) : 0.0;
}

inline double point_segment_distance(Vec p, Vec a, Vec b) {
    const Vec ab = b - a;
    const double len2 = norm2(ab);
    double t = len2 > 0 ? dot(p - a, ab) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return norm(p - (a + t * ab));
}

// Deterministic 64-bit mixing (splitmix64 finaliser).
inline u64 mix64(u64 x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

// ---------------------------------------------------------------------------
// The surface being reduced.

struct Surface {
    std::vector<float> x, y, z;
    std::vector<EdgeKey> key;
    std::vector<u8> flags;
    std::vector<i32> tri;
    // Per triangle: bound on the distance between this triangle and the input
    // surface it stands for (see evaluate()).
    std::vector<float> err;

    i32 vertices() const { return static_cast<i32>(key.size()); }
    i32 triangles() const { return static_cast<i32>(tri.size() / 3); }
    Vec pos(i32 v) const {
        const auto i = static_cast<std::size_t>(v);
        return {x[i], y[i], z[i]};
    }
    bool locked(i32 v) const { return (flags[static_cast<std::size_t>(v)] & kLocked) != 0; }
};

std::string key_text(const Surface& s, i32 v) { return std::to_string(s.key[static_cast<std::size_t>(v)]); }

// ---------------------------------------------------------------------------
// Step 1: fans. For vertex v, slots off[v] .. off[v+1] list its triangles in
// counter-clockwise order (seen from the side the normals point to); in the
// triangle of slot s the corners run v, next[s], prev[s], and the triangle of
// slot s+1 is the one across edge (v, prev[s]). A border vertex's fan is a
// path starting at the triangle whose edge (v, next) is a border edge; an
// interior vertex's fan is a cycle starting at its smallest triangle index.

struct Fans {
    std::vector<i32> off, face, next, prev;
    std::vector<u8> border;

    i32 k(i32 v) const { return off[static_cast<std::size_t>(v) + 1] - off[static_cast<std::size_t>(v)]; }
    // Neighbours: k of them for an interior vertex, k + 1 on the border.
    i32 nn(i32 v) const { return k(v) + border[static_cast<std::size_t>(v)]; }
    i32 nbr(i32 v, i32 j) const {
        const i32 o = off[static_cast<std::size_t>(v)];
        return j < k(v) ? next[static_cast<std::size_t>(o + j)] : prev[static_cast<std::size_t>(o + j - 1)];
    }
};

enum FanProblem : u8 { kFanOk = 0, kEdgeCount, kEdgeDirection, kVertexFans };

void build_fans(const Surface& s, int threads, Fans& fans, std::vector<i32>& scratch_count,
                std::vector<i32>& scratch_corner) {
    const i32 nv = s.vertices(), nt = s.triangles();
    auto& count = scratch_count;
    count.assign(static_cast<std::size_t>(nv), 0);
    for (i32 c = 0; c < 3 * nt; ++c) ++count[static_cast<std::size_t>(s.tri[static_cast<std::size_t>(c)])];
    exclusive_scan(count, fans.off);
    // Corners in triangle order within each vertex: a counting sort.
    auto& corner = scratch_corner;
    corner.resize(static_cast<std::size_t>(3 * nt));
    {
        std::vector<i32>& fill = count;
        std::copy(fans.off.begin(), fans.off.end() - 1, fill.begin());
        for (i32 c = 0; c < 3 * nt; ++c) {
            const i32 v = s.tri[static_cast<std::size_t>(c)];
            corner[static_cast<std::size_t>(fill[static_cast<std::size_t>(v)]++)] = c;
        }
    }
    fans.face.resize(corner.size());
    fans.next.resize(corner.size());
    fans.prev.resize(corner.size());
    fans.border.assign(static_cast<std::size_t>(nv), 0);

    // Order each fan; record the first problem per vertex.
    std::vector<u8> problem(static_cast<std::size_t>(nv), kFanOk);
    std::vector<i32> problem_other(static_cast<std::size_t>(nv), -1);
    std::vector<i32> problem_count(static_cast<std::size_t>(nv), 0);
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        const i32 o = fans.off[static_cast<std::size_t>(v)];
        const i32 k = fans.off[static_cast<std::size_t>(v) + 1] - o;
        if (k == 0) return;
        constexpr i32 kSmall = 48;
        i32 tb[kSmall], ab[kSmall], bb[kSmall], ob[kSmall];
        std::vector<i32> heap;
        i32 *t = tb, *a = ab, *b = bb, *order = ob;
        if (k > kSmall) {
            heap.resize(static_cast<std::size_t>(4 * k));
            t = heap.data();
            a = t + k;
            b = a + k;
            order = b + k;
        }
        for (i32 i = 0; i < k; ++i) {
            const i32 c = corner[static_cast<std::size_t>(o + i)];
            const i32 tri = c / 3, r = c % 3;
            t[i] = tri;
            a[i] = s.tri[static_cast<std::size_t>(3 * tri + (r + 1) % 3)];
            b[i] = s.tri[static_cast<std::size_t>(3 * tri + (r + 2) % 3)];
        }
        auto fail = [&](FanProblem what, i32 other, i32 n) {
            problem[static_cast<std::size_t>(v)] = what;
            problem_other[static_cast<std::size_t>(v)] = other;
            problem_count[static_cast<std::size_t>(v)] = n;
        };
        // Each neighbour u: edge (v,u) in at most 2 triangles, once each way.
        for (i32 i = 0; i < k; ++i) {
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
        // A slot without predecessor starts a path (a border edge (v, a)).
        i32 start = -1, starts = 0;
        for (i32 i = 0; i < k; ++i) {
            bool has_pred = false;
            for (i32 j = 0; j < k && !has_pred; ++j) has_pred = b[j] == a[i];
            if (!has_pred) {
                ++starts;
                start = i;
            }
        }
        if (starts > 1) return fail(kVertexFans, -1, 0);
        if (starts == 0) {
            start = 0;
            for (i32 i = 1; i < k; ++i)
                if (t[i] < t[start]) start = i;
        }
        order[0] = start;
        for (i32 step = 1; step < k; ++step) {
            const i32 want = b[order[step - 1]];
            i32 found = -1;
            for (i32 j = 0; j < k; ++j)
                if (a[j] == want) found = j;
            if (found < 0 || found == start) return fail(kVertexFans, -1, 0);
            order[step] = found;
        }
        for (i32 step = 0; step < k; ++step) {
            fans.face[static_cast<std::size_t>(o + step)] = t[order[step]];
            fans.next[static_cast<std::size_t>(o + step)] = a[order[step]];
            fans.prev[static_cast<std::size_t>(o + step)] = b[order[step]];
        }
        fans.border[static_cast<std::size_t>(v)] = starts == 1;
    });
    for (i32 v = 0; v < nv; ++v) {
        const u8 what = problem[static_cast<std::size_t>(v)];
        if (what == kFanOk) continue;
        const i32 u = problem_other[static_cast<std::size_t>(v)];
        std::ostringstream m;
        m << "tetiso::reduce: the input is not an oriented 2-manifold: ";
        if (what == kEdgeCount)
            m << "edge (key " << key_text(s, std::min(u, v)) << ", key " << key_text(s, std::max(u, v)) << ") has "
              << problem_count[static_cast<std::size_t>(v)] << " triangles";
        else if (what == kEdgeDirection)
            m << "edge (key " << key_text(s, std::min(u, v)) << ", key " << key_text(s, std::max(u, v))
              << ") is run in the same direction by both of its triangles (inconsistent orientation)";
        else
            m << "vertex (key " << key_text(s, v) << ") is non-manifold: its triangles form more than one fan";
        throw Error(m.str());
    }
}

// ---------------------------------------------------------------------------
// Step 2: edges. Edge e joins v0[e] < v1[e]; f1[e] is the triangle that runs
// v0 → v1, f2[e] the one that runs v1 → v0 (-1 on the border, at most one of
// them). slot[off[v] + v + j] is the edge to neighbour j of v;
// tedge[3t + r] is the edge from corner r to corner r+1 of triangle t.

struct Edges {
    std::vector<i32> v0, v1, f1, f2;
    std::vector<i32> slot;
    std::vector<i32> tedge;
    i32 count() const { return static_cast<i32>(v0.size()); }
};

void build_edges(const Surface& s, const Fans& fans, int threads, Edges& edges, std::vector<i32>& scratch_count,
                 std::vector<i32>& scratch_offset) {
    const i32 nv = s.vertices();
    auto& count = scratch_count;
    count.assign(static_cast<std::size_t>(nv), 0);
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        i32 c = 0;
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) c += fans.nbr(v, j) > v;
        count[static_cast<std::size_t>(v)] = c;
    });
    auto& eoff = scratch_offset;
    exclusive_scan(count, eoff);
    const i32 ne = eoff[static_cast<std::size_t>(nv)];
    edges.v0.resize(static_cast<std::size_t>(ne));
    edges.v1.resize(static_cast<std::size_t>(ne));
    edges.f1.resize(static_cast<std::size_t>(ne));
    edges.f2.resize(static_cast<std::size_t>(ne));
    edges.slot.assign(fans.face.size() + static_cast<std::size_t>(nv), -1);
    edges.tedge.assign(s.tri.size(), -1);
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        const i32 o = fans.off[static_cast<std::size_t>(v)], k = fans.k(v), n = fans.nn(v);
        const bool border = fans.border[static_cast<std::size_t>(v)];
        i32 e = eoff[static_cast<std::size_t>(v)];
        for (i32 j = 0; j < n; ++j) {
            const i32 u = fans.nbr(v, j);
            if (u < v) continue;
            edges.v0[static_cast<std::size_t>(e)] = v;
            edges.v1[static_cast<std::size_t>(e)] = u;
            edges.f1[static_cast<std::size_t>(e)] = j < k ? fans.face[static_cast<std::size_t>(o + j)] : -1;
            edges.f2[static_cast<std::size_t>(e)] =
                j > 0 ? fans.face[static_cast<std::size_t>(o + j - 1)]
                      : (border ? -1 : fans.face[static_cast<std::size_t>(o + k - 1)]);
            edges.slot[static_cast<std::size_t>(o + v + j)] = e;
            ++e;
        }
    });
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        const i32 o = fans.off[static_cast<std::size_t>(v)], n = fans.nn(v);
        for (i32 j = 0; j < n; ++j) {
            const i32 u = fans.nbr(v, j);
            if (u > v) continue;
            const i32 ou = fans.off[static_cast<std::size_t>(u)];
            for (i32 i = 0, m = fans.nn(u); i < m; ++i)
                if (fans.nbr(u, i) == v) {
                    edges.slot[static_cast<std::size_t>(o + v + j)] = edges.slot[static_cast<std::size_t>(ou + u + i)];
                    break;
                }
        }
        // Triangle edges: each is written by its tail vertex only.
        for (i32 j = 0, k = fans.k(v); j < k; ++j) {
            const i32 t = fans.face[static_cast<std::size_t>(o + j)];
            i32 r = 0;
            while (s.tri[static_cast<std::size_t>(3 * t + r)] != v) ++r;
            edges.tedge[static_cast<std::size_t>(3 * t + r)] = edges.slot[static_cast<std::size_t>(o + v + j)];
        }
    });
}

// ---------------------------------------------------------------------------
// Step 3: per-triangle unit normal (zero when the triangle is degenerate) and
// quality (sine of its smallest angle).

struct Normals {
    std::vector<float> nx, ny, nz, q;
    Vec n(i32 t) const {
        const auto i = static_cast<std::size_t>(t);
        return {nx[i], ny[i], nz[i]};
    }
    bool valid(i32 t) const { return q[static_cast<std::size_t>(t)] > kNormalQuality; }
    // Below this quality a float normal is dominated by rounding.
    static constexpr float kNormalQuality = 1e-5f;
};

void build_normals(const Surface& s, int threads, Normals& normals) {
    const i32 nt = s.triangles();
    normals.nx.resize(static_cast<std::size_t>(nt));
    normals.ny.resize(static_cast<std::size_t>(nt));
    normals.nz.resize(static_cast<std::size_t>(nt));
    normals.q.resize(static_cast<std::size_t>(nt));
    parallel_for(threads, nt, [&](i64 ti) {
        const auto t = static_cast<std::size_t>(ti);
        Vec n;
        const double q = quality(s.pos(s.tri[3 * t]), s.pos(s.tri[3 * t + 1]), s.pos(s.tri[3 * t + 2]), &n);
        normals.nx[t] = static_cast<float>(n.x);
        normals.ny[t] = static_cast<float>(n.y);
        normals.nz[t] = static_cast<float>(n.z);
        normals.q[t] = static_cast<float>(q);
    });
}

// ---------------------------------------------------------------------------
// Step 4: evaluate every edge.
//
// Φ (paper): for an interior edge (u, w) with faces f1 (running u → w) and f2
// and unit normals n1, n2, the leaf of each end is traversed from f1 away from
// f2; the faces met while their normal is at least as close to n1 as to n2
// form part 1, all later faces part 2; Φ_j = min over parts s of min over the
// normals n of part s of n_s · n. The traversal keeps part 1 contiguous, so a
// leaf folded along a line through the edge ("bent" leaf) scores 1 while a
// ridge across the edge does not. t = (2/π) atan(Φ_w / Φ_u),
// Φ = Φ_u t + Φ_w (1 - t), and the collapsed vertex is placed at
// t u + (1 - t) w: when w's leaf is the flatter one, t > 1/2 and the vertex
// stays near u — the less flat end (a corner, a crease) is preserved, and Φ,
// which leans to the less flat end's value as well, stays a smooth minimum.
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
//    produce where the surface passes through a mesh node): collapsed
//    whatever Φ is, with first priority.
//  - valence-3 vertices: an interior free vertex with three neighbours is
//    removed (collapsed into its neighbour of smallest key; the three faces
//    become one), whatever Φ is; the error bound still applies.
//  - flips: an interior edge that is not collapsed is flipped when its faces
//    are nearly coplanar and the flip raises their smaller minimum angle by
//    20 % — the long edge between two narrow triangles.
//
// Legality (all must hold, else the operation is dropped):
//  - link condition: the common neighbours of u and w are exactly the
//    opposite vertices (two inside, one on the border);
//  - every vertex keeps at least 3 neighbours (2 on the border), so no
//    component drops below a tetrahedron; a border loop keeps 3 edges;
//  - every surviving face of the two leaves keeps its orientation (normal
//    turns by at most max_normal_turn) and gets no smaller minimum angle than
//    min(min_angle, its own before), and no face of non-zero area becomes
//    degenerate;
//  - error: new bound = max bound of the faces involved + the largest of the
//    distances of p to the planes of the old faces, of u and w to the planes
//    of the new faces, and (on the border) of u and w to the new border
//    polyline; it must stay <= max_error. Because each triangle carries the
//    bound of the input region it replaced, the bounds add along the history
//    of a region: a one-sided guard, cheap and local (after Ronfard and
//    Rossignac's plane-distance error).

enum OpKind : u8 { kNone = 0, kCollapse = 1, kFlip = 2 };

struct Ops {
    std::vector<u8> kind;
    std::vector<u64> priority;
    std::vector<float> px, py, pz, err;
    std::vector<i32> survivor;
};

struct Params {
    double phi;
    double q_min;        // sin(min_angle)
    double cos_turn;     // cos(max_normal_turn)
    double cos_flip;     // cos(flip_max_dihedral)
    double max_error;    // <= 0: none
    double short_ratio;
    bool flips;
};

constexpr int kPriorityScoreBits = 22;
constexpr int kPriorityHashBits = 40;
constexpr u64 kClassFlip = 0, kClassCollapse = 1, kClassValence3 = 2, kClassShort = 3;

u64 make_priority(u64 cls, double score, u64 hash) {
    score = std::clamp(score, 0.0, 1.0);
    const u64 scale = (u64{1} << kPriorityScoreBits) - 1;
    const u64 s = static_cast<u64>(score * static_cast<double>(scale));
    return (cls << (kPriorityScoreBits + kPriorityHashBits)) | (s << kPriorityHashBits) |
           (hash & ((u64{1} << kPriorityHashBits) - 1));
}

class Evaluator {
public:
    Evaluator(const Surface& s, const Fans& fans, const Edges& edges, const Normals& normals, const Params& params,
              int round)
        : s_(s), fans_(fans), edges_(edges), normals_(normals), p_(params), round_(round) {}

    void operator()(i32 e, Ops& ops) const {
        ops.kind[static_cast<std::size_t>(e)] = kNone;
        const i32 u = edges_.v0[static_cast<std::size_t>(e)], w = edges_.v1[static_cast<std::size_t>(e)];
        const i32 f1 = edges_.f1[static_cast<std::size_t>(e)], f2 = edges_.f2[static_cast<std::size_t>(e)];
        const u64 hash = mix64(s_.key[static_cast<std::size_t>(u)] * 0x9e3779b97f4a7c15ULL ^
                               mix64(s_.key[static_cast<std::size_t>(w)] + static_cast<u64>(round_)));
        if (try_collapse(e, u, w, f1, f2, hash, ops)) return;
        if (p_.flips && f1 >= 0 && f2 >= 0) try_flip(e, u, w, f1, f2, hash, ops);
    }

private:
    i32 third(i32 t, i32 a, i32 b) const {
        for (int r = 0; r < 3; ++r) {
            const i32 v = s_.tri[static_cast<std::size_t>(3 * t + r)];
            if (v != a && v != b) return v;
        }
        return -1;
    }
    i32 slot_of(i32 v, i32 t) const {
        const i32 o = fans_.off[static_cast<std::size_t>(v)], k = fans_.k(v);
        for (i32 j = 0; j < k; ++j)
            if (fans_.face[static_cast<std::size_t>(o + j)] == t) return o + j;
        return -1;
    }
    bool border(i32 v) const { return fans_.border[static_cast<std::size_t>(v)] != 0; }

    // Φ_j of the leaf of v for edge faces f1, f2 (f2 < 0: border edge, one
    // part against n1). dir: +1 when f2 precedes f1 in v's fan, -1 otherwise.
    double leaf_phi(i32 v, i32 f1, i32 f2, Vec n1, Vec n2, int dir) const {
        const i32 o = fans_.off[static_cast<std::size_t>(v)], k = fans_.k(v);
        const i32 s1 = slot_of(v, f1) - o;
        double phi = 1.0;
        if (f2 < 0) {
            for (i32 j = 0; j < k; ++j) {
                const i32 t = fans_.face[static_cast<std::size_t>(o + j)];
                if (t == f1 || !normals_.valid(t)) continue;
                phi = std::min(phi, dot(n1, normals_.n(t)));
            }
            return phi;
        }
        const bool cycle = !border(v);
        bool part1 = true;
        i32 j = s1;
        for (i32 step = 0; step < k; ++step) {
            const i32 t = fans_.face[static_cast<std::size_t>(o + j)];
            if (t == f2) break;
            if (normals_.valid(t)) {
                const Vec n = normals_.n(t);
                const double d1 = dot(n, n1), d2 = dot(n, n2);
                if (part1 && d1 < d2) part1 = false;
                phi = std::min(phi, part1 ? d1 : d2);
            }
            j += dir;
            if (cycle) j = (j + k) % k;
            else if (j < 0 || j >= k) break;
        }
        if (!cycle) {
            // The faces beyond f2 (a path does not wrap around): part 2.
            for (j = slot_of(v, f2) - o - dir; j >= 0 && j < k; j -= dir) {
                const i32 t = fans_.face[static_cast<std::size_t>(o + j)];
                if (normals_.valid(t)) phi = std::min(phi, dot(normals_.n(t), n2));
            }
        }
        return phi;
    }

    // The other border neighbour of border vertex v on border edge (v, u).
    i32 border_other(i32 v, i32 u) const {
        const i32 first = fans_.nbr(v, 0), last = fans_.nbr(v, fans_.k(v));
        return first == u ? last : first;
    }

    bool try_collapse(i32 e, i32 u, i32 w, i32 f1, i32 f2, u64 hash, Ops& ops) const {
        const bool border_edge = f1 < 0 || f2 < 0;
        const bool bu = border(u), bw = border(w);
        if (!border_edge && bu && bw) return false;
        const bool pin_u = s_.locked(u) || (!border_edge && bu);
        const bool pin_w = s_.locked(w) || (!border_edge && bw);
        if (pin_u && pin_w) return false;
        const Vec pu = s_.pos(u), pw = s_.pos(w);
        const i32 c = f1 >= 0 ? third(f1, u, w) : -1;
        const i32 d = f2 >= 0 ? third(f2, u, w) : -1;

        // Valence-3 branch: an interior free vertex with three neighbours,
        // removed through the edge to its neighbour of smallest index (= key).
        for (const i32 mover : {w, u}) {
            const i32 keep = mover == w ? u : w;
            if (border(mover) || s_.locked(mover) || fans_.k(mover) != 3) continue;
            i32 smallest = fans_.nbr(mover, 0);
            for (i32 j = 1; j < 3; ++j) smallest = std::min(smallest, fans_.nbr(mover, j));
            if (smallest != keep) continue;
            return finish_collapse(e, u, w, f1, f2, c, d, s_.pos(keep), keep, kClassValence3, 1.0, hash, ops);
        }

        // Very short edges.
        const double len = norm(pw - pu);
        double other_sum = 0.0;
        int other_n = 0;
        if (c >= 0) {
            const Vec pc = s_.pos(c);
            other_sum += norm(pc - pu) + norm(pc - pw);
            other_n += 2;
        }
        if (d >= 0) {
            const Vec pd = s_.pos(d);
            other_sum += norm(pd - pu) + norm(pd - pw);
            other_n += 2;
        }
        const double local = other_n ? other_sum / other_n : 0.0;
        const bool short_edge = len == 0.0 || len <= p_.short_ratio * local;

        // Φ of both leaves.
        double phi_u = -1.0, phi_w = -1.0;
        if (border_edge) {
            const i32 f = f1 >= 0 ? f1 : f2;
            if (normals_.valid(f)) {
                const Vec n = normals_.n(f);
                phi_u = leaf_phi(u, f, -1, n, n, 1);
                phi_w = leaf_phi(w, f, -1, n, n, 1);
            }
            // 1D criterion along the border polyline.
            const i32 up = border_other(u, w), wn = border_other(w, u);
            const Vec dir = pw - pu;
            const Vec du = pu - s_.pos(up), dw = s_.pos(wn) - pw;
            const double lu = norm(du), lw = norm(dw);
            if (len > 0) {
                phi_u = std::min(phi_u, lu > 0 ? dot(du, dir) / (lu * len) : 1.0);
                phi_w = std::min(phi_w, lw > 0 ? dot(dw, dir) / (lw * len) : 1.0);
            }
        } else {
            const bool v1 = normals_.valid(f1), v2 = normals_.valid(f2);
            if (v1 || v2) {
                const Vec n1 = v1 ? normals_.n(f1) : normals_.n(f2);
                const Vec n2 = v2 ? normals_.n(f2) : n1;
                // In u's fan f2 precedes f1: traverse forward; in w's, backward.
                phi_u = leaf_phi(u, f1, f2, n1, n2, +1);
                phi_w = leaf_phi(w, f1, f2, n1, n2, -1);
            }
        }

        Vec p;
        i32 keep;
        double phi;
        if (pin_u || pin_w) {
            keep = pin_u ? u : w;
            p = s_.pos(keep);
            phi = pin_u ? phi_w : phi_u;
        } else if (phi_u > 0 && phi_w > 0) {
            const double t = (2.0 / kPi) * std::atan(phi_w / phi_u);
            phi = phi_u * t + phi_w * (1.0 - t);
            if (len == 0.0) {
                p = pu;
                keep = u;
            } else {
                p = t * pu + (1.0 - t) * pw;
                keep = t >= 0.5 ? u : w;
            }
        } else {
            // A leaf folds back: Φ gives no position; a short edge still
            // collapses, to its midpoint (it moves by a tiny amount).
            phi = std::min(phi_u, phi_w);
            p = len == 0.0 ? pu : 0.5 * (pu + pw);
            keep = u;
        }
        if (short_edge) {
            const double score = local > 0 ? 1.0 - len / local : 1.0;
            return finish_collapse(e, u, w, f1, f2, c, d, p, keep, kClassShort, score, hash, ops);
        }
        if (!(phi > p_.phi)) return false;
        return finish_collapse(e, u, w, f1, f2, c, d, p, keep, kClassCollapse, phi, hash, ops);
    }

    // Legality and error of collapsing (u, w) to p, keeping vertex `keep`.
    bool finish_collapse(i32 e, i32 u, i32 w, i32 f1, i32 f2, i32 c, i32 d, Vec p, i32 keep, u64 cls,
                         double score, u64 hash, Ops& ops) const {
        const bool border_edge = f1 < 0 || f2 < 0;
        // Link condition.
        const i32 nu = fans_.nn(u), nw = fans_.nn(w);
        i32 common = 0;
        for (i32 i = 0; i < nu; ++i) {
            const i32 x = fans_.nbr(u, i);
            if (x == w) continue;
            for (i32 j = 0; j < nw; ++j)
                if (fans_.nbr(w, j) == x) {
                    if (x != c && x != d) return false;
                    ++common;
                }
        }
        if (common != (border_edge ? 1 : 2)) return false;
        // Valences.
        const bool p_border = border(u) || border(w);
        if (nu + nw - 2 - common < (p_border ? 2 : 3)) return false;
        for (const i32 o : {c, d})
            if (o >= 0 && fans_.nn(o) - 1 < (border(o) ? 2 : 3)) return false;
        double border_error = 0.0;
        if (border_edge) {
            const i32 up = border_other(u, w), wn = border_other(w, u);
            if (up == wn) return false; // a border loop of 3 edges
            const Vec a = s_.pos(up), b = s_.pos(wn);
            for (const Vec q : {s_.pos(u), s_.pos(w)})
                border_error =
                    std::max(border_error, std::min(point_segment_distance(q, a, p), point_segment_distance(q, p, b)));
        }

        // Geometry of the faces of both leaves.
        double err_old = 0.0, plane = 0.0;
        Vec nsum{0, 0, 0};
        for (const i32 v : {u, w}) {
            const Vec pv = s_.pos(v);
            const i32 o = fans_.off[static_cast<std::size_t>(v)], k = fans_.k(v);
            for (i32 j = o; j < o + k; ++j) {
                const i32 t = fans_.face[static_cast<std::size_t>(j)];
                if (v == w && (t == f1 || t == f2)) continue; // seen from u
                err_old = std::max(err_old, static_cast<double>(s_.err[static_cast<std::size_t>(t)]));
                if (normals_.valid(t)) {
                    const Vec n = normals_.n(t);
                    plane = std::max(plane, std::abs(dot(n, p - pv)));
                    nsum = nsum + n;
                }
            }
        }
        double back = 0.0;
        for (const i32 v : {u, w}) {
            const Vec pv = s_.pos(v);
            const i32 o = fans_.off[static_cast<std::size_t>(v)], k = fans_.k(v);
            for (i32 j = o; j < o + k; ++j) {
                const i32 t = fans_.face[static_cast<std::size_t>(j)];
                if (t == f1 || t == f2) continue;
                const Vec a = s_.pos(fans_.next[static_cast<std::size_t>(j)]);
                const Vec b = s_.pos(fans_.prev[static_cast<std::size_t>(j)]);
                Vec n;
                const double q_new = quality(p, a, b, &n);
                const double q_old = normals_.q[static_cast<std::size_t>(t)];
                if (q_new < std::min(p_.q_min, q_old)) return false;
                if (q_old > 0 && !(q_new > 0)) return false;
                if (q_new > 0) {
                    if (normals_.valid(t)) {
                        if (dot(n, normals_.n(t)) < p_.cos_turn) return false;
                    } else if (dot(n, nsum) < 0) {
                        return false;
                    }
                    back = std::max(back, std::abs(dot(n, pv - p)));
                }
            }
        }
        const double err_new = err_old + std::max(std::max(plane, back), border_error);
        if (p_.max_error > 0 && err_new > p_.max_error) return false;

        const auto i = static_cast<std::size_t>(e);
        ops.kind[i] = kCollapse;
        ops.priority[i] = make_priority(cls, score, hash);
        ops.px[i] = static_cast<float>(p.x);
        ops.py[i] = static_cast<float>(p.y);
        ops.pz[i] = static_cast<float>(p.z);
        ops.err[i] = static_cast<float>(err_new);
        ops.survivor[i] = keep;
        return true;
    }

    bool try_flip(i32 e, i32 u, i32 w, i32 f1, i32 f2, u64 hash, Ops& ops) const {
        const i32 c = third(f1, u, w), d = third(f2, u, w);
        if (c == d) return false;
        if (fans_.nn(u) - 1 < (border(u) ? 2 : 3) || fans_.nn(w) - 1 < (border(w) ? 2 : 3)) return false;
        for (i32 j = 0, n = fans_.nn(c); j < n; ++j)
            if (fans_.nbr(c, j) == d) return false;
        const double q_old = std::min(normals_.q[static_cast<std::size_t>(f1)], normals_.q[static_cast<std::size_t>(f2)]);
        const Vec pu = s_.pos(u), pw = s_.pos(w), pc = s_.pos(c), pd = s_.pos(d);
        // f1 = (u, w, c), f2 = (w, u, d) → g1 = (c, u, d), g2 = (d, w, c).
        Vec n1, n2;
        const double q1 = quality(pc, pu, pd, &n1), q2 = quality(pd, pw, pc, &n2);
        const double q_new = std::min(q1, q2);
        if (!(q_new > 1.2 * q_old) || q_new < std::min(p_.q_min, q_old) || !(q_new > 0)) return false;
        if (dot(n1, n2) < p_.cos_flip) return false;
        const bool v1 = normals_.valid(f1), v2 = normals_.valid(f2);
        if (!v1 && !v2) return false;
        const Vec m1 = v1 ? normals_.n(f1) : normals_.n(f2);
        const Vec m2 = v2 ? normals_.n(f2) : m1;
        if (dot(m1, m2) < p_.cos_flip) return false;
        for (const Vec m : {m1, m2})
            for (const Vec n : {n1, n2})
                if (dot(m, n) < p_.cos_flip) return false;
        // Error: the gap between the two diagonals.
        const Vec axis = cross(pw - pu, pd - pc);
        const double axis_len = norm(axis);
        if (!(axis_len > 0)) return false;
        const double gap = std::abs(dot(pc - pu, axis)) / axis_len;
        const double err_new = std::max(s_.err[static_cast<std::size_t>(f1)], s_.err[static_cast<std::size_t>(f2)]) + gap;
        if (p_.max_error > 0 && err_new > p_.max_error) return false;
        const auto i = static_cast<std::size_t>(e);
        ops.kind[i] = kFlip;
        ops.priority[i] = make_priority(kClassFlip, q_new - q_old, hash);
        ops.err[i] = static_cast<float>(err_new);
        return true;
    }

    const Surface& s_;
    const Fans& fans_;
    const Edges& edges_;
    const Normals& normals_;
    const Params& p_;
    int round_;
};

// ---------------------------------------------------------------------------
// Step 5: independent set. Operation o touches the vertex set S(o) (the two
// ends of a collapse; the ends and both opposite vertices of a flip). o is
// chosen when it beats every active operation o' whose S(o') lies within
// path length 1 of S(o): best[v] is the best operation touching v, ring[v]
// the best over v's closed 1-ring, and o wins when ring[v] == o for all v in
// S(o). Two winners are then at path length >= 2, so their leaves share no
// face and the tests each passed stay valid. Ties in priority fall to the
// vertex keys. Later passes add operations that stay clear of all winners.

class Selector {
public:
    Selector(const Surface& s, const Fans& fans, const Edges& edges, const Ops& ops)
        : s_(s), fans_(fans), edges_(edges), ops_(ops) {}

    // True when operation a ranks above operation b (b may be -1).
    bool beats(i32 a, i32 b) const {
        if (b < 0) return true;
        const u64 pa = ops_.priority[static_cast<std::size_t>(a)], pb = ops_.priority[static_cast<std::size_t>(b)];
        if (pa != pb) return pa > pb;
        const EdgeKey a0 = s_.key[static_cast<std::size_t>(edges_.v0[static_cast<std::size_t>(a)])];
        const EdgeKey b0 = s_.key[static_cast<std::size_t>(edges_.v0[static_cast<std::size_t>(b)])];
        if (a0 != b0) return a0 > b0;
        return s_.key[static_cast<std::size_t>(edges_.v1[static_cast<std::size_t>(a)])] >
               s_.key[static_cast<std::size_t>(edges_.v1[static_cast<std::size_t>(b)])];
    }

    // The vertices an operation touches (2 or 4).
    int touched(i32 e, i32 out[4]) const {
        out[0] = edges_.v0[static_cast<std::size_t>(e)];
        out[1] = edges_.v1[static_cast<std::size_t>(e)];
        if (ops_.kind[static_cast<std::size_t>(e)] != kFlip) return 2;
        out[2] = third(edges_.f1[static_cast<std::size_t>(e)], out[0], out[1]);
        out[3] = third(edges_.f2[static_cast<std::size_t>(e)], out[0], out[1]);
        return 4;
    }

    void select(int threads, int passes, std::vector<u8>& active, std::vector<u8>& chosen) const {
        const i32 nv = s_.vertices(), ne = edges_.count();
        std::vector<i32> best(static_cast<std::size_t>(nv)), ring(static_cast<std::size_t>(nv));
        std::vector<u8> end(static_cast<std::size_t>(nv)), claimed(static_cast<std::size_t>(nv));
        for (int pass = 0; pass < passes; ++pass) {
            // best[v]: over edges at v and flips of the edges opposite v.
            parallel_for(threads, nv, [&](i64 vi) {
                const i32 v = static_cast<i32>(vi);
                const i32 o = fans_.off[static_cast<std::size_t>(v)], k = fans_.k(v), n = fans_.nn(v);
                i32 b = -1;
                for (i32 j = 0; j < n; ++j) {
                    const i32 e = edges_.slot[static_cast<std::size_t>(o + v + j)];
                    if (active[static_cast<std::size_t>(e)] && beats(e, b)) b = e;
                }
                for (i32 j = 0; j < k; ++j) {
                    const i32 t = fans_.face[static_cast<std::size_t>(o + j)];
                    i32 r = 0;
                    while (s_.tri[static_cast<std::size_t>(3 * t + r)] != v) ++r;
                    const i32 e = edges_.tedge[static_cast<std::size_t>(3 * t + (r + 1) % 3)];
                    if (active[static_cast<std::size_t>(e)] && ops_.kind[static_cast<std::size_t>(e)] == kFlip &&
                        beats(e, b))
                        b = e;
                }
                best[static_cast<std::size_t>(v)] = b;
            });
            parallel_for(threads, nv, [&](i64 vi) {
                const i32 v = static_cast<i32>(vi);
                i32 b = best[static_cast<std::size_t>(v)];
                for (i32 j = 0, n = fans_.nn(v); j < n; ++j) {
                    const i32 x = best[static_cast<std::size_t>(fans_.nbr(v, j))];
                    if (x >= 0 && beats(x, b)) b = x;
                }
                ring[static_cast<std::size_t>(v)] = b;
                end[static_cast<std::size_t>(v)] = 0;
            });
            i64 winners = 0;
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : winners) if (threads > 1 && ne > 2048)
#endif
            for (i32 e = 0; e < ne; ++e) {
                if (!active[static_cast<std::size_t>(e)]) continue;
                i32 vs[4];
                const int n = touched(e, vs);
                bool win = true;
                for (int i = 0; i < n && win; ++i) win = ring[static_cast<std::size_t>(vs[i])] == e;
                if (!win) continue;
                chosen[static_cast<std::size_t>(e)] = 1;
                for (int i = 0; i < n; ++i) end[static_cast<std::size_t>(vs[i])] = 1;
                ++winners;
            }
            if (winners == 0 || pass + 1 == passes) break;
            parallel_for(threads, nv, [&](i64 vi) {
                const i32 v = static_cast<i32>(vi);
                u8 c = end[static_cast<std::size_t>(v)];
                for (i32 j = 0, n = fans_.nn(v); j < n && !c; ++j) c = end[static_cast<std::size_t>(fans_.nbr(v, j))];
                claimed[static_cast<std::size_t>(v)] = c;
            });
            i64 left = 0;
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : left) if (threads > 1 && ne > 2048)
#endif
            for (i32 e = 0; e < ne; ++e) {
                if (!active[static_cast<std::size_t>(e)]) continue;
                i32 vs[4];
                const int n = touched(e, vs);
                bool free = true;
                for (int i = 0; i < n && free; ++i) free = !claimed[static_cast<std::size_t>(vs[i])];
                active[static_cast<std::size_t>(e)] = free;
                left += free;
            }
            if (left == 0) break;
        }
    }

private:
    i32 third(i32 t, i32 a, i32 b) const {
        for (int r = 0; r < 3; ++r) {
            const i32 v = s_.tri[static_cast<std::size_t>(3 * t + r)];
            if (v != a && v != b) return v;
        }
        return -1;
    }

    const Surface& s_;
    const Fans& fans_;
    const Edges& edges_;
    const Ops& ops_;
};

// ---------------------------------------------------------------------------
// The driver.

void check_input(const Piece& in) {
    const std::size_t nv = in.key.size();
    if (in.x.size() != nv || in.y.size() != nv || in.z.size() != nv)
        throw Error("tetiso::reduce: x, y, z and key differ in length");
    if (!in.flags.empty() && in.flags.size() != nv) throw Error("tetiso::reduce: flags and key differ in length");
    if (in.triangles.size() % 3 != 0) throw Error("tetiso::reduce: the triangle array is not a multiple of 3");
    if (nv > static_cast<std::size_t>(std::numeric_limits<i32>::max()) ||
        in.triangles.size() > static_cast<std::size_t>(std::numeric_limits<i32>::max()))
        throw Error("tetiso::reduce: mesh too large for 32-bit indices");
    for (std::size_t v = 1; v < nv; ++v)
        if (!(in.key[v - 1] < in.key[v]))
            throw Error("tetiso::reduce: vertex keys are not sorted and unique at vertex " + std::to_string(v) +
                        " (key " + std::to_string(in.key[v]) + ")");
    for (std::size_t v = 0; v < nv; ++v)
        if (!std::isfinite(in.x[v]) || !std::isfinite(in.y[v]) || !std::isfinite(in.z[v]))
            throw Error("tetiso::reduce: vertex (key " + std::to_string(in.key[v]) + ") has a coordinate that is not finite");
    for (std::size_t t = 0; t < in.triangle_count(); ++t) {
        const i32 a = in.triangles[3 * t], b = in.triangles[3 * t + 1], c = in.triangles[3 * t + 2];
        for (const i32 v : {a, b, c})
            if (v < 0 || static_cast<std::size_t>(v) >= nv)
                throw Error("tetiso::reduce: triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                            " of " + std::to_string(nv));
        if (a == b || b == c || c == a)
            throw Error("tetiso::reduce: triangle " + std::to_string(t) + " repeats vertex (key " +
                        std::to_string(in.key[static_cast<std::size_t>(a == b || a == c ? a : b)]) + ")");
    }
}

void check_options(const ReduceOptions& o) {
    auto bad = [](const std::string& what) { throw Error("tetiso::reduce: " + what); };
    if (!(o.phi > 0.0 && o.phi <= 1.0)) bad("phi = " + std::to_string(o.phi) + " is outside (0, 1]");
    if (o.threads < 0) bad("threads = " + std::to_string(o.threads) + " is negative");
    if (o.max_rounds < 0) bad("max_rounds = " + std::to_string(o.max_rounds) + " is negative");
    if (!(o.min_angle_degrees >= 0.0 && o.min_angle_degrees <= 30.0))
        bad("min_angle_degrees = " + std::to_string(o.min_angle_degrees) + " is outside [0, 30]");
    if (std::isnan(o.max_error)) bad("max_error is NaN");
    if (!(o.max_normal_turn_degrees > 0.0 && o.max_normal_turn_degrees < 90.0))
        bad("max_normal_turn_degrees = " + std::to_string(o.max_normal_turn_degrees) + " is outside (0, 90)");
    if (!(o.short_edge_ratio >= 0.0 && o.short_edge_ratio < 1.0))
        bad("short_edge_ratio = " + std::to_string(o.short_edge_ratio) + " is outside [0, 1)");
    if (!(o.flip_max_dihedral_degrees >= 0.0 && o.flip_max_dihedral_degrees < 90.0))
        bad("flip_max_dihedral_degrees = " + std::to_string(o.flip_max_dihedral_degrees) + " is outside [0, 90)");
    if (o.selection_passes < 1) bad("selection_passes = " + std::to_string(o.selection_passes) + " is below 1");
}

} // namespace

Piece reduce(const Piece& in, const ReduceOptions& options, ReduceReport* report) {
    const auto start_time = std::chrono::steady_clock::now();
    check_options(options);
    check_input(in);
    const int threads = resolve_threads(options.threads);
    const Params params{options.phi,
                        std::sin(options.min_angle_degrees * kPi / 180.0),
                        std::cos(options.max_normal_turn_degrees * kPi / 180.0),
                        std::cos(options.flip_max_dihedral_degrees * kPi / 180.0),
                        options.max_error,
                        options.short_edge_ratio,
                        options.flips};

    Surface s{in.x, in.y, in.z, in.key,
              in.flags.empty() ? std::vector<u8>(in.key.size(), 0) : in.flags, in.triangles,
              std::vector<float>(in.triangle_count(), 0.0f)};
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    rep = ReduceReport{};
    rep.triangles_in = in.triangle_count();
    rep.vertices_in = in.vertex_count();

    Fans fans;
    Edges edges;
    Normals normals;
    Ops ops;
    std::vector<i32> scratch_a, scratch_b;
    std::vector<u8> active, chosen, vertex_alive, triangle_alive;
    std::vector<i32> remap;
    int idle_rounds = 0;

    // The first round validates the input: build_fans throws on non-manifold
    // or misoriented input before anything is changed.
    for (int round = 0;; ++round) {
        build_fans(s, threads, fans, scratch_a, scratch_b);
        if (round >= options.max_rounds) break;
        build_edges(s, fans, threads, edges, scratch_a, scratch_b);
        build_normals(s, threads, normals);
        const i32 ne = edges.count();
        ops.kind.resize(static_cast<std::size_t>(ne));
        ops.priority.resize(static_cast<std::size_t>(ne));
        ops.px.resize(static_cast<std::size_t>(ne));
        ops.py.resize(static_cast<std::size_t>(ne));
        ops.pz.resize(static_cast<std::size_t>(ne));
        ops.err.resize(static_cast<std::size_t>(ne));
        ops.survivor.resize(static_cast<std::size_t>(ne));
        const Evaluator evaluate(s, fans, edges, normals, params, round);
        parallel_for(threads, ne, [&](i64 e) { evaluate(static_cast<i32>(e), ops); });

        active.resize(static_cast<std::size_t>(ne));
        chosen.assign(static_cast<std::size_t>(ne), 0);
        std::size_t candidates = 0;
        for (i32 e = 0; e < ne; ++e) {
            active[static_cast<std::size_t>(e)] = ops.kind[static_cast<std::size_t>(e)] != kNone;
            candidates += active[static_cast<std::size_t>(e)];
        }
        ReduceRound stats;
        stats.round = round;
        stats.candidates = candidates;
        if (candidates == 0) {
            rep.rounds.push_back(stats);
            break;
        }
        const Selector selector(s, fans, edges, ops);
        selector.select(threads, options.selection_passes, active, chosen);

        // Step 6: apply. Chosen operations share no triangle and no vertex.
        const i32 nv = s.vertices(), nt = s.triangles();
        vertex_alive.assign(static_cast<std::size_t>(nv), 1);
        triangle_alive.assign(static_cast<std::size_t>(nt), 1);
        std::size_t collapses = 0, flips = 0;
        for (i32 e = 0; e < ne; ++e)
            if (chosen[static_cast<std::size_t>(e)]) {
                if (ops.kind[static_cast<std::size_t>(e)] == kCollapse) ++collapses;
                else ++flips;
            }
        parallel_for(threads, ne, [&](i64 ei) {
            const auto e = static_cast<std::size_t>(ei);
            if (!chosen[e]) return;
            const i32 u = edges.v0[e], w = edges.v1[e], f1 = edges.f1[e], f2 = edges.f2[e];
            const float err = ops.err[e];
            if (ops.kind[e] == kFlip) {
                i32 c = -1, d = -1;
                for (int r = 0; r < 3; ++r) {
                    const i32 a = s.tri[static_cast<std::size_t>(3 * f1 + r)], b = s.tri[static_cast<std::size_t>(3 * f2 + r)];
                    if (a != u && a != w) c = a;
                    if (b != u && b != w) d = b;
                }
                // f1 = (u, w, c), f2 = (w, u, d) → (c, u, d), (d, w, c).
                const i32 g1[3] = {c, u, d}, g2[3] = {d, w, c};
                for (int r = 0; r < 3; ++r) {
                    s.tri[static_cast<std::size_t>(3 * f1 + r)] = g1[r];
                    s.tri[static_cast<std::size_t>(3 * f2 + r)] = g2[r];
                }
                s.err[static_cast<std::size_t>(f1)] = err;
                s.err[static_cast<std::size_t>(f2)] = err;
                return;
            }
            const i32 keep = ops.survivor[e], gone = keep == u ? w : u;
            if (!s.locked(keep)) {
                s.x[static_cast<std::size_t>(keep)] = ops.px[e];
                s.y[static_cast<std::size_t>(keep)] = ops.py[e];
                s.z[static_cast<std::size_t>(keep)] = ops.pz[e];
            }
            vertex_alive[static_cast<std::size_t>(gone)] = 0;
            for (const i32 v : {keep, gone}) {
                const i32 o = fans.off[static_cast<std::size_t>(v)], k = fans.k(v);
                for (i32 j = o; j < o + k; ++j) {
                    const i32 t = fans.face[static_cast<std::size_t>(j)];
                    if (t == f1 || t == f2) {
                        triangle_alive[static_cast<std::size_t>(t)] = 0;
                        continue;
                    }
                    s.err[static_cast<std::size_t>(t)] = err;
                    if (v == gone)
                        for (int r = 0; r < 3; ++r)
                            if (s.tri[static_cast<std::size_t>(3 * t + r)] == gone)
                                s.tri[static_cast<std::size_t>(3 * t + r)] = keep;
                }
            }
        });
        stats.collapses = collapses;
        stats.flips = flips;
        rep.rounds.push_back(stats);

        // Step 7: compact, keeping order.
        if (collapses > 0) {
            remap.resize(static_cast<std::size_t>(nv));
            i32 next = 0;
            for (i32 v = 0; v < nv; ++v) remap[static_cast<std::size_t>(v)] = vertex_alive[static_cast<std::size_t>(v)] ? next++ : -1;
            for (i32 v = 0; v < nv; ++v) {
                const i32 r = remap[static_cast<std::size_t>(v)];
                if (r < 0) continue;
                const auto a = static_cast<std::size_t>(r), b = static_cast<std::size_t>(v);
                s.x[a] = s.x[b];
                s.y[a] = s.y[b];
                s.z[a] = s.z[b];
                s.key[a] = s.key[b];
                s.flags[a] = s.flags[b];
            }
            s.x.resize(static_cast<std::size_t>(next));
            s.y.resize(static_cast<std::size_t>(next));
            s.z.resize(static_cast<std::size_t>(next));
            s.key.resize(static_cast<std::size_t>(next));
            s.flags.resize(static_cast<std::size_t>(next));
            i32 tn = 0;
            for (i32 t = 0; t < nt; ++t) {
                if (!triangle_alive[static_cast<std::size_t>(t)]) continue;
                for (int r = 0; r < 3; ++r)
                    s.tri[static_cast<std::size_t>(3 * tn + r)] =
                        remap[static_cast<std::size_t>(s.tri[static_cast<std::size_t>(3 * t + r)])];
                s.err[static_cast<std::size_t>(tn)] = s.err[static_cast<std::size_t>(t)];
                ++tn;
            }
            s.tri.resize(static_cast<std::size_t>(3 * tn));
            s.err.resize(static_cast<std::size_t>(tn));
        }
        idle_rounds = collapses == 0 ? idle_rounds + 1 : 0;
        if (idle_rounds >= 2) break;
    }

    Piece out;
    out.x = std::move(s.x);
    out.y = std::move(s.y);
    out.z = std::move(s.z);
    out.key = std::move(s.key);
    out.flags = std::move(s.flags);
    out.triangles = std::move(s.tri);
    out.domains = in.domains;
    rep.triangles_out = out.triangle_count();
    rep.vertices_out = out.vertex_count();
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return out;
}

} // namespace tetiso
