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
//   4. classify:  per edge, the collapse branch that applies and the
//                 priority (cheap: lengths, valences, no Φ);
//   5. select:    an independent set — no two chosen operations closer than
//                 path length 2 — the paper's greedy choice in priority
//                 order, made on several threads by deterministic
//                 reservations; Φ, the position and the legality tests are
//                 computed here, only for what could still be chosen; then
//                 the flips;
//   6. apply:     the chosen operations touch disjoint triangles and vertices;
//   7. compact:   drop removed vertices and triangles, keeping their order (so
//                 vertex keys stay sorted).
// Every per-element computation depends on that element's inputs only and no
// floating-point value is ever summed across elements, so the output is the
// same for any thread count.
#include "tetiso/reduce.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <initializer_list>
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
using u32 = std::uint32_t;
using u64 = std::uint64_t;
using u8 = std::uint8_t;
using u16 = std::uint16_t;

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------
// Parallel primitives. Everything above them is written per element.

int resolve_threads(int threads) {
#ifdef _OPENMP
    if (threads == 0) return omp_get_max_threads();
#endif
    return threads < 1 ? 1 : threads;
}

// The most threads a round uses, whatever it is offered: the most measured.
// A round is a dozen short parallel loops with a join after each. While the
// lists, masks, counting sorts and compaction of a round ran on one thread,
// eight threads beat sixteen on the 16-core device (session 12); with them
// parallel (session 28), sixteen were as fast or faster at every size, from
// an 84 K-triangle gyroid surface (0.195 against 0.227 s, medians of 3) to
// the 1.64 M-triangle paper surface at N = 100 (2.44 against 3.72 s;
// results/speedup/README.md).
constexpr int kMaxRoundThreads = 16;

// Below this many elements a loop runs on the calling thread: a fork and join
// costs more than the work, and far more on an oversubscribed machine.
constexpr i64 kParallelMin = 16384;
// The same for loops that run legality tests, which cost microseconds each
// and most in the late rounds, where the candidates are few: with the
// threshold above, a domain's late rounds ran on one thread whatever the
// count (on the device, a domain-sized surface's selection gained 1.7x from
// 16 threads and its proposals 4.0x; with this one the selection gains 2.9x:
// results/speedup/device-n500-s8-reduce-threads.txt).
constexpr i64 kParallelMinTests = 64;

// min_parallel: the size below which the loop stays on the calling thread.
template <class Function>
void parallel_for(int threads, i64 n, const Function& function, i64 min_parallel = kParallelMin) {
#ifdef _OPENMP
    if (threads > 1 && n > min_parallel) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (i64 i = 0; i < n; ++i) function(i);
        return;
    }
#endif
    (void)threads;
    for (i64 i = 0; i < n; ++i) function(i);
}

// parallel_for for loops of legality tests (or sample moves, which cost as
// much): few elements, uneven costs, so a low threshold and dynamic chunks.
template <class Function>
void parallel_for_tests(int threads, i64 n, const Function& function) {
#ifdef _OPENMP
    if (threads > 1 && n > kParallelMinTests) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 16)
        for (i64 i = 0; i < n; ++i) function(i);
        return;
    }
#endif
    (void)threads;
    for (i64 i = 0; i < n; ++i) function(i);
}

// parallel_for's threshold for the reservations' window: a few thousand
// cheap elements per loop, in contiguous blocks (a static schedule) so that
// threads do not share the cache lines of a per-element byte array.
constexpr i64 kParallelMinWindow = 2048;

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

// The scans and filters below split [0, n) into one contiguous block per
// thread: each block counts its share, the counts are summed in block order,
// and each block writes its part from there. Integer sums and block order
// only, so the result is the serial loop's for any thread count. Loops that
// stayed serial while the rest of a round ran on eight threads (the lists of
// candidates and flips, the refusal masks, the counting sorts, compaction)
// held a large part of a multi-threaded round's time.
struct Blocks {
    i64 n, count;
    Blocks(int threads, i64 size) : n(size), count(threads > 1 && size > kParallelMin ? threads : 1) {}
    i64 begin(i64 b) const { return n * b / count; }
    bool parallel() const { return count > 1; }
};

// first[b] = the number of kept elements in the blocks before block b, for
// b = 0 .. blocks.count (the last: all of them). keep runs once per element.
template <class Keep>
std::vector<i64> block_starts(int threads, const Blocks& blocks, const Keep& keep) {
    std::vector<i64> first(static_cast<std::size_t>(blocks.count) + 1, 0);
    parallel_for(blocks.parallel() ? threads : 1, blocks.count, [&](i64 b) {
        i64 c = 0;
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i) c += keep(i) ? 1 : 0;
        first[static_cast<std::size_t>(b) + 1] = c;
    }, 0);
    for (std::size_t b = 0; b < static_cast<std::size_t>(blocks.count); ++b) first[b + 1] += first[b];
    return first;
}

// out = every i < n with keep(i), ascending. keep runs twice per element on
// several threads (count, then write), so it must be cheap and pure.
template <class Keep>
void parallel_filter(int threads, i64 n, const Keep& keep, std::vector<i32>& out) {
    const Blocks blocks(threads, n);
    if (!blocks.parallel()) {
        out.clear();
        for (i64 i = 0; i < n; ++i)
            if (keep(i)) out.push_back(static_cast<i32>(i));
        return;
    }
    const std::vector<i64> first = block_starts(threads, blocks, keep);
    out.resize(static_cast<std::size_t>(first.back()));
    parallel_for(threads, blocks.count, [&](i64 b) {
        auto at = static_cast<std::size_t>(first[static_cast<std::size_t>(b)]);
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i)
            if (keep(i)) out[at++] = static_cast<i32>(i);
    }, 0);
}

// rank[i] = the number of kept elements before i, for each kept i; -1 for
// the others. Returns the number kept.
template <class Keep>
i32 parallel_rank(int threads, i64 n, const Keep& keep, std::vector<i32>& rank) {
    rank.resize(static_cast<std::size_t>(n));
    const Blocks blocks(threads, n);
    if (!blocks.parallel()) {
        i32 next = 0;
        for (i64 i = 0; i < n; ++i) rank[static_cast<std::size_t>(i)] = keep(i) ? next++ : -1;
        return next;
    }
    const std::vector<i64> first = block_starts(threads, blocks, keep);
    parallel_for(threads, blocks.count, [&](i64 b) {
        i64 next = first[static_cast<std::size_t>(b)];
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i)
            rank[static_cast<std::size_t>(i)] = keep(i) ? static_cast<i32>(next++) : -1;
    }, 0);
    return static_cast<i32>(first.back());
}

// The number of i < n with counted(i) (an integer sum).
template <class Counted>
i64 parallel_count(int threads, i64 n, const Counted& counted) {
    return block_starts(threads, Blocks(threads, n), counted).back();
}

// Sorts a short run in place (a vertex's corners, a face's samples): an
// insertion sort, which costs nothing on a run already in order and beats
// std::sort's call on the few elements these runs hold.
inline void sort_short_run(i32* first, i32* last) {
    for (i32* i = first + (first != last); i < last; ++i) {
        const i32 value = *i;
        i32* j = i;
        for (; j > first && *(j - 1) > value; --j) *j = *(j - 1);
        *j = value;
    }
}

// A stable counting sort of the indices 0 .. n-1 by key(i) in 0 .. groups-1:
// group g is order[first[g]] .. order[first[g + 1]], its indices ascending.
// On several threads the counters are atomic, which leaves each group in any
// order, so each is sorted back afterwards: the result is one thread's for
// any count. count: scratch, one per group.
template <class Key>
void group_by_key(int threads, i64 n, i64 groups, const Key& key, std::vector<i32>& first,
                  std::vector<i32>& order, std::vector<i32>& count) {
    const bool atomic = threads > 1 && n > kParallelMin;
    count.assign(static_cast<std::size_t>(groups), 0);
    if (atomic)
        parallel_for(threads, n, [&](i64 i) {
            std::atomic_ref<i32>(count[static_cast<std::size_t>(key(i))]).fetch_add(1, std::memory_order_relaxed);
        });
    else
        for (i64 i = 0; i < n; ++i) ++count[static_cast<std::size_t>(key(i))];
    exclusive_scan(count, first);
    parallel_for(threads, groups, [&](i64 g) { count[static_cast<std::size_t>(g)] = first[static_cast<std::size_t>(g)]; });
    order.resize(static_cast<std::size_t>(n));
    if (!atomic) {
        for (i64 i = 0; i < n; ++i) order[static_cast<std::size_t>(count[static_cast<std::size_t>(key(i))]++)] = static_cast<i32>(i);
        return;
    }
    parallel_for(threads, n, [&](i64 i) {
        const i32 at = std::atomic_ref<i32>(count[static_cast<std::size_t>(key(i))]).fetch_add(1, std::memory_order_relaxed);
        order[static_cast<std::size_t>(at)] = static_cast<i32>(i);
    });
    parallel_for(threads, groups, [&](i64 g) {
        sort_short_run(order.data() + first[static_cast<std::size_t>(g)], order.data() + first[static_cast<std::size_t>(g) + 1]);
    });
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
// product of the two longer sides. 0 for a degenerate triangle. height_out:
// the height over the longest side.
inline double quality(Vec a, Vec b, Vec c, Vec* normal_out = nullptr, double* height_out = nullptr) {
    const Vec ab = b - a, bc = c - b, ca = a - c;
    const Vec n = cross(ab, c - a);
    const double area2 = norm(n);
    if (normal_out) *normal_out = area2 > 0 ? (1.0 / area2) * n : Vec{0, 0, 0};
    double l0 = norm2(ab), l1 = norm2(bc), l2 = norm2(ca);
    if (height_out) {
        const double longest = std::max(l0, std::max(l1, l2));
        *height_out = longest > 0 ? area2 / std::sqrt(longest) : 0.0;
    }
    // Drop the shortest side.
    const double shortest = std::min(l0, std::min(l1, l2));
    double product;
    if (shortest == l0) product = l1 * l2;
    else if (shortest == l1) product = l0 * l2;
    else product = l0 * l1;
    return product > 0 ? area2 / std::sqrt(product) : 0.0;
}

// Whether triangles (a, b1, c1) and (a, b2, c2), with unit normals n1 and
// n2, share a point other than their common corner a (they share no other
// corner). Each triangle that crosses the other's plane does so along a
// segment starting at a, on the line common to both planes; the triangles
// overlap exactly when these segments leave a the same way. Triangles that
// lie in one plane (within a millionth of their size: rounding leaves a
// flat surface's corners that far apart) overlap when one's side or bisector
// points strictly into the other's angle at a.
inline bool overlap_at_corner(Vec a, Vec b1, Vec c1, Vec n1, Vec b2, Vec c2, Vec n2) {
    const Vec eb1 = b1 - a, ec1 = c1 - a, eb2 = b2 - a, ec2 = c2 - a;
    const double sb2 = dot(eb2, n1), sc2 = dot(ec2, n1);
    if ((sb2 > 0 && sc2 > 0) || (sb2 < 0 && sc2 < 0)) {
        const double flat = 1e-6 * std::sqrt(std::max(norm2(eb2), norm2(ec2)));
        if (std::abs(sb2) > flat || std::abs(sc2) > flat) return false;
    } else {
        const double sb1 = dot(eb1, n2), sc1 = dot(ec1, n2);
        if ((sb1 > 0 && sc1 > 0) || (sb1 < 0 && sc1 < 0)) return false;
        const double flat = 1e-6 * std::sqrt(std::max({norm2(eb1), norm2(ec1), norm2(eb2), norm2(ec2)}));
        const bool coplanar = std::abs(sb2) <= flat && std::abs(sc2) <= flat;
        if (!coplanar && sb1 != sc1 && sb2 != sc2) {
            const Vec x1 = eb1 + (sb1 / (sb1 - sc1)) * (ec1 - eb1);
            const Vec x2 = eb2 + (sb2 / (sb2 - sc2)) * (ec2 - eb2);
            return dot(x1, x2) > 0;
        }
    }
    // One plane: compare the angles at a, turning about n1.
    auto inside = [&](Vec d, Vec e, Vec f) {
        const double turn = dot(cross(e, f), n1);
        return dot(cross(e, d), n1) * turn > 0 && dot(cross(d, f), n1) * turn > 0;
    };
    auto bisector = [](Vec e, Vec f) { return (1.0 / norm(e)) * e + (1.0 / norm(f)) * f; };
    return inside(eb2, eb1, ec1) || inside(ec2, eb1, ec1) || inside(bisector(eb2, ec2), eb1, ec1) ||
           inside(eb1, eb2, ec2) || inside(ec1, eb2, ec2);
}

// Whether triangles (a, b, c), of unit normal n1, and (b, a, d), which share
// edge (a, b), overlap: only when they lie in one plane with c and d on the
// same side of the edge (the surface folded flat onto itself).
inline bool overlap_at_edge(Vec a, Vec b, Vec c, Vec n1, Vec d) {
    const Vec ab = b - a, ad = d - a;
    if (std::abs(dot(ad, n1)) > 1e-6 * std::sqrt(std::max(norm2(ab), norm2(ad)))) return false;
    return dot(cross(ab, c - a), cross(ab, ad)) > 0;
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

// Positions are interleaved (xyz[3v..3v+2]): the tests read a vertex's three
// coordinates together, from vertices scattered over the arrays, so one
// cache line serves where three did (no gain was measurable on its own on
// the 2-core VM; it costs nothing, and the sample points below do the same).
struct Surface {
    std::vector<float> xyz;
    std::vector<EdgeKey> key;
    std::vector<u8> flags;
    std::vector<i32> tri;
    // Per triangle: bound on the distance between this triangle and the input
    // surface it stands for (see evaluate()).
    std::vector<float> err;

    i32 vertices() const { return static_cast<i32>(key.size()); }
    i32 triangles() const { return static_cast<i32>(tri.size() / 3); }
    Vec pos(i32 v) const {
        const float* p = xyz.data() + 3 * static_cast<std::size_t>(v);
        return {p[0], p[1], p[2]};
    }
    bool locked(i32 v) const { return (flags[static_cast<std::size_t>(v)] & kLocked) != 0; }
};

// Error samples, frozen where this call's input had them. Each is owned by
// one current triangle, the one of its region it was last measured against;
// an operation re-measures the samples of every face it replaces against the
// new faces, so the distance of each sample to the reduced surface is known
// (as an upper bound: the face found, not necessarily the nearest) and never
// accumulates from round to round.
//
// On a raw surface (an input without error bounds) a sample is one input
// vertex, and the bound is exact at every one of them. An input that was
// reduced before (Piece::error set: a seam's region) may carry the raw
// vertices of some triangles (Piece::sample_xyz, the triangles marked
// sampled, which stand for exactly those): each is a sample again, with base
// 0, so the bound stays exact there and a seam's reduction spends the whole
// budget anew rather than what its domains left. Every other triangle stands
// for raw vertices within its error of it, wherever they are: it is one
// sample, its three corners with that error as base. Its distance to a face
// is the largest of its corners', which bounds the distance of every point
// of the triangle (distance to one triangle is convex), so base + distance
// bounds the raw vertices it stands for. Vertex samples with the largest
// error of their triangles as base would not: a raw vertex lies near the
// inside of a triangle, which can stand farther from the new faces than its
// corners do (up to 1.7x the bound over a job's seams on random fields,
// test_random_fields). Bounds add up only across calls whose input lacks
// the raw vertices, e.g. a seam's region beyond the samples a job keeps.
struct Samples {
    struct Point {
        float x, y, z, base;
    };
    // One point per sample, with the sample's base: a raw vertex, or the
    // first corner of a triangle sample, whose other two corners lie in
    // far_point at 2 * far[sample] (far is -1 for a raw vertex, and empty
    // when every sample is one). A seam's region holds mostly raw vertices,
    // so they take one point, not three. Kept in the order of their owners,
    // so the samples of triangle t are one run (its FaceGeometry's
    // samples_begin .. samples_end, which sort() writes) and a test reads
    // them as one run rather than one cache miss each (the loads of
    // scattered samples were 4-5 % of a profile of the paper surface's
    // reduction; the selection step went from 4.96 to 4.6 s with this
    // order). sort() restores the order at the start of every round; an
    // operation changes only owner[], which the points stay in step with.
    // far_point is never reordered: triangle samples are few.
    std::vector<Point> point;
    std::vector<i32> owner; // triangle, per sample
    std::vector<i32> far;
    std::vector<Point> far_point;
    bool enabled = false;

    bool on() const { return enabled; }
    const Point* point_of(std::size_t sample) const { return point.data() + sample; }
    // The other two corners of a triangle sample, or null for a raw vertex.
    const Point* far_corners(std::size_t sample) const {
        return far.empty() || far[sample] < 0 ? nullptr : far_point.data() + 2 * static_cast<std::size_t>(far[sample]);
    }

    void build(const Piece& in) {
        point.clear();
        owner.clear();
        far.clear();
        far_point.clear();
        enabled = true;
        const std::size_t nv = in.vertex_count(), nt = in.triangle_count();
        if (!in.error.empty()) {
            point.reserve(nt + in.sample_count());
            for (std::size_t i = 0; i < in.sample_count(); ++i) {
                point.push_back({in.sample_xyz[3 * i], in.sample_xyz[3 * i + 1], in.sample_xyz[3 * i + 2], 0.0f});
                owner.push_back(in.sample_triangle[i]);
                far.push_back(-1);
            }
            for (std::size_t t = 0; t < nt; ++t) {
                if (in.triangle_sampled(t)) continue;
                for (std::size_t r = 0; r < 3; ++r) {
                    const auto v = static_cast<std::size_t>(in.triangles[3 * t + r]);
                    (r == 0 ? point : far_point).push_back({in.x[v], in.y[v], in.z[v], in.error[t]});
                }
                owner.push_back(static_cast<i32>(t));
                far.push_back(static_cast<i32>(far_point.size() / 2 - 1));
            }
            return;
        }
        // A vertex of no triangle is no sample: no operation can move it.
        std::vector<i32> first(nv, -1);
        for (std::size_t t = nt; t-- > 0;)
            for (std::size_t r = 0; r < 3; ++r) first[static_cast<std::size_t>(in.triangles[3 * t + r])] = static_cast<i32>(t);
        for (std::size_t v = 0; v < nv; ++v)
            if (first[v] >= 0) {
                point.push_back({in.x[v], in.y[v], in.z[v], 0.0f});
                owner.push_back(first[v]);
            }
    }

    // Stable counting sort by owner (group_by_key); each face's range goes
    // straight into its record (faces: the round's FaceGeometry, one per
    // triangle).
    template <class Faces>
    void sort(Faces& faces, int threads) {
        const auto ns = static_cast<i64>(owner.size());
        group_by_key(threads, ns, static_cast<i64>(faces.size()),
                     [&](i64 i) { return owner[static_cast<std::size_t>(i)]; }, begin_, source_, fill_);
        parallel_for(threads, static_cast<i64>(faces.size()), [&](i64 ti) {
            const auto t = static_cast<std::size_t>(ti);
            faces[t].samples_begin = begin_[t];
            faces[t].samples_end = begin_[t + 1];
        });
        sorted_point_.resize(point.size());
        sorted_owner_.resize(owner.size());
        sorted_far_.resize(far.size());
        parallel_for(threads, ns, [&](i64 ai) {
            const auto at = static_cast<std::size_t>(ai);
            const auto i = static_cast<std::size_t>(source_[at]);
            sorted_point_[at] = point[i];
            sorted_owner_[at] = owner[i];
            if (!far.empty()) sorted_far_[at] = far[i];
        });
        point.swap(sorted_point_);
        owner.swap(sorted_owner_);
        far.swap(sorted_far_);
    }

    // Writes the raw vertices among the samples into `out` (see
    // ReduceOptions::keep_samples), grouped by triangle: those of every
    // triangle that holds no sample that is a triangle, which is then marked
    // sampled: it stands for exactly its samples.
    void hand_on(Piece& out) const {
        const std::size_t nt = out.triangle_count();
        std::vector<u8> holds_triangle(nt, 0);
        for (std::size_t i = 0; i < far.size(); ++i)
            if (far[i] >= 0) holds_triangle[static_cast<std::size_t>(owner[i])] = 1;
        std::vector<i32> first(nt + 1, 0);
        for (const i32 t : owner)
            if (!holds_triangle[static_cast<std::size_t>(t)]) ++first[static_cast<std::size_t>(t) + 1];
        for (std::size_t t = 0; t < nt; ++t) first[t + 1] += first[t];
        out.sampled.resize(nt);
        for (std::size_t t = 0; t < nt; ++t) out.sampled[t] = holds_triangle[t] ? 0 : 1;
        out.sample_xyz.resize(3 * static_cast<std::size_t>(first[nt]));
        out.sample_triangle.resize(static_cast<std::size_t>(first[nt]));
        std::vector<i32> at(first.begin(), first.end() - 1);
        for (std::size_t i = 0; i < owner.size(); ++i) {
            const auto t = static_cast<std::size_t>(owner[i]);
            if (holds_triangle[t]) continue;
            const auto j = static_cast<std::size_t>(at[t]++);
            out.sample_xyz[3 * j] = point[i].x;
            out.sample_xyz[3 * j + 1] = point[i].y;
            out.sample_xyz[3 * j + 2] = point[i].z;
            out.sample_triangle[j] = static_cast<i32>(t);
        }
    }

private:
    std::vector<i32> fill_, begin_, source_;
    std::vector<Point> sorted_point_;
    std::vector<i32> sorted_owner_;
    std::vector<i32> sorted_far_;
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
    std::vector<u8> problem; // build_fans's per-vertex findings, kept for reuse

    i32 k(i32 v) const { return off[static_cast<std::size_t>(v) + 1] - off[static_cast<std::size_t>(v)]; }
    // Neighbours: k of them for an interior vertex, k + 1 on the border.
    i32 nn(i32 v) const { return k(v) + border[static_cast<std::size_t>(v)]; }
    // Neighbour j < nn(v): next of each slot, then, on the border, prev of
    // the last slot (read from next/prev rather than a copy of them: one
    // array less to write every round).
    i32 nbr(i32 v, i32 j) const {
        const i32 slot = off[static_cast<std::size_t>(v)] + j;
        return slot < off[static_cast<std::size_t>(v) + 1] ? next[static_cast<std::size_t>(slot)]
                                                           : prev[static_cast<std::size_t>(slot - 1)];
    }
};

enum FanProblem : u8 { kFanOk = 0, kEdgeCount, kEdgeDirection, kVertexFans };

// validate: check every edge and vertex (the input); later rounds only
// order (the operations keep the surface manifold).
void build_fans(const Surface& s, int threads, bool validate, Fans& fans, std::vector<i32>& scratch_count,
                std::vector<i32>& scratch_corner) {
    const i32 nv = s.vertices(), nt = s.triangles();
    // Each vertex's corners, in triangle order.
    auto& corner = scratch_corner;
    group_by_key(threads, 3 * static_cast<i64>(nt), nv,
                 [&](i64 c) { return s.tri[static_cast<std::size_t>(c)]; }, fans.off, corner, scratch_count);
    fans.face.resize(corner.size());
    fans.next.resize(corner.size());
    fans.prev.resize(corner.size());
    fans.border.assign(static_cast<std::size_t>(nv), 0);

    // Order each fan; record the first problem per vertex.
    std::vector<u8>& problem = fans.problem;
    problem.assign(static_cast<std::size_t>(nv), kFanOk);
    std::vector<i32> problem_other(validate ? static_cast<std::size_t>(nv) : 0, -1);
    std::vector<i32> problem_count(validate ? static_cast<std::size_t>(nv) : 0, 0);
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        const i32 o = fans.off[static_cast<std::size_t>(v)];
        const i32 k = fans.off[static_cast<std::size_t>(v) + 1] - o;
        if (k == 0) return;
        constexpr i32 kSmall = 48;
        i32 tb[kSmall], ab[kSmall], bb[kSmall], ob[kSmall], sb[kSmall], pb[kSmall];
        std::vector<i32> heap;
        i32 *t = tb, *a = ab, *b = bb, *order = ob, *succ = sb, *pred = pb;
        if (k > kSmall) {
            heap.resize(static_cast<std::size_t>(6 * k));
            t = heap.data();
            a = t + k;
            b = a + k;
            order = b + k;
            succ = order + k;
            pred = succ + k;
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
            if (!validate) return;
            problem_other[static_cast<std::size_t>(v)] = other;
            problem_count[static_cast<std::size_t>(v)] = n;
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
        // above, or the operations keeping the surface manifold), so the
        // first one found is the one: one search per slot, where looking for
        // predecessors and then for each step's successor took two.
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
            const auto slot = static_cast<std::size_t>(o + step);
            fans.face[slot] = t[order[step]];
            fans.next[slot] = a[order[step]];
            fans.prev[slot] = b[order[step]];
        }
        fans.border[static_cast<std::size_t>(v)] = starts == 1;
    });
    for (i32 v = 0; v < nv; ++v) {
        const u8 what = problem[static_cast<std::size_t>(v)];
        if (what == kFanOk) continue;
        if (!validate)
            throw Error("tetiso::reduce: internal error: vertex (key " + key_text(s, v) + ") became non-manifold");
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
// Step 2: edges. Edge e joins v0[e] < v1[e], and v1 is neighbour s0[e] of v0.
// Everything else about it is read from v0's fan (faces()): f1 is the
// triangle that runs v0 → v1, f2 the one that runs v1 → v0 (-1 on the
// border, at most one of them), c and d their third corners (-1 with them).
// Each edge is written by its smaller end alone. The record is kept to what
// the fan cannot give cheaply: every array here is written once per round and
// read by every step after it, and at 15 workers a round's traffic is what
// slows a task (scripts/probe_contention.py). Storing the faces, opposite
// corners and v0's slot in v1's ring as well (eight arrays, 32 bytes per
// edge) made the edge table the largest thing a round wrote.

struct EdgeFaces {
    i32 f1, f2, c, d;
};

struct Edges {
    std::vector<i32> v0, v1, s0;
    // The edges vertex v owns are first[v] .. first[v + 1]: build_edges
    // writes them grouped by v0, in ascending v0.
    std::vector<i32> first;
    i32 count() const { return static_cast<i32>(v0.size()); }

    EdgeFaces faces(const Fans& fans, i32 e) const {
        const auto i = static_cast<std::size_t>(e);
        const i32 v = v0[i], j = s0[i];
        const i32 o = fans.off[static_cast<std::size_t>(v)], k = fans.k(v);
        // f1 = (v, u, c) sits in slot j, f2 = (u, v, d) in the slot before.
        const i32 before = j > 0 ? o + j - 1 : (fans.border[static_cast<std::size_t>(v)] ? -1 : o + k - 1);
        EdgeFaces r;
        r.f1 = j < k ? fans.face[static_cast<std::size_t>(o + j)] : -1;
        r.c = j < k ? fans.prev[static_cast<std::size_t>(o + j)] : -1;
        r.f2 = before >= 0 ? fans.face[static_cast<std::size_t>(before)] : -1;
        r.d = before >= 0 ? fans.next[static_cast<std::size_t>(before)] : -1;
        return r;
    }
    // A border edge has one face: v1 is v0's last neighbour (no f1), or its
    // first on the border (no f2).
    bool border(const Fans& fans, i32 e) const {
        const auto i = static_cast<std::size_t>(e);
        const i32 v = v0[i], j = s0[i];
        return j == fans.k(v) || (j == 0 && fans.border[static_cast<std::size_t>(v)]);
    }
};

void build_edges(const Fans& fans, int threads, Edges& edges, std::vector<i32>& scratch_count) {
    const i32 nv = static_cast<i32>(fans.off.size()) - 1;
    auto& count = scratch_count;
    count.resize(static_cast<std::size_t>(nv));
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        i32 c = 0;
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) c += fans.nbr(v, j) > v;
        count[static_cast<std::size_t>(v)] = c;
    });
    auto& eoff = edges.first;
    exclusive_scan(count, eoff);
    const auto ne = static_cast<std::size_t>(eoff[static_cast<std::size_t>(nv)]);
    for (auto* a : {&edges.v0, &edges.v1, &edges.s0}) a->resize(ne);
    parallel_for(threads, nv, [&](i64 vi) {
        const i32 v = static_cast<i32>(vi);
        auto e = static_cast<std::size_t>(eoff[static_cast<std::size_t>(v)]);
        for (i32 j = 0, n = fans.nn(v); j < n; ++j) {
            const i32 u = fans.nbr(v, j);
            if (u < v) continue;
            edges.v0[e] = v;
            edges.v1[e] = u;
            edges.s0[e] = j;
            ++e;
        }
    });
}

// ---------------------------------------------------------------------------
// Step 3: per-triangle record of what a legality test reads of each face of
// a leaf: unit normal (zero when the triangle is degenerate), quality (sine
// of its smallest angle), error bound (a copy of Surface::err) and the range
// of its error samples (written by the round's Samples::sort). One 32-byte
// record, so a
// test's first touch of a face is one cache miss where separate arrays for
// the geometry, the bounds and the sample offsets cost three (those loads
// were the hot spots of the tests' profile).

// Whether the normal of triangle (a, b, c), of quality q, is the surface's
// rather than rounding's. Corners are floats: a face whose height over its
// longest side is within a few units in the last place of its coordinates
// has a normal that rounding chose, whatever its quality (a needle one ulp
// wide and a hundred long has q = 0.01). Marching tetrahedra make such faces
// where the surface passes within float resolution of a mesh node: the
// corners near the node then differ in one coordinate alone, by a few ulps,
// and lie on a line. Judging their collapses by those normals refused every
// way out of such a cluster, which stayed in the output as zero-area
// triangles (6 of them in the N = 1000 paper job). Below kValidQuality the
// normal is rounding's at any size.
constexpr double kValidQuality = 1e-5;
constexpr double kRoundingUlps = 4.0;

// q and height: quality()'s, for the same corners.
inline bool resolved(Vec a, Vec b, Vec c, double q, double height) {
    if (!(q > kValidQuality)) return false;
    const double extent = std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z), std::fabs(b.x), std::fabs(b.y),
                                    std::fabs(b.z), std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    return height > kRoundingUlps * std::numeric_limits<float>::epsilon() * extent;
}

// The same, measuring the triangle first (for the few faces that need it).
inline bool resolved(Vec a, Vec b, Vec c) {
    double height;
    const double q = quality(a, b, c, nullptr, &height);
    return resolved(a, b, c, q, height);
}

struct FaceGeometry {
    float nx, ny, nz, q;
    float err;
    i32 samples_begin, samples_end; // samples [begin, end): Samples::point_of
    i32 is_resolved;                // resolved(): the normal means something
    Vec n() const { return {nx, ny, nz}; }
    bool valid() const { return is_resolved != 0; }
};
static_assert(sizeof(FaceGeometry) == 32);

void build_geometry(const Surface& s, int threads, std::vector<FaceGeometry>& geometry) {
    const i32 nt = s.triangles();
    geometry.resize(static_cast<std::size_t>(nt));
    parallel_for(threads, nt, [&](i64 ti) {
        const auto t = static_cast<std::size_t>(ti);
        Vec n;
        const Vec a = s.pos(s.tri[3 * t]), b = s.pos(s.tri[3 * t + 1]), c = s.pos(s.tri[3 * t + 2]);
        double height;
        const double q = quality(a, b, c, &n, &height);
        geometry[t] = {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z), static_cast<float>(q),
                       s.err[t], 0, 0, resolved(a, b, c, q, height) ? 1 : 0};
    });
}

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
// Whether the half-open angle [a, b) at a fan's apex, seen along m (the
// sides ea, eb taken from the apex), holds the ray `ray` (perpendicular to
// m); across = m x ray. starts_on_ray: a is the ray's own side, counted as
// on it whatever rounding says. A fan whose faces all turn the same way
// about the apex turns once around it exactly when one of its angles holds
// the ray along the first side of its first face.
inline bool holds_ray(Vec ea, Vec eb, Vec ray, Vec across, bool starts_on_ray) {
    const double sa = starts_on_ray ? 0.0 : dot(ea, across), sb = dot(eb, across);
    if (!(sa <= 0 && sb > 0)) return false;
    const double t = sa / (sa - sb);
    return dot(ea, ray) + t * (dot(eb, ray) - dot(ea, ray)) > 0;
}

struct Cone {
    float x, y, z; // unit mean normal
    u16 flat;
    u16 beside_sharp; // a neighbour's cone is not flat
};
constexpr double kConeMargin = 1e-3;

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
int owned_corners(const Fans& fans, const std::vector<Cone>& cones, i32 u, i32 w, bool border_edge, i32* out) {
    if (!border_edge && !cones[static_cast<std::size_t>(u)].beside_sharp &&
        !cones[static_cast<std::size_t>(w)].beside_sharp)
        return 0;
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
            if (v != u && v != w && !cones[static_cast<std::size_t>(v)].flat && !add(v)) return -1;
        }
    if (border_edge)
        for (const auto& [end, other] : {std::pair{u, w}, std::pair{w, u}}) {
            const i32 first = fans.nbr(end, 0), last = fans.nbr(end, fans.k(end));
            if (!add(first == other ? last : first)) return -1;
        }
    return n;
}

// A tested operation: chosen, or refused (no possible operation), or legal
// but blocked by a corner it would own that another chosen one claimed.
enum class Verdict : u8 { kIllegal, kBlocked, kLegal };

void build_cones(const Surface& s, const Fans& fans, const std::vector<FaceGeometry>& geometry, int threads,
                 std::vector<Cone>& cones) {
    const auto nv = static_cast<i32>(fans.off.size() - 1);
    cones.resize(static_cast<std::size_t>(nv));
    parallel_for(threads, nv, [&](i64 vi) {
        const auto v = static_cast<std::size_t>(vi);
        Cone& c = cones[v];
        c = {0, 0, 0, 0, 0};
        const i32 begin = fans.off[v], end = fans.off[v + 1];
        Vec m{0, 0, 0};
        for (i32 slot = begin; slot < end; ++slot) {
            const FaceGeometry& g = geometry[static_cast<std::size_t>(fans.face[static_cast<std::size_t>(slot)])];
            if (!g.valid()) return;
            m = m + g.n();
        }
        const double len = norm(m);
        if (!(len > 0)) return;
        m = (1.0 / len) * m;
        c.x = static_cast<float>(m.x);
        c.y = static_cast<float>(m.y);
        c.z = static_cast<float>(m.z);
        const Vec stored{c.x, c.y, c.z};
        for (i32 slot = begin; slot < end; ++slot)
            if (!(dot(geometry[static_cast<std::size_t>(fans.face[static_cast<std::size_t>(slot)])].n(), stored) >
                  2 * kConeMargin))
                return;
        // A border fan must also turn less than once around the vertex, else
        // it could wind over itself (stacked like a ramp) while every face
        // faces m: its faces, in fan order, hold the direction of its first
        // edge only in the first face's angle.
        if (fans.border[v]) {
            const Vec pv = s.pos(static_cast<i32>(vi));
            Vec ray = s.pos(fans.next[static_cast<std::size_t>(begin)]) - pv; // the first face's first side
            ray = ray - dot(ray, stored) * stored;
            const Vec across = cross(stored, ray);
            int holding = 0;
            for (i32 slot = begin; slot < end; ++slot)
                holding += holds_ray(s.pos(fans.next[static_cast<std::size_t>(slot)]) - pv,
                                     s.pos(fans.prev[static_cast<std::size_t>(slot)]) - pv, ray, across, slot == begin);
            if (holding != 1) return;
        }
        c.flat = 1;
    });
    // Few cones are not flat: their neighbours are marked from them, so that
    // most collapses learn that they own no corner from their two ends.
    parallel_for(threads, nv, [&](i64 vi) {
        const auto v = static_cast<std::size_t>(vi);
        if (cones[v].flat) return;
        for (i32 j = 0, m = fans.nn(static_cast<i32>(vi)); j < m; ++j)
            std::atomic_ref<u16>(cones[static_cast<std::size_t>(fans.nbr(static_cast<i32>(vi), j))].beside_sharp)
                .store(1, std::memory_order_relaxed);
    });
}

// Distance from p to triangle (a, b, c) (Ericson, Real-Time Collision
// Detection, 5.1.5). Inlined into the sample loops, which call it most of
// all (13 % of a job's profile): 2 % off a job on the VM.
[[gnu::always_inline]] inline double point_triangle_distance(Vec p, Vec a, Vec b, Vec c) {
    const Vec ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return norm(ap);
    const Vec bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return norm(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return norm(p - (a + (d1 / (d1 - d3)) * ab));
    const Vec cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return norm(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return norm(p - (a + (d2 / (d2 - d6)) * ac));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return norm(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
    const double denom = va + vb + vc;
    if (!(denom > 0)) return std::min(norm(ap), std::min(norm(bp), norm(cp)));
    const double v = vb / denom, w = vc / denom;
    return norm(p - (a + v * ab + w * ac));
}

// ---------------------------------------------------------------------------
// Step 4: classify every edge: which collapse branch applies and the
// operation's priority, both from lengths and valences only. Φ, the position
// and the legality tests wait for the selection (step 5) and run only for the
// operations it reaches unblocked: in a round about one edge in twenty
// collapses and most are blocked by a chosen neighbour, so computing Φ for
// all of them was most of a round (on the paper surface at N = 100, Φ is now
// computed 2.8 M times instead of 17 M). The priority ranks shorter edges,
// relative to the other edges of their faces, first: unlike Φ it is known
// before Φ is, and it gave 10-13 % fewer triangles and a larger mean smallest
// angle (33.8° against 29.6°) than ranking by Φ, at a smaller Hausdorff
// distance on the paper surface and the same error bound. Flips, the lowest
// class, are proposed after all collapses are chosen, for the edges they left
// clear. Edges whose answer cannot have changed since they last had no legal
// operation are skipped (see Quiet below).
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
//    produce where the surface passes through a mesh node), and the two
//    shorter edges of a degenerate face (a cap): collapsed whatever Φ is,
//    with first priority.
//  - every other collapse needs Φ > Φ*; among them the shorter edge (against
//    the mean of its faces' other edges) goes first.
//  - valence-3 vertices: an interior free vertex with three neighbours is
//    removed (collapsed into its neighbour of smallest key; the three faces
//    become one), whatever Φ is; the legality and error tests still apply.
//  - flips: an interior edge that is not collapsed is flipped when its faces
//    are nearly coplanar and the flip raises their smaller minimum angle by
//    20 % — the long edge between two narrow triangles. Lowest priority.
//
// Legality (all must hold, else the operation is dropped):
//  - link condition: the common neighbours of u and w are exactly the
//    opposite vertices (two inside, one on the border);
//  - no new edge joins two locked vertices (a piece across an interface may
//    create the same edge, and seaming would give it 3 or 4 triangles);
//  - every vertex keeps at least 3 neighbours (2 on the border), so no
//    component drops below a tetrahedron; a border loop keeps 3 edges;
//  - every surviving face of the two leaves keeps its orientation (normal
//    turns by at most max_normal_turn, or stays on the side of the leaf's
//    mean normal where it had none) and keeps a non-zero area; the smallest
//    angle over the new faces is at least min(min_angle, the smallest angle
//    over the old faces), so collapses that remove a degenerate face stay
//    possible but none makes the worst angle of its region worse. Faces
//    that do not move (around a survivor that stays put) are not judged,
//    and a valence-3 removal's one new face has no turn test (see
//    legal_collapse);
//  - no new contact: faces that share a corner meet nowhere else, among the
//    new faces and between them and the faces around their outer corners
//    (see Cones); contacts the replaced faces had already do not count;
//  - error: every vertex of this call's input is kept as a sample, frozen
//    where it was and owned by one current face (see Samples). A collapse
//    re-measures the samples of all faces of both leaves against the new
//    faces: each must lie within max_error of one of them (less its own
//    bound from earlier calls), and goes to it. So the distance of every
//    input vertex to the reduced surface stays within max_error, exactly
//    and with no accumulation over rounds (an earlier design added each
//    collapse's displacement to the faces' bounds: it stopped the paper
//    surface at N = 100 at 3.6x fewer triangles where this reaches 14x, for
//    a measured Hausdorff distance of 0.21 h against 0.43 h, both within
//    0.5 h). Between input vertices the surfaces may part further: the
//    sampled symmetric Hausdorff distance was 1.0-1.7x max_error at 0.25 h
//    on the built-in fields, 2.4x at 0.1 h (results/reduce/bound_sweep.md).
//    The new faces get the largest sample bound of the fan (plus, on the
//    border, the old bounds and the border polyline's departure), the bound
//    that the next call (a seam's reduction) starts from.

// kPending: a collapse whose branch and priority are known but whose Φ and
// position wait until the selection reaches it (Evaluator::classify).
// kQuiet: skipped, its answer unchanged since a round that found none.
enum OpKind : u8 { kNone = 0, kCollapse = 1, kFlip = 2, kPending = 3, kQuiet = 4 };

struct Ops {
    std::vector<u8> kind;
    std::vector<u32> priority;
    std::vector<float> px, py, pz, err;
    std::vector<i32> survivor;
    void resize(std::size_t n) {
        kind.resize(n);
        priority.resize(n);
        px.resize(n);
        py.resize(n);
        pz.resize(n);
        err.resize(n);
        survivor.resize(n);
    }
};

struct Params {
    double phi;
    double q_min;     // sin(min_angle)
    double cos_turn;  // cos(max_normal_turn)
    double cos_flip;  // cos(flip_max_dihedral)
    double max_error; // <= 0: none
    double short_ratio;
    bool flips;
};

// A priority is 32 bits: class, score, then a few bits of a hash that
// varies with the round (equal priorities fall to the vertex keys, see
// Selector::beats). 32 rather than 64 bits halve the radix sort's passes,
// which streamed more memory per round than any other step.
constexpr int kPriorityScoreBits = 22;
constexpr int kPriorityHashBits = 8;
constexpr u32 kClassFlip = 0, kClassCollapse = 1, kClassValence3 = 2, kClassShort = 3;

u32 make_priority(u32 cls, double score, u64 hash) {
    score = std::clamp(score, 0.0, 1.0);
    const u32 scale = (u32{1} << kPriorityScoreBits) - 1;
    const auto s = static_cast<u32>(score * static_cast<double>(scale));
    return (cls << (kPriorityScoreBits + kPriorityHashBits)) | (s << kPriorityHashBits) |
           static_cast<u32>(hash & ((u64{1} << kPriorityHashBits) - 1));
}

u32 priority_class(u32 priority) { return priority >> (kPriorityScoreBits + kPriorityHashBits); }

// The slots, in the fans of both ends, of the faces of an edge.
struct EdgeSlots {
    i32 u, w, f1, f2;
    i32 ou, ku, uf1, uf2; // u's fan offset, size, slot of f1 / f2 (-1: none)
    i32 ow, kw, wf1, wf2; // wf1, wf2: -1 unless slots() was asked for them
    i32 c, d;             // opposite vertices (-1: none)
};

class Evaluator {
public:
    // samples: null when there is no error bound.
    Evaluator(const Surface& s, const Fans& fans, const Edges& edges, const std::vector<FaceGeometry>& geometry,
              const std::vector<Cone>& cones, const Samples* samples, const Params& params, int round)
        : s_(s), fans_(fans), edges_(edges), geo_(geometry), cones_(cones), samples_(samples), p_(params),
          round_(round) {}

    // with_w_slots: also find f1 and f2 in w's fan (a scan of its ring),
    // which only Φ and the legality tests read.
    EdgeSlots slots(i32 e, bool with_w_slots = true) const {
        const auto i = static_cast<std::size_t>(e);
        EdgeSlots r;
        r.u = edges_.v0[i];
        r.w = edges_.v1[i];
        const EdgeFaces f = edges_.faces(fans_, e);
        r.f1 = f.f1;
        r.f2 = f.f2;
        r.c = f.c;
        r.d = f.d;
        r.ou = fans_.off[static_cast<std::size_t>(r.u)];
        r.ku = fans_.k(r.u);
        r.ow = fans_.off[static_cast<std::size_t>(r.w)];
        r.kw = fans_.k(r.w);
        const i32 j = edges_.s0[i];
        r.uf1 = j < r.ku ? j : -1;
        r.uf2 = j > 0 ? j - 1 : (border(r.u) ? -1 : r.ku - 1);
        r.wf1 = r.wf2 = -1;
        if (!with_w_slots) return r;
        // m: where u sits in w's ring (neighbours are distinct in a manifold
        // fan, so the first match is the one).
        i32 m = 0;
        for (const i32 n = fans_.nn(r.w); m < n && fans_.nbr(r.w, m) != r.u; ++m) {
        }
        r.wf2 = m < r.kw ? m : -1;
        r.wf1 = m > 0 ? m - 1 : (border(r.w) ? -1 : r.kw - 1);
        return r;
    }

    // The cheap part of a collapse's proposal: its branch and priority
    // (kPending, or a complete kCollapse for a valence-3 vertex), or kNone
    // when no collapse is possible (a flip may still be, see propose_flip).
    void classify(i32 e, Ops& ops) const {
        const auto i = static_cast<std::size_t>(e);
        ops.kind[i] = kNone;
        classify_collapse(slots(e, false), hash(e), ops, i);
    }

    // Whether collapse e is possible: a kPending one gets its Φ and position
    // first (kNone when Φ is not above Φ*), then the legality tests run.
    // owner: where to move the samples of a legal collapse (its caller
    // chooses every operation this finds legal); null when there are no
    // samples.
    // free_corners(owned, n): whether the corners the collapse would own
    // are its to take (n = -1: too many); asked only of a legal collapse,
    // which is blocked when they are not, its samples left where they were.
    template <class FreeCorners>
    Verdict legal(i32 e, Ops& ops, std::vector<i32>* owner, const FreeCorners& free_corners) const {
        const auto i = static_cast<std::size_t>(e);
        if (ops.kind[i] == kFlip) return Verdict::kLegal; // fully tested in propose_flip
        const EdgeSlots r = slots(e);
        if (ops.kind[i] == kPending && !place_collapse(r, ops, i)) return Verdict::kIllegal;
        bool blocked = false;
        if (legal_collapse(r, ops, i, owner, [&](bool border_edge) {
                i32 owned[kMaxOwned];
                const int n = owned_corners(fans_, cones_, r.u, r.w, border_edge, owned);
                blocked = !free_corners(owned, n);
                return !blocked;
            }))
            return Verdict::kLegal;
        return blocked ? Verdict::kBlocked : Verdict::kIllegal;
    }

    // A flip for an interior edge with no collapse: kFlip when it gains
    // and passes every test (it needs no test at selection).
    bool propose_flip(i32 e, Ops& ops) const {
        const EdgeSlots r = slots(e, false);
        return p_.flips && r.f1 >= 0 && r.f2 >= 0 && propose_flip(r, hash(e), ops, static_cast<std::size_t>(e));
    }

private:
    // Breaks ties in priority; changes with the round so that an edge that
    // loses a tie once does not lose it every round.
    u64 hash(i32 e) const {
        return mix64(s_.key[static_cast<std::size_t>(edges_.v0[static_cast<std::size_t>(e)])] * 0x9e3779b97f4a7c15ULL ^
                     mix64(s_.key[static_cast<std::size_t>(edges_.v1[static_cast<std::size_t>(e)])] +
                           static_cast<u64>(round_)));
    }

    bool border(i32 v) const { return fans_.border[static_cast<std::size_t>(v)] != 0; }
    const FaceGeometry& geo(i32 t) const { return geo_[static_cast<std::size_t>(t)]; }
    i32 face(i32 slot) const { return fans_.face[static_cast<std::size_t>(slot)]; }

    // Φ_j of the leaf of a vertex (fan offset o, size k) for an interior edge
    // whose faces sit in slots s1 and s2: traversal from s1 in direction dir
    // (away from s2); on a border vertex the faces beyond s2 join part 2.
    double leaf_phi(i32 o, i32 k, bool path, i32 s1, i32 s2, int dir, Vec n1, Vec n2) const {
        double phi = 1.0;
        bool part1 = true;
        i32 j = s1;
        for (i32 step = 0; step < k; ++step) {
            if (j == s2) break;
            const FaceGeometry& g = geo(face(o + j));
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
                const FaceGeometry& g = geo(face(o + j));
                if (g.valid()) phi = std::min(phi, dot(g.n(), n2));
            }
        return phi;
    }

    // Φ_j of a border edge's end: its leaf against the edge's one face.
    double leaf_phi_border(i32 o, i32 k, Vec n) const {
        double phi = 1.0;
        for (i32 j = 0; j < k; ++j) {
            const FaceGeometry& g = geo(face(o + j));
            if (g.valid()) phi = std::min(phi, dot(n, g.n()));
        }
        return phi;
    }

    // The other border neighbour of border vertex v on border edge (v, x).
    i32 border_other(i32 v, i32 x) const {
        const i32 first = fans_.nbr(v, 0), last = fans_.nbr(v, fans_.k(v));
        return first == x ? last : first;
    }

    // Which ends are pinned (kept where they are): a locked vertex, or a
    // border vertex on an interior edge. False when the edge cannot collapse
    // at all (an interior edge between two border vertices would pinch the
    // surface; two pinned ends cannot meet).
    bool pins(const EdgeSlots& r, bool& pin_u, bool& pin_w) const {
        const bool border_edge = r.f1 < 0 || r.f2 < 0;
        const bool bu = border(r.u), bw = border(r.w);
        if (!border_edge && bu && bw) return false;
        pin_u = s_.locked(r.u) || (!border_edge && bu);
        pin_w = s_.locked(r.w) || (!border_edge && bw);
        return !(pin_u && pin_w);
    }

    // The edge's length and the mean length of the other edges of its faces
    // (0 when it has no opposite vertex).
    void lengths(const EdgeSlots& r, double& len, double& local) const {
        const Vec pu = s_.pos(r.u), pw = s_.pos(r.w);
        len = norm(pw - pu);
        local = 0.0;
        int local_n = 0;
        for (const i32 o : {r.c, r.d})
            if (o >= 0) {
                const Vec po = s_.pos(o);
                local += norm(po - pu) + norm(po - pw);
                local_n += 2;
            }
        local = local_n ? local / local_n : 0.0;
    }

    // A complete collapse: the survivor keep, moved to p.
    static bool set_collapse(Ops& ops, std::size_t i, Vec p, i32 keep) {
        ops.kind[i] = kCollapse;
        ops.px[i] = static_cast<float>(p.x);
        ops.py[i] = static_cast<float>(p.y);
        ops.pz[i] = static_cast<float>(p.z);
        ops.survivor[i] = keep;
        return true;
    }

    bool classify_collapse(const EdgeSlots& r, u64 hash, Ops& ops, std::size_t i) const {
        const i32 u = r.u, w = r.w;
        bool pin_u = false, pin_w = false;
        if (!pins(r, pin_u, pin_w)) return false;

        // Valence-3 branch: complete here, its position is the survivor's.
        for (const i32 mover : {w, u}) {
            const i32 keep = mover == w ? u : w;
            if (border(mover) || s_.locked(mover) || fans_.k(mover) != 3) continue;
            i32 smallest = fans_.nbr(mover, 0);
            for (i32 j = 1; j < 3; ++j) smallest = std::min(smallest, fans_.nbr(mover, j));
            if (smallest != keep) continue;
            ops.priority[i] = make_priority(kClassValence3, 1.0, hash);
            return set_collapse(ops, i, s_.pos(keep), keep);
        }

        double len, local;
        lengths(r, len, local);
        bool short_edge = len == 0.0 || len <= p_.short_ratio * local;
        // A degenerate face (a cap: one corner on the opposite side) goes by
        // collapsing one of its two shorter edges.
        for (const auto& [f, o] : {std::pair{r.f1, r.c}, std::pair{r.f2, r.d}})
            if (!short_edge && f >= 0 && !geo(f).valid()) {
                const Vec po = s_.pos(o), pu = s_.pos(u), pw = s_.pos(w);
                short_edge = len < std::max(norm(po - pu), norm(po - pw));
            }
        // Shorter edges, relative to their faces' other edges, go first.
        ops.kind[i] = kPending;
        ops.priority[i] = short_edge ? make_priority(kClassShort, local > 0 ? 1.0 - len / local : 1.0, hash)
                                     : make_priority(kClassCollapse, local > 0 ? local / (len + local) : 1.0, hash);
        return true;
    }

    // Φ and the position of a kPending collapse. A short edge collapses
    // whatever Φ is; any other needs Φ > Φ* (else kind becomes kNone).
    bool place_collapse(const EdgeSlots& r, Ops& ops, std::size_t i) const {
        const i32 u = r.u, w = r.w;
        const bool border_edge = r.f1 < 0 || r.f2 < 0;
        const bool bu = border(u), bw = border(w);
        bool pin_u = false, pin_w = false;
        pins(r, pin_u, pin_w);
        const bool short_edge = priority_class(ops.priority[i]) == kClassShort;
        const Vec pu = s_.pos(u), pw = s_.pos(w);
        const double len = norm(pw - pu);

        double phi_u = -1.0, phi_w = -1.0;
        if (border_edge) {
            const i32 f = r.f1 >= 0 ? r.f1 : r.f2;
            if (geo(f).valid()) {
                phi_u = leaf_phi_border(r.ou, r.ku, geo(f).n());
                phi_w = leaf_phi_border(r.ow, r.kw, geo(f).n());
            }
            // 1D criterion along the border polyline.
            if (len > 0) {
                const Vec dir = (1.0 / len) * (pw - pu);
                const Vec du = pu - s_.pos(border_other(u, w)), dw = s_.pos(border_other(w, u)) - pw;
                const double lu = norm(du), lw = norm(dw);
                if (lu > 0) phi_u = std::min(phi_u, dot(du, dir) / lu);
                if (lw > 0) phi_w = std::min(phi_w, dot(dw, dir) / lw);
            }
        } else {
            const bool v1 = geo(r.f1).valid(), v2 = geo(r.f2).valid();
            if (v1 || v2) {
                const Vec n1 = v1 ? geo(r.f1).n() : geo(r.f2).n();
                const Vec n2 = v2 ? geo(r.f2).n() : n1;
                // In u's fan f2 precedes f1: traverse forward; in w's, backward.
                if (!pin_u) phi_u = leaf_phi(r.ou, r.ku, bu, r.uf1, r.uf2, +1, n1, n2);
                if (!pin_w) phi_w = leaf_phi(r.ow, r.kw, bw, r.wf1, r.wf2, -1, n1, n2);
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
            keep = t >= 0.5 ? u : w;
            p = len == 0.0 ? pu : t * pu + (1.0 - t) * pw;
        } else {
            // A leaf folds back (a corner, a spike): Φ gives no position. A
            // short edge still collapses, into the folded end so the corner
            // stays, or to its midpoint when both ends fold (a tiny move).
            phi = std::min(phi_u, phi_w);
            keep = phi_u <= 0 || phi_w > 0 ? u : w;
            p = phi_u <= 0 && phi_w <= 0 ? (len == 0.0 ? pu : 0.5 * (pu + pw)) : s_.pos(keep);
        }
        if (!short_edge && !(phi > p_.phi)) {
            ops.kind[i] = kNone;
            return false;
        }
        return set_collapse(ops, i, p, keep);
    }

    template <class Owns>
    bool legal_collapse(const EdgeSlots& r, Ops& ops, std::size_t i, std::vector<i32>* owner, const Owns& owns) const {
        const i32 u = r.u, w = r.w, c = r.c, d = r.d;
        const bool border_edge = r.f1 < 0 || r.f2 < 0;
        // Link condition.
        const i32 nu = fans_.nn(u), nw = fans_.nn(w);
        i32 common = 0;
        for (i32 a = 0; a < nu; ++a) {
            const i32 x = fans_.nbr(u, a);
            if (x == w) continue;
            for (i32 b = 0; b < nw; ++b)
                if (fans_.nbr(w, b) == x) {
                    if (x != c && x != d) return false;
                    ++common;
                }
        }
        if (common != (border_edge ? 1 : 2)) return false;
        // No new edge between two locked vertices: the piece across the
        // interface (or, after a seam, the rest of the piece around the
        // reduced region) may hold the same edge, and once merged by key it
        // would have three or four triangles. A collapse joins the survivor
        // to the other end's neighbours; only a locked survivor can do harm.
        const i32 keep = ops.survivor[i], gone = keep == u ? w : u;
        if (s_.locked(keep))
            for (i32 j = 0, n = fans_.nn(gone); j < n; ++j) {
                const i32 x = fans_.nbr(gone, j);
                if (x != keep && x != c && x != d && s_.locked(x)) return false;
            }
        // Valences, border loops.
        if (nu + nw - 2 - common < ((border(u) || border(w)) ? 2 : 3)) return false;
        for (const i32 o : {c, d})
            if (o >= 0 && fans_.nn(o) - 1 < (border(o) ? 2 : 3)) return false;
        const Vec p{ops.px[i], ops.py[i], ops.pz[i]};
        const Vec pu = s_.pos(u), pw = s_.pos(w);
        double increment = 0.0;
        if (border_edge) {
            const i32 up = border_other(u, w), wn = border_other(w, u);
            if (up == wn) return false; // a border loop of 3 edges
            const Vec a = s_.pos(up), b = s_.pos(wn);
            for (const Vec q : {pu, pw})
                increment = std::max(increment,
                                     std::min(point_segment_distance(q, a, p), point_segment_distance(q, p, b)));
        }

        // Old faces of both leaves: error bound, worst quality, mean normal.
        double err_old = 0.0, q_worst = 1.0;
        Vec nsum{0, 0, 0};
        for_each_leaf_face(r, [&](i32 slot, bool) {
            const i32 t = face(slot);
            const FaceGeometry& g = geo(t);
            err_old = std::max(err_old, static_cast<double>(g.err));
            q_worst = std::min(q_worst, static_cast<double>(g.q));
            if (g.valid()) nsum = nsum + g.n();
        });
        const double q_floor = std::min(p_.q_min, q_worst);
        // A valence-3 vertex's three faces become the one across their outer
        // corners, whose area vector is the sum of theirs (an identity, for
        // any position of the vertex): on average it turns from none of
        // them, however far it turns from the one whose place it takes. That
        // turn measured the height of the vertex above the new face, which is
        // the error test's to judge, and it kept 38 valence-3 vertices in
        // tiny clusters where the surface passes near a mesh node, each
        // blocking the collapse of a needle's short edge (the link condition
        // fails through it) in the N = 100 paper surface.
        const bool removes_valence3 = priority_class(ops.priority[i]) == kClassValence3;
        // New faces: (p, next, prev) for every other face of both leaves.
        NewFan fan;
        fan.p = p;
        int faces = 0;
        bool spoiled = false;
        for_each_leaf_face(r, [&](i32 slot, bool removed) {
            if (removed || spoiled) return;
            const i32 ia = fans_.next[static_cast<std::size_t>(slot)];
            const i32 ib = fans_.prev[static_cast<std::size_t>(slot)];
            __builtin_prefetch(&cones_[static_cast<std::size_t>(ia)]); // read by clear_of_neighbours
            const Vec a = s_.pos(ia), b = s_.pos(ib);
            Vec n;
            const double q_new = quality(p, a, b, &n);
            const FaceGeometry& g = geo(face(slot));
            const i32 end = slot < r.ou + r.ku ? u : w;
            // A face of the survivor's leaf, where the survivor stays put
            // (a pinned end, a valence-3 removal), does not change and is not
            // judged. Judged, it failed the quality floor whenever it was its
            // region's worst face: its quality, recomputed from its corners
            // in another order, came out a few units in the last place below
            // the stored one. That refused most collapses next to a needle,
            // and the needle stayed (304 triangles with an angle below 1° in
            // the N = 100 paper surface's reduction, 49 without it).
            const Vec pe = s_.pos(end);
            const bool moves = p.x != pe.x || p.y != pe.y || p.z != pe.z;
            // No face with a normal of its own (valid) becomes degenerate or
            // turns; one whose normal is rounding's may become degenerate,
            // its own short edge will remove it, and must face the leaves'
            // way only once the collapse gives it a normal of its own.
            spoiled = moves && (q_new < q_floor || (!(q_new > 0) && g.valid()) ||
                                (g.valid() ? q_new > 0 && !removes_valence3 && dot(n, g.n()) < p_.cos_turn
                                           : resolved(p, a, b) && dot(n, nsum) < 0));
            if (faces < NewFan::kMax) {
                fan.a[faces] = a;
                fan.b[faces] = b;
                fan.n[faces] = n;
                fan.ia[faces] = ia;
                fan.ib[faces] = ib;
                fan.end[faces] = end;
                fan.tri[faces] = face(slot);
            }
            ++faces;
        });
        if (spoiled || faces > NewFan::kMax) return false;
        fan.count = faces;
        if (!samples_) {
            if (!clear_of_neighbours(u, w, border_edge, fan) || !owns(border_edge)) return false;
            ops.err[i] = static_cast<float>(err_old + increment);
            return true;
        }
        // On the border the polyline's 1D departure adds to the bounds it
        // replaces (the samples see only the 2D one).
        double worst = border_edge ? err_old + increment : 0.0;
        if (worst > p_.max_error) return false;
        // The placements wait until every sample has found a face: a test
        // that fails half way must leave the owners as they were.
        thread_local std::vector<std::pair<i32, i32>> placed;
        placed.clear();
        if (!place_samples(r, fan, worst, [&](i32 sample, i32 t, double) {
                if (owner) placed.emplace_back(sample, t);
            }))
            return false;
        if (!clear_of_neighbours(u, w, border_edge, fan) || !owns(border_edge)) return false;
        for (const auto& [sample, t] : placed) (*owner)[static_cast<std::size_t>(sample)] = t;
        ops.err[i] = static_cast<float>(worst);
        return true;
    }

public:
    // Re-measures the samples of a chosen flip's two faces against the new
    // ones and gives each its new owner (before apply() changes anything).
    // A chosen collapse needs no such step: its legality test, run when its
    // turn came, already moved its samples.
    void move_flip_samples(i32 e, std::vector<i32>& owner) const {
        const EdgeSlots r = slots(e, false);
        double worst = 0.0;
        place_flip_samples(r, worst, [&](i32 sample, i32 t, double) { owner[static_cast<std::size_t>(sample)] = t; });
    }

private:
    // Calls f(slot, removed) for every face of both leaves of a collapse,
    // once each: u's fan, then w's without f1 and f2 (already seen from u).
    // removed: the face is f1 or f2, which the collapse deletes; every other
    // face becomes a new face in this order.
    template <class F>
    void for_each_leaf_face(const EdgeSlots& r, const F& f) const {
        for (i32 j = 0; j < r.ku; ++j) f(r.ou + j, j == r.uf1 || j == r.uf2);
        for (i32 j = 0; j < r.kw; ++j)
            if (j != r.wf1 && j != r.wf2) f(r.ow + j, false);
    }

    // The faces a collapse makes: (p, a[f], b[f]), which replace triangle
    // tri[f] (the same index: apply() rewrites triangles in place).
    struct NewFan {
        static constexpr int kMax = 96;
        Vec p, a[kMax], b[kMax], n[kMax]; // n: unit normal, zero when degenerate
        i32 ia[kMax], ib[kMax], tri[kMax];
        i32 end[kMax]; // the end, u or w, whose place p takes in this face
        int count = 0;
    };

    // A triangle for the contact tests: corners (vertex, position), unit
    // normal (zero when degenerate).
    struct Corners {
        i32 id[3];
        Vec at[3];
        Vec n;
    };

    // Whether two faces that share a corner or an edge (by vertex, or by
    // position where a mesh node made two vertices coincide) meet anywhere
    // else. Faces with nothing in common, or degenerate ones, are not judged.
    static bool touch(const Corners& f, const Corners& g) {
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
    static Corners new_face(const NewFan& fan, int f) {
        return {{-1, fan.ia[f], fan.ib[f]}, {fan.p, fan.a[f], fan.b[f]}, fan.n[f]};
    }
    Corners old_face(const NewFan& fan, int f) const {
        Corners c{{fan.end[f], fan.ia[f], fan.ib[f]}, {s_.pos(fan.end[f]), fan.a[f], fan.b[f]}, {0, 0, 0}};
        quality(c.at[0], c.at[1], c.at[2], &c.n);
        return c;
    }

    // Whether the faces a collapse of (u, w) makes come into contact with
    // no face that shares a corner with them, other than along that corner
    // or edge: the new ones among themselves (the fan around p), and the
    // faces around their outer corners (by cones where they settle it, see
    // Cones). Where a fan is tested face by face, a contact the replaced
    // faces had already is no new one: extraction leaves faces that touch
    // along a line where the surface passes through a mesh node, and
    // cleaning those up must stay possible. Faces that share no corner are
    // not tested.
    bool clear_of_neighbours(i32 u, i32 w, bool border_edge, const NewFan& fan) const {
        if (!fan_at_p_embedded(fan))
            for (int f = 0; f < fan.count; ++f) {
                if (norm2(fan.n[f]) == 0) continue;
                for (int g = f + 1; g < fan.count; ++g)
                    if (!apart(fan.p, fan.n[f], fan.a[g], fan.b[g]) && touch(new_face(fan, f), new_face(fan, g)) &&
                        !touch(old_face(fan, f), old_face(fan, g)))
                        return false;
            }
        // Each outer corner v: a[f] of one new face and b[g] of another (on
        // the border, the ends of the chain have one). Reading only v's cone
        // settles it; the ring is read where the cone does not.
        // The corners tested face by face are those the collapse owns for the
        // round (owned_corners): no other operation of the round changes
        // their fans. Elsewhere a new face outside its corner's cone
        // is refused (rare: 11 corners in the reduction of the N = 100 paper
        // surface), as the cone argument needs every operation at that
        // corner to keep to it.
        const i32 moved_a = border_edge ? border_other(u, w) : -1, moved_b = border_edge ? border_other(w, u) : -1;
        for (int f = 0; f < fan.count; ++f)
            for (const i32 v : {fan.ia[f], fan.ib[f]}) {
                if (v == moved_a || v == moved_b || !cones_[static_cast<std::size_t>(v)].flat) {
                    if (!ring_clear(u, w, fan, v)) return false;
                } else if (!inside_cone(v, fan.n[f])) {
                    return false;
                }
            }
        return true;
    }

    // Whether new face normal n lies in the cone of v's fan (see Cones):
    // then the faces replaced at v are replaced by faces on the same side,
    // and v's fan stays embedded.
    bool inside_cone(i32 v, Vec n) const {
        const Cone& c = cones_[static_cast<std::size_t>(v)];
        return c.flat && dot(n, {c.x, c.y, c.z}) > kConeMargin;
    }

    // Whether the new faces around p meet only along their shared edges:
    // seen along the mean of their normals, each turns the same way about p
    // and together they turn once around it (less, when p is on the border).
    // That is counted on a ray along the first side of the first face (of
    // the chain, on the border): the half-open angles [a, b) of the faces
    // must hold it once. A closed fan turning k times holds every ray k
    // times; an open one turning more than once holds its first side twice.
    static bool fan_at_p_embedded(const NewFan& fan) {
        Vec m{0, 0, 0};
        for (int f = 0; f < fan.count; ++f) m = m + fan.n[f];
        const double len = norm(m);
        if (!(len > 0)) return false;
        m = (1.0 / len) * m;
        for (int f = 0; f < fan.count; ++f)
            if (!(dot(fan.n[f], m) > kConeMargin)) return false;
        int first = 0; // on the border: the face whose first side no face ends on
        bool open = false;
        for (int f = 0; f < fan.count && !open; ++f) {
            bool follows = false;
            for (int g = 0; g < fan.count && !follows; ++g) follows = fan.ib[g] == fan.ia[f];
            if (!follows) first = f, open = true;
        }
        Vec ray = fan.a[first] - fan.p;
        ray = ray - dot(ray, m) * m;
        const Vec across = cross(m, ray);
        // Each side is measured the same way in both faces that hold it, so
        // that rounding cannot count the first side twice or not at all; on
        // the border, the first side is the first face's own.
        int holding = 0;
        for (int f = 0; f < fan.count; ++f)
            holding += holds_ray(fan.a[f] - fan.p, fan.b[f] - fan.p, ray, across, open && f == first);
        return holding == 1;
    }

    // The exact test at outer corner v, for a cone that does not settle it:
    // each face around v that the collapse leaves as it is, against each new
    // face at v.
    bool ring_clear(i32 u, i32 w, const NewFan& fan, i32 v) const {
        int at_v[2], n_at_v = 0;
        for (int f = 0; f < fan.count && n_at_v < 2; ++f)
            if (fan.ia[f] == v || fan.ib[f] == v) at_v[n_at_v++] = f;
        const Vec pv = s_.pos(v);
        const i32 begin = fans_.off[static_cast<std::size_t>(v)], end = fans_.off[static_cast<std::size_t>(v) + 1];
        for (i32 slot = begin; slot < end; ++slot) {
            const i32 x = fans_.next[static_cast<std::size_t>(slot)];
            const i32 y = fans_.prev[static_cast<std::size_t>(slot)];
            if (x == u || x == w || y == u || y == w) continue; // a face the collapse replaces
            const Vec px = s_.pos(x), py = s_.pos(y);
            for (int j = 0; j < n_at_v; ++j) {
                const int h = at_v[j];
                if (norm2(fan.n[h]) == 0) continue;
                const i32 o = fan.ia[h] == v ? fan.ib[h] : fan.ia[h];
                const Vec po = fan.ia[h] == v ? fan.b[h] : fan.a[h];
                bool overlap;
                if (x == o || y == o) {
                    // Across the edge (v, o): only a face folded flat onto h.
                    const Vec third = x == o ? py : px;
                    overlap = overlap_at_edge(pv, po, fan.p, fan.n[h], third) &&
                              !overlap_at_edge(pv, po, s_.pos(fan.end[h]), old_face(fan, h).n, third);
                } else {
                    if (apart(pv, fan.n[h], px, py)) continue;
                    Vec ng;
                    if (!(quality(pv, px, py, &ng) > 0)) continue;
                    overlap = overlap_at_corner(pv, fan.p, po, fan.n[h], px, py, ng) &&
                              !touch(old_face(fan, h), Corners{{v, x, y}, {pv, px, py}, ng});
                }
                if (overlap) return false;
            }
        }
        return true;
    }

    // Whether x and y lie clearly on one side of the plane through corner a
    // of normal n: then a face (a, x, y) meets the face of that plane at a
    // only (overlap_at_corner's first test, which settles most pairs).
    static bool apart(Vec a, Vec n, Vec x, Vec y) {
        const Vec ex = x - a, ey = y - a;
        const double sx = dot(ex, n), sy = dot(ey, n);
        if (!((sx > 0 && sy > 0) || (sx < 0 && sy < 0))) return false;
        const double flat2 = 1e-12 * std::max(norm2(ex), norm2(ey));
        return sx * sx > flat2 || sy * sy > flat2;
    }

    // A sample's distance to triangle (a, b, c): its point's, or the largest
    // of its corners' (see Samples).
    [[gnu::always_inline]] double sample_distance(i32 sample, Vec a, Vec b, Vec c) const {
        const Samples::Point* p = samples_->point_of(static_cast<std::size_t>(sample));
        double d = point_triangle_distance({p->x, p->y, p->z}, a, b, c);
        if (const Samples::Point* q = samples_->far_corners(static_cast<std::size_t>(sample)))
            for (int k = 0; k < 2; ++k) d = std::max(d, point_triangle_distance({q[k].x, q[k].y, q[k].z}, a, b, c));
        return d;
    }

    // Places every sample of the old faces of both leaves of a collapse on a
    // new face: on the face that replaces its own when that is within its
    // room (the common case: a face that moves a little keeps its samples),
    // else on the nearest. Calls visit(sample, triangle) for each and raises
    // worst to each sample's bound; false when some sample has no new face
    // within max_error.
    template <class Visit>
    bool place_samples(const EdgeSlots& r, const NewFan& fan, double& worst, const Visit& visit) const {
        int replacement = 0;
        bool placed = true;
        for_each_leaf_face(r, [&](i32 slot, bool removed) {
            const auto t = static_cast<std::size_t>(face(slot));
            const int own = removed ? -1 : replacement++;
            const FaceGeometry& g = geo_[t];
            for (i32 sample = g.samples_begin; sample < g.samples_end && placed; ++sample) {
                const Samples::Point* sp = samples_->point_of(static_cast<std::size_t>(sample));
                const double base = sp->base;
                int at = -1;
                double d = 0.0;
                if (own >= 0) {
                    d = sample_distance(sample, fan.p, fan.a[own], fan.b[own]);
                    if (base + d <= p_.max_error) at = own;
                }
                if (at < 0) {
                    d = std::numeric_limits<double>::infinity();
                    for (int f = 0; f < fan.count; ++f) {
                        const double df = sample_distance(sample, fan.p, fan.a[f], fan.b[f]);
                        if (df < d) {
                            d = df;
                            at = f;
                        }
                    }
                    if (!(base + d <= p_.max_error)) {
                        placed = false;
                        return;
                    }
                }
                worst = std::max(worst, base + d);
                visit(sample, fan.tri[at], base + d);
            }
        });
        return placed;
    }

    // The same for a flip: f1 = (u, w, c), f2 = (w, u, d) become
    // (c, u, d) in f1's place and (d, w, c) in f2's; each sample of either
    // goes to the nearer of the two.
    template <class Visit>
    bool place_flip_samples(const EdgeSlots& r, double& worst, const Visit& visit) const {
        const Vec pu = s_.pos(r.u), pw = s_.pos(r.w), pc = s_.pos(r.c), pd = s_.pos(r.d);
        for (const i32 t : {r.f1, r.f2})
            for (i32 sample = geo(t).samples_begin; sample < geo(t).samples_end; ++sample) {
                const Samples::Point* sp = samples_->point_of(static_cast<std::size_t>(sample));
                const double d1 = sample_distance(sample, pc, pu, pd), d2 = sample_distance(sample, pd, pw, pc);
                const double bound = sp->base + std::min(d1, d2);
                if (!(bound <= p_.max_error)) return false;
                worst = std::max(worst, bound);
                visit(sample, d1 <= d2 ? r.f1 : r.f2, bound);
            }
        return true;
    }

    bool propose_flip(const EdgeSlots& r, u64 hash, Ops& ops, std::size_t i) const {
        const i32 u = r.u, w = r.w, c = r.c, d = r.d;
        const FaceGeometry &g1 = geo(r.f1), &g2 = geo(r.f2);
        const double q_old = std::min(g1.q, g2.q);
        if (q_old >= 0.5 || c == d) return false; // no triangle with an angle below 30°: nothing to gain
        if (!g1.valid() && !g2.valid()) return false;
        const Vec pu = s_.pos(u), pw = s_.pos(w), pc = s_.pos(c), pd = s_.pos(d);
        // f1 = (u, w, c), f2 = (w, u, d) → g1 = (c, u, d), g2 = (d, w, c).
        Vec n1, n2;
        const double q1 = quality(pc, pu, pd, &n1), q2 = quality(pd, pw, pc, &n2);
        const double q_new = std::min(q1, q2);
        if (!(q_new > 1.2 * q_old) || q_new < std::min(p_.q_min, q_old)) return false;
        const Vec m1 = g1.valid() ? g1.n() : g2.n();
        const Vec m2 = g2.valid() ? g2.n() : m1;
        if (dot(m1, m2) < p_.cos_flip || dot(n1, n2) < p_.cos_flip) return false;
        for (const Vec m : {m1, m2})
            for (const Vec n : {n1, n2})
                if (dot(m, n) < p_.cos_flip) return false;
        if (fans_.nn(u) - 1 < (border(u) ? 2 : 3) || fans_.nn(w) - 1 < (border(w) ? 2 : 3)) return false;
        for (i32 j = 0, n = fans_.nn(c); j < n; ++j)
            if (fans_.nbr(c, j) == d) return false;
        if (s_.locked(c) && s_.locked(d)) return false; // see legal_collapse: no new locked-locked edge
        // No face pushed through its neighbours (see Cones); where a cone
        // does not settle it the flip, an improvement only, is not made.
        if (!inside_cone(u, n1) || !inside_cone(c, n1) || !inside_cone(d, n1) || !inside_cone(w, n2) ||
            !inside_cone(c, n2) || !inside_cone(d, n2))
            return false;
        // Error: the gap between the two diagonals.
        const Vec axis = cross(pw - pu, pd - pc);
        const double axis_len = norm(axis);
        if (!(axis_len > 0)) return false;
        const double gap = std::abs(dot(pc - pu, axis)) / axis_len;
        double err_new = std::max(g1.err, g2.err) + gap;
        if (samples_) {
            err_new = 0.0;
            if (!place_flip_samples(r, err_new, [](i32, i32, double) {})) return false;
        }
        ops.kind[i] = kFlip;
        ops.priority[i] = make_priority(kClassFlip, q_new - q_old, hash);
        ops.err[i] = static_cast<float>(err_new);
        return true;
    }

    const Surface& s_;
    const Fans& fans_;
    const Edges& edges_;
    const std::vector<FaceGeometry>& geo_;
    const std::vector<Cone>& cones_;
    const Samples* samples_;
    const Params& p_;
    int round_;
};

// ---------------------------------------------------------------------------
// Step 5: independent set. Operation o touches the vertex set S(o) (the two
// ends of a collapse; the ends and both opposite vertices of a flip); o and o'
// conflict when S(o') lies within path length 1 of S(o). The paper's choice
// is sequential: operations in priority order, each taken when no operation
// taken before conflicts with it and it is legal. Priorities are fixed within
// a round and legality does not depend on what else is chosen, so that set
// is a function of the round alone; ties in priority fall to the vertex keys,
// never to thread or order. Two chosen operations are at path length >= 2, so
// their leaves share no face and the tests of each stay valid whatever the
// others do; an illegal operation never blocks its neighbours. On one thread
// the choice runs as such (choose_in_order); on more, deterministic
// reservations (choose_by_reservations) make exactly the same choices with
// the tests in parallel, so the set is the same for every count.

// chosen[e]: 1 for a chosen operation. A collapse is tested only when its
// turn has come, so its test's sample placements are stored at once (the test
// never runs again before apply).
constexpr u8 kChosen = 1;

// The reservations' choice (Selector::choose_by_reservations): a window of
// at least kReservationWindowMin operations, or 1/kReservationSteps of the
// round's, so a round takes some tens of steps of three parallel loops; with
// kReservationMin operations or fewer the sweep runs on the calling thread.
constexpr std::size_t kReservationWindowMin = 512;
constexpr std::size_t kReservationSteps = 32;
constexpr i64 kReservationMin = 256;
constexpr i32 kNoReservation = std::numeric_limits<i32>::max();
// From this many operations a round's sort by priority runs on several
// threads (below it, one thread sorts in a millisecond or less).
constexpr std::size_t kParallelSortMin = std::size_t{1} << 16;

// An operation in the reservations' window: its rank in the round's order,
// the edge and its ends (read once, when it enters).
struct WindowSlot {
    i32 rank, e, u, w;
    // -1 until computed. The corners themselves are found again when
    // needed (few operations own any): stored here, they made the window
    // four times larger, and the 8-thread selection 1.4x slower.
    i32 owned_count;
};

// The selection's working arrays, kept from round to round so that no round
// pays for fresh pages (on the 2-core VM a reduction ran 5-8 % faster when
// glibc was told to keep freed memory, so page faults are not free there).
struct SelectScratch {
    std::vector<i32> claimed; // == the stamp: within path length 1 of a chosen operation
    // The sequential choice's order (a radix sort by priority).
    std::vector<u32> sort_key, sort_key_spare;
    std::vector<i32> order, order_spare;
    std::vector<std::pair<i32, i32>> ends; // the sweep's operations' ends, in its order
    std::vector<u32> histogram;
    // The reservations' choice: per vertex, the earliest rank (position in
    // `order`) of a window operation touching it; the window, and each
    // slot's state in the current step.
    std::vector<i32> reservation;
    std::vector<WindowSlot> window, waiting;
    std::vector<u8> window_state;
};

class Selector {
public:
    Selector(const Surface& s, const Fans& fans, const Edges& edges, const Ops& ops, const std::vector<Cone>& cones,
             SelectScratch& scratch)
        : s_(s), fans_(fans), edges_(edges), ops_(ops), cones_(cones), scratch_(scratch) {}

    // True when operation a ranks above operation b (b may be -1).
    bool beats(i32 a, i32 b) const {
        if (b < 0) return true;
        const u32 pa = ops_.priority[static_cast<std::size_t>(a)], pb = ops_.priority[static_cast<std::size_t>(b)];
        if (pa != pb) return pa > pb;
        const EdgeKey a0 = s_.key[static_cast<std::size_t>(edges_.v0[static_cast<std::size_t>(a)])];
        const EdgeKey b0 = s_.key[static_cast<std::size_t>(edges_.v0[static_cast<std::size_t>(b)])];
        if (a0 != b0) return a0 > b0;
        return s_.key[static_cast<std::size_t>(edges_.v1[static_cast<std::size_t>(a)])] >
               s_.key[static_cast<std::size_t>(edges_.v1[static_cast<std::size_t>(b)])];
    }

    int touched(i32 e, i32 out[4]) const {
        const auto i = static_cast<std::size_t>(e);
        out[0] = edges_.v0[i];
        out[1] = edges_.v1[i];
        if (ops_.kind[i] != kFlip) return 2;
        const EdgeFaces f = edges_.faces(fans_, e);
        out[2] = f.c;
        out[3] = f.d;
        return 4;
    }

    // candidates: the edges with an operation, ascending. Sets chosen[e] for
    // the operations chosen, refused[e] for those found illegal.
    // legal(e, free_corners) tests e and gives its Verdict, storing the
    // sample placements of one it finds legal; free_corners tells whether
    // the corners e would own are its to take (Evaluator::legal).
    template <class Legal>
    void select(int threads, const std::vector<i32>& candidates, std::vector<u8>& chosen, std::vector<u8>& refused,
                const Legal& legal) const {
        scratch_.claimed.assign(static_cast<std::size_t>(s_.vertices()), 0);
        stamp_ = 0;
        if (threads <= 1 || static_cast<i64>(candidates.size()) <= kReservationMin)
            choose_in_order(candidates, chosen, refused, legal);
        else
            choose_by_reservations(threads, candidates, chosen, refused, legal);
    }

    // After select(): stamps the closed neighbourhoods of the operations it
    // chose afresh, so that clear() tells what the round's later choices (the
    // flips) may still take.
    void claim_chosen(int threads, const std::vector<i32>& candidates, const std::vector<u8>& chosen) const {
        ++stamp_;
        parallel_for(threads, static_cast<i64>(candidates.size()), [&](i64 ci) {
            const i32 e = candidates[static_cast<std::size_t>(ci)];
            if (chosen[static_cast<std::size_t>(e)]) claim_around(e);
        });
    }

    // Collapse e's owned corners (see owned_corners); flips own none (they
    // are dropped where a cone does not decide).
    int owned_corners(i32 e, i32* out) const {
        const auto i = static_cast<std::size_t>(e);
        if (ops_.kind[i] == kFlip) return 0;
        const i32 u = edges_.v0[i], w = edges_.v1[i];
        const bool border_edge = fans_.border[static_cast<std::size_t>(u)] &&
                                 fans_.border[static_cast<std::size_t>(w)] && edges_.border(fans_, e);
        return tetiso::owned_corners(fans_, cones_, u, w, border_edge, out);
    }

    // clear() for a collapse, whose ends are known.
    bool clear_collapse(i32 u, i32 w) const {
        return scratch_.claimed[static_cast<std::size_t>(u)] != stamp_ &&
               scratch_.claimed[static_cast<std::size_t>(w)] != stamp_;
    }
    bool clear_owned(const i32* owned, int n) const {
        for (int k = 0; k < n; ++k)
            if (scratch_.claimed[static_cast<std::size_t>(owned[k])] == stamp_) return false;
        return true;
    }

    // Whether no vertex operation e touches lies within path length 1 of an
    // operation claimed under the current stamp (in the sweep: chosen
    // earlier in it; after claim_chosen(): chosen by select()).
    bool clear(i32 e) const {
        i32 vs[4];
        const int n = touched(e, vs);
        for (int i = 0; i < n; ++i)
            if (scratch_.claimed[static_cast<std::size_t>(vs[i])] == stamp_) return false;
        return true;
    }

    // The flips, the lowest class, after every collapse: the same sweep in
    // priority order (flips are tested when proposed, and few).
    void choose_flips(const std::vector<i32>& flips, std::vector<u8>& chosen) const {
        order_by_priority(flips);
        for (const i32 e : scratch_.order) {
            if (!clear(e)) continue;
            chosen[static_cast<std::size_t>(e)] = kChosen;
            claim_around(e);
        }
    }

private:
    // The sequential greedy choice: operations in descending priority, each
    // taken when it is clear of those taken before and legal.
    //
    // The sweep visits the surface in random order, and most operations are
    // dropped at the first look, clear() finding an end claimed: that look
    // was a chain of two cache misses (the edge's ends, then their claims)
    // that nothing could overlap. The ends are gathered first, in a loop
    // whose loads are independent, and the claims are prefetched a few
    // operations ahead.
    template <class Legal>
    void choose_in_order(const std::vector<i32>& ops, std::vector<u8>& chosen, std::vector<u8>& refused,
                         const Legal& legal) const {
        order_by_priority(ops);
        ++stamp_;
        const std::vector<i32>& order = scratch_.order;
        std::vector<std::pair<i32, i32>>& ends = scratch_.ends;
        ends.resize(order.size());
        for (std::size_t k = 0; k < order.size(); ++k) {
            const auto e = static_cast<std::size_t>(order[k]);
            ends[k] = {edges_.v0[e], edges_.v1[e]};
        }
        constexpr std::size_t kAhead = 16;
        for (std::size_t k = 0; k < order.size(); ++k) {
            if (k + kAhead < order.size()) {
                __builtin_prefetch(&scratch_.claimed[static_cast<std::size_t>(ends[k + kAhead].first)]);
                __builtin_prefetch(&scratch_.claimed[static_cast<std::size_t>(ends[k + kAhead].second)]);
            }
            const i32 e = order[k];
            if (!clear_collapse(ends[k].first, ends[k].second)) continue;
            const Verdict verdict =
                legal(e, [&](const i32* owned, int n) { return n >= 0 && clear_owned(owned, n); });
            if (verdict == Verdict::kIllegal) refused[static_cast<std::size_t>(e)] = 1;
            if (verdict != Verdict::kLegal) continue;
            chosen[static_cast<std::size_t>(e)] = kChosen;
            claim_around(e);
        }
    }

    // The same sequential greedy choice, on several threads, by deterministic
    // reservations: operations enter a window in priority order; in each step
    // every window operation not yet blocked by a chosen one reserves its two
    // ends with its rank (an atomic minimum), and one that finds no earlier
    // rank anywhere within path length 1 of its ends has no undecided earlier
    // operation in conflict with it. Its turn in the sequential order has
    // come: it is tested, and chosen if legal, exactly as the sweep would;
    // those decided in one step are pairwise clear of each other. The others
    // wait for the next step, ahead of the operations entering behind them.
    // Each operation is tested at most once, the tests run in parallel, and
    // the set is the sweep's for any count. On the 16-core device this chose
    // 1.16-1.25x faster than the passes it replaced (local maxima of the
    // priority, with a bulk test of what was left after 16 passes) at 4 and 8
    // threads on the N = 100 paper surface, and 1.13x at 4 threads on a
    // 346 K-triangle gyroid (results/speedup/README.md, session 13).
    template <class Legal>
    void choose_by_reservations(int threads, const std::vector<i32>& ops, std::vector<u8>& chosen,
                                std::vector<u8>& refused, const Legal& legal) const {
        order_by_priority(ops, threads);
        ++stamp_;
        const std::vector<i32>& order = scratch_.order;
        const std::size_t n = order.size();
        std::vector<i32>& reservation = scratch_.reservation;
        std::vector<WindowSlot>& window = scratch_.window;
        std::vector<WindowSlot>& waiting = scratch_.waiting;
        std::vector<u8>& state = scratch_.window_state;
        reservation.assign(static_cast<std::size_t>(s_.vertices()), kNoReservation);
        window.clear();
        const std::size_t width = std::max<std::size_t>(kReservationWindowMin, n / kReservationSteps);
        // kTestOnly: blocked by a corner it would own, claimed by an earlier
        // choice (or owning too many); tested only to tell refused from
        // blocked, as the sweep does.
        constexpr u8 kReserved = 1, kDecided = 2, kTaken = 4, kTestOnly = 8;
        std::size_t next = 0;
        while (next < n || !window.empty()) {
            while (window.size() < width && next < n) {
                window.push_back({static_cast<i32>(next), order[next], -1, -1, -1});
                ++next;
            }
            const i64 nw = static_cast<i64>(window.size());
            state.assign(window.size(), 0);
            parallel_for(threads, nw, [&](i64 wi) {
                WindowSlot& slot = window[static_cast<std::size_t>(wi)];
                if (slot.u < 0) {
                    slot.u = edges_.v0[static_cast<std::size_t>(slot.e)];
                    slot.w = edges_.v1[static_cast<std::size_t>(slot.e)];
                }
                if (!clear_collapse(slot.u, slot.w)) return; // blocked: decided for good
                i32 owned[kMaxOwned];
                slot.owned_count = owned_corners(slot.e, owned);
                if (slot.owned_count < 0 || !clear_owned(owned, slot.owned_count)) {
                    state[static_cast<std::size_t>(wi)] = kTestOnly;
                    return;
                }
                state[static_cast<std::size_t>(wi)] = kReserved;
                for_each_footprint(slot, [&](i32 v) {
                    std::atomic_ref<i32> held(reservation[static_cast<std::size_t>(v)]);
                    i32 current = held.load(std::memory_order_relaxed);
                    while (slot.rank < current &&
                           !held.compare_exchange_weak(current, slot.rank, std::memory_order_relaxed)) {
                    }
                });
            }, kParallelMinWindow);
            parallel_for_tests(threads, nw, [&](i64 wi) {
                u8& st = state[static_cast<std::size_t>(wi)];
                if (!st) return;
                const WindowSlot& slot = window[static_cast<std::size_t>(wi)];
                if (st == kTestOnly) {
                    if (legal(slot.e, [](const i32*, int) { return false; }) == Verdict::kIllegal)
                        refused[static_cast<std::size_t>(slot.e)] = 1;
                    return;
                }
                // Its own vertices first: a shared end is the commonest conflict.
                bool first = true;
                for_each_footprint(slot, [&](i32 v) {
                    first = first && reservation[static_cast<std::size_t>(v)] == slot.rank;
                });
                if (!first) return;
                bool nearby = false; // an earlier operation nearby is undecided
                for_each_footprint(slot, [&](i32 v) {
                    for (i32 j = 0, m = fans_.nn(v); j < m && !nearby; ++j)
                        nearby = reservation[static_cast<std::size_t>(fans_.nbr(v, j))] < slot.rank;
                });
                if (nearby) return;
                st |= kDecided;
                // Its owned corners were clear when it reserved them, and only
                // an earlier operation, all decided now, could have claimed them.
                if (legal(slot.e, [](const i32*, int) { return true; }) != Verdict::kLegal) {
                    refused[static_cast<std::size_t>(slot.e)] = 1;
                    return;
                }
                chosen[static_cast<std::size_t>(slot.e)] = kChosen;
                st |= kTaken;
            });
            parallel_for(threads, nw, [&](i64 wi) {
                const u8 st = state[static_cast<std::size_t>(wi)];
                if (!st || st == kTestOnly) return;
                const WindowSlot& slot = window[static_cast<std::size_t>(wi)];
                for_each_footprint(slot, [&](i32 v) {
                    std::atomic_ref<i32>(reservation[static_cast<std::size_t>(v)])
                        .store(kNoReservation, std::memory_order_relaxed);
                });
                if (st & kTaken) claim_around(slot.e);
            }, kParallelMinWindow);
            // The waiting keep their order, ahead of the operations still to
            // enter: the window stays sorted by rank.
            waiting.clear();
            for (std::size_t wi = 0; wi < window.size(); ++wi)
                if (state[wi] == kReserved) waiting.push_back(window[wi]);
            window.swap(waiting);
        }
    }

    // scratch_.order = ops, best first (beats() order): a stable LSD radix
    // sort of the complemented priorities, skipping the digits all share;
    // equal priorities are then put in beats() order. On one thread, digits
    // of 16 bits for large rounds (two passes) and of 8 for small ones, where
    // clearing and scanning 65,536-entry counters cost more than the sort (5 %
    // of a job's profile with 30^3-cell domains, whose late rounds have tens
    // of operations). On several, each thread counts and scatters its own
    // block of the keys, with 11-bit digits so that the per-block counters
    // stay small and their scan cheap; every stable sort by the same key gives
    // the same order, so the thread count does not show in the result. (The
    // one-thread sort was 0.24 s of the 2-thread selection of the paper
    // surface on the 2-core VM, and the reservations wait for it each round.)
    void order_by_priority(const std::vector<i32>& ops, int threads = 1) const {
        const std::size_t n = ops.size();
        if (n < (std::size_t{1} << 14)) radix_order<8>(ops, 1);
        else if (threads > 1 && n >= kParallelSortMin) radix_order<11>(ops, threads);
        else radix_order<16>(ops, 1);
        const std::vector<u32>& key = scratch_.sort_key;
        std::vector<i32>& order = scratch_.order;
        for (std::size_t i = 0; i + 1 < n;) {
            std::size_t j = i + 1;
            while (j < n && key[j] == key[i]) ++j;
            if (j - i > 1)
                std::sort(order.begin() + static_cast<std::ptrdiff_t>(i), order.begin() + static_cast<std::ptrdiff_t>(j),
                          [&](i32 a, i32 b) { return beats(a, b); });
            i = j;
        }
    }

    // threads: the number of blocks, each counted and scattered by one
    // iteration of a parallel loop; 1 sorts on the calling thread.
    template <int kDigitBits>
    void radix_order(const std::vector<i32>& ops, int threads) const {
        const std::size_t n = ops.size();
        std::vector<u32>& key = scratch_.sort_key;
        std::vector<u32>& key_spare = scratch_.sort_key_spare;
        std::vector<i32>& order = scratch_.order;
        std::vector<i32>& order_spare = scratch_.order_spare;
        key.resize(n);
        key_spare.resize(n);
        order.resize(n);
        order_spare.resize(n);
        if (n == 0) return;
        parallel_for(threads, static_cast<i64>(n), [&](i64 i) {
            const auto k = static_cast<std::size_t>(i);
            order[k] = ops[k];
            key[k] = ~ops_.priority[static_cast<std::size_t>(ops[k])];
        });
        const auto blocks = static_cast<std::size_t>(threads);
        const auto block_begin = [&](std::size_t b) { return n * b / blocks; };
        constexpr int kDigits = (32 + kDigitBits - 1) / kDigitBits;
        constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
        std::vector<u32>& count = scratch_.histogram;
        count.resize(blocks * kBuckets);
        for (int d = 0; d < kDigits; ++d) {
            const int shift = d * kDigitBits;
            const auto digit = [&](u32 k) { return (k >> shift) & (kBuckets - 1); };
            parallel_for(threads, static_cast<i64>(blocks), [&](i64 b) {
                u32* c = count.data() + static_cast<std::size_t>(b) * kBuckets;
                std::fill(c, c + kBuckets, 0u);
                for (std::size_t i = block_begin(static_cast<std::size_t>(b)); i < block_begin(static_cast<std::size_t>(b) + 1); ++i)
                    ++c[digit(key[i])];
            }, 0);
            std::size_t shared = 0;
            for (std::size_t b = 0; b < blocks; ++b) shared += count[b * kBuckets + digit(key[0])];
            if (shared == n) continue;
            // Offsets in bucket order and, within a bucket, block order: the
            // scatter keeps the keys' order among equal digits (stable).
            u32 sum = 0;
            for (std::size_t bucket = 0; bucket < kBuckets; ++bucket)
                for (std::size_t b = 0; b < blocks; ++b) {
                    const u32 here = count[b * kBuckets + bucket];
                    count[b * kBuckets + bucket] = sum;
                    sum += here;
                }
            parallel_for(threads, static_cast<i64>(blocks), [&](i64 b) {
                u32* c = count.data() + static_cast<std::size_t>(b) * kBuckets;
                for (std::size_t i = block_begin(static_cast<std::size_t>(b)); i < block_begin(static_cast<std::size_t>(b) + 1); ++i) {
                    const u32 at = c[digit(key[i])]++;
                    key_spare[at] = key[i];
                    order_spare[at] = order[i];
                }
            }, 0);
            key.swap(key_spare);
            order.swap(order_spare);
        }
    }

    const Surface& s_;
    const Fans& fans_;
    const Edges& edges_;
    const Ops& ops_;
    const std::vector<Cone>& cones_;
    void claim(i32 v) const {
        std::atomic_ref<i32>(scratch_.claimed[static_cast<std::size_t>(v)]).store(stamp_, std::memory_order_relaxed);
    }
    // Claims the closed 1-ring of every vertex chosen operation e touches
    // and of every corner it owns.
    void claim_around(i32 e) const {
        i32 vs[4 + kMaxOwned];
        int n = touched(e, vs);
        n += std::max(0, owned_corners(e, vs + n));
        for (int i = 0; i < n; ++i) {
            claim(vs[i]);
            for (i32 j = 0, m = fans_.nn(vs[i]); j < m; ++j) claim(fans_.nbr(vs[i], j));
        }
    }

    // A window operation's ends, then its owned corners.
    template <class F>
    void for_each_footprint(const WindowSlot& slot, const F& f) const {
        f(slot.u);
        f(slot.w);
        if (slot.owned_count <= 0) return;
        i32 owned[kMaxOwned];
        const int n = owned_corners(slot.e, owned);
        for (int k = 0; k < n; ++k) f(owned[k]);
    }

    SelectScratch& scratch_;
    mutable i32 stamp_ = 0;
};

// ---------------------------------------------------------------------------
// Input and option checks.

void check_input(const Piece& in) {
    const std::size_t nv = in.key.size();
    if (in.x.size() != nv || in.y.size() != nv || in.z.size() != nv)
        throw Error("tetiso::reduce: x, y, z and key differ in length");
    if (!in.flags.empty() && in.flags.size() != nv) throw Error("tetiso::reduce: flags and key differ in length");
    if (in.triangles.size() % 3 != 0) throw Error("tetiso::reduce: the triangle array is not a multiple of 3");
    if (!in.error.empty() && in.error.size() != in.triangle_count())
        throw Error("tetiso::reduce: error and triangles differ in length");
    for (std::size_t t = 0; t < in.error.size(); ++t)
        if (!(in.error[t] >= 0.0f && std::isfinite(in.error[t])))
            throw Error("tetiso::reduce: triangle " + std::to_string(t) + " has an error bound that is not a finite non-negative number");
    if (in.sample_xyz.size() != 3 * in.sample_triangle.size())
        throw Error("tetiso::reduce: sample_xyz is not three coordinates per sample_triangle");
    if ((!in.sample_triangle.empty() || !in.sampled.empty()) && in.error.empty())
        throw Error("tetiso::reduce: samples without error bounds (a raw surface's samples are its vertices)");
    if (!in.sampled.empty() && in.sampled.size() != in.triangle_count())
        throw Error("tetiso::reduce: sampled and triangles differ in length");
    for (std::size_t i = 0; i < in.sample_count(); ++i) {
        const i32 t = in.sample_triangle[i];
        if (t < 0 || static_cast<std::size_t>(t) >= in.triangle_count())
            throw Error("tetiso::reduce: sample " + std::to_string(i) + " refers to triangle " + std::to_string(t) +
                        " of " + std::to_string(in.triangle_count()));
        if (!in.triangle_sampled(static_cast<std::size_t>(t)))
            throw Error("tetiso::reduce: sample " + std::to_string(i) + " is held by triangle " + std::to_string(t) +
                        ", which is not marked sampled");
        for (std::size_t c = 0; c < 3; ++c)
            if (!std::isfinite(in.sample_xyz[3 * i + c]))
                throw Error("tetiso::reduce: sample " + std::to_string(i) + " has a coordinate that is not finite");
    }
    if (nv > static_cast<std::size_t>(std::numeric_limits<i32>::max() / 2) ||
        in.triangles.size() > static_cast<std::size_t>(std::numeric_limits<i32>::max() / 2))
        throw Error("tetiso::reduce: mesh too large for 32-bit indices");
    for (std::size_t v = 1; v < nv; ++v)
        if (!(in.key[v - 1] < in.key[v]))
            throw Error("tetiso::reduce: vertex keys are not sorted and unique at vertex " + std::to_string(v) +
                        " (key " + std::to_string(in.key[v]) + ")");
    for (std::size_t v = 0; v < nv; ++v)
        if (!std::isfinite(in.x[v]) || !std::isfinite(in.y[v]) || !std::isfinite(in.z[v]))
            throw Error("tetiso::reduce: vertex (key " + std::to_string(in.key[v]) +
                        ") has a coordinate that is not finite");
    for (std::size_t t = 0; t < in.triangle_count(); ++t) {
        const i32 a = in.triangles[3 * t], b = in.triangles[3 * t + 1], c = in.triangles[3 * t + 2];
        for (const i32 v : {a, b, c})
            if (v < 0 || static_cast<std::size_t>(v) >= nv)
                throw Error("tetiso::reduce: triangle " + std::to_string(t) + " refers to vertex " +
                            std::to_string(v) + " of " + std::to_string(nv));
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
}

// ---------------------------------------------------------------------------
// Step 6: apply the chosen operations. They share no triangle and no vertex,
// so each writes only its own elements. changed[v] is set for every vertex
// whose fan, or a face of it, was altered: the vertices of every face of both
// leaves of a collapse, the four corners of a flip. Two operations may mark
// the same vertex, hence the atomic (relaxed: the value is all that matters).

void apply(Surface& s, const Fans& fans, const Edges& edges, const Ops& ops, const std::vector<u8>& chosen,
           int threads, std::vector<u8>& vertex_alive, std::vector<u8>& triangle_alive, std::vector<u8>& changed) {
    vertex_alive.assign(static_cast<std::size_t>(s.vertices()), 1);
    triangle_alive.assign(static_cast<std::size_t>(s.triangles()), 1);
    changed.assign(static_cast<std::size_t>(s.vertices()), 0);
    auto mark = [&](i32 v) { std::atomic_ref<u8>(changed[static_cast<std::size_t>(v)]).store(1, std::memory_order_relaxed); };
    parallel_for(threads, edges.count(), [&](i64 ei) {
        const auto e = static_cast<std::size_t>(ei);
        if (!chosen[e]) return;
        const i32 u = edges.v0[e], w = edges.v1[e];
        const EdgeFaces ef = edges.faces(fans, static_cast<i32>(e));
        const i32 f1 = ef.f1, f2 = ef.f2;
        const float err = ops.err[e];
        if (ops.kind[e] == kFlip) {
            const i32 c = ef.c, d = ef.d;
            for (const i32 v : {u, w, c, d}) mark(v);
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
        if (!s.locked(keep)) { // a locked survivor is pinned: p is its own position
            float* p = s.xyz.data() + 3 * static_cast<std::size_t>(keep);
            p[0] = ops.px[e];
            p[1] = ops.py[e];
            p[2] = ops.pz[e];
        }
        vertex_alive[static_cast<std::size_t>(gone)] = 0;
        for (const i32 v : {keep, gone}) {
            const i32 o = fans.off[static_cast<std::size_t>(v)], k = fans.k(v);
            for (i32 j = o; j < o + k; ++j) {
                const i32 t = fans.face[static_cast<std::size_t>(j)];
                for (int r = 0; r < 3; ++r) mark(s.tri[static_cast<std::size_t>(3 * t + r)]);
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
}

// Quiet edges. An edge's answer (its proposal and legality) reads the fans
// of its two ends — their faces, those faces' corners' positions and error
// bounds — and the fans of the two opposite vertices (valences, the flip's
// diagonal). A collapse changes the fans of exactly the vertices of its two
// leaves' faces and moves only the survivor, whose neighbours are among
// them; a flip changes the fans of its four corners. So an edge none of whose
// four vertices apply() marked has the answer it had last round. An
// unchanged vertex keeps its triangles and their order, so its fan comes out
// the same and an edge it owns keeps its slot: refused_slots[v] has bit j set
// when the edge v owns at slot j (v its smaller end) was found to have no
// possible operation (Φ not above Φ*, illegal, no flip). An edge so marked
// whose four vertices are unchanged is skipped; an edge blocked before its
// answer was known is not marked. (Marking a vertex only when every edge it
// owns was refused, as before, evaluated 2.80 M operations on the paper
// surface at N = 100 where this evaluates 2.69 M, for the same output and
// about the same time.)
// Once most of the surface is as reduced as the criterion and the bounds
// allow, a round costs what the last one changed rather than a full
// evaluation.
// Slots past the mask's width are never marked: their edges are re-tested.
constexpr i32 kRefusedSlots = 32;

bool known_refused(const std::vector<u32>& refused_slots, const Edges& edges, std::size_t e) {
    const i32 j = edges.s0[e];
    return j < kRefusedSlots && (refused_slots[static_cast<std::size_t>(edges.v0[e])] >> j & 1u);
}

bool unchanged(const Fans& fans, const Edges& edges, const std::vector<u8>& changed, std::size_t e) {
    const i32 u = edges.v0[e], w = edges.v1[e];
    if (changed[static_cast<std::size_t>(u)] || changed[static_cast<std::size_t>(w)]) return false;
    const EdgeFaces f = edges.faces(fans, static_cast<i32>(e));
    for (const i32 o : {f.c, f.d})
        if (o >= 0 && changed[static_cast<std::size_t>(o)]) return false;
    return true;
}

// Step 7: drop removed vertices and triangles, keeping the order of the rest
// (so keys stay sorted). The ranks are integer scans; the copies are gathers
// into the spare arrays, which then change places with the live ones.
// vertex_marks, vertex_masks: per-vertex arrays that follow the vertices
// (changed, refused_slots); triangle_refs: triangle indices to renumber (the
// samples' owners).
struct CompactSpare {
    Surface surface;
    std::vector<u8> marks;
    std::vector<u32> masks;
};

void compact(Surface& s, const std::vector<u8>& vertex_alive, const std::vector<u8>& triangle_alive, int threads,
             std::vector<u8>& vertex_marks, std::vector<u32>& vertex_masks, std::vector<i32>& triangle_refs,
             std::vector<i32>& remap, std::vector<i32>& scratch, CompactSpare& spare) {
    const i32 nv = s.vertices(), nt = s.triangles();
    const i32 next = parallel_rank(threads, nv, [&](i64 v) { return vertex_alive[static_cast<std::size_t>(v)] != 0; }, remap);
    Surface& to = spare.surface;
    to.xyz.resize(3 * static_cast<std::size_t>(next));
    to.key.resize(static_cast<std::size_t>(next));
    to.flags.resize(static_cast<std::size_t>(next));
    spare.marks.resize(static_cast<std::size_t>(next));
    spare.masks.resize(static_cast<std::size_t>(next));
    parallel_for(threads, nv, [&](i64 vi) {
        const auto v = static_cast<std::size_t>(vi);
        const i32 r = remap[v];
        if (r < 0) return;
        const auto a = static_cast<std::size_t>(r);
        for (std::size_t c = 0; c < 3; ++c) to.xyz[3 * a + c] = s.xyz[3 * v + c];
        to.key[a] = s.key[v];
        to.flags[a] = s.flags[v];
        spare.marks[a] = vertex_marks[v];
        spare.masks[a] = vertex_masks[v];
    });
    s.xyz.swap(to.xyz);
    s.key.swap(to.key);
    s.flags.swap(to.flags);
    vertex_marks.swap(spare.marks);
    vertex_masks.swap(spare.masks);
    auto& tpos = scratch;
    const i32 tn = parallel_rank(threads, nt, [&](i64 t) { return triangle_alive[static_cast<std::size_t>(t)] != 0; }, tpos);
    to.tri.resize(static_cast<std::size_t>(3 * tn));
    to.err.resize(static_cast<std::size_t>(tn));
    parallel_for(threads, nt, [&](i64 ti) {
        const auto t = static_cast<std::size_t>(ti);
        const i32 at = tpos[t];
        if (at < 0) return;
        for (std::size_t r = 0; r < 3; ++r)
            to.tri[3 * static_cast<std::size_t>(at) + r] = remap[static_cast<std::size_t>(s.tri[3 * t + r])];
        to.err[static_cast<std::size_t>(at)] = s.err[t];
    });
    s.tri.swap(to.tri);
    s.err.swap(to.err);
    parallel_for(threads, static_cast<i64>(triangle_refs.size()), [&](i64 i) {
        i32& t = triangle_refs[static_cast<std::size_t>(i)];
        if (t >= 0) t = tpos[static_cast<std::size_t>(t)];
    });
}

} // namespace

Piece reduce(const Piece& in, const ReduceOptions& options, ReduceReport* report) {
    const auto start_time = std::chrono::steady_clock::now();
    check_options(options);
    check_input(in);
    int available = resolve_threads(options.threads);
    const Params params{options.phi,
                        std::sin(options.min_angle_degrees * kPi / 180.0),
                        std::cos(options.max_normal_turn_degrees * kPi / 180.0),
                        std::cos(options.flip_max_dihedral_degrees * kPi / 180.0),
                        options.max_error,
                        options.short_edge_ratio,
                        options.flips};

    std::vector<float> xyz(3 * in.vertex_count());
    for (std::size_t v = 0; v < in.vertex_count(); ++v) {
        xyz[3 * v] = in.x[v];
        xyz[3 * v + 1] = in.y[v];
        xyz[3 * v + 2] = in.z[v];
    }
    Surface s{std::move(xyz), in.key,
              in.flags.empty() ? std::vector<u8>(in.key.size(), 0) : in.flags, in.triangles,
              in.error.empty() ? std::vector<float>(in.triangle_count(), 0.0f) : in.error};
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    rep = ReduceReport{};
    rep.triangles_in = in.triangle_count();
    rep.vertices_in = in.vertex_count();

    Fans fans;
    Edges edges;
    std::vector<FaceGeometry> geometry;
    std::vector<Cone> cones;
    Ops ops;
    std::vector<i32> scratch_a, scratch_b, remap;
    CompactSpare spare; // compact()'s second set of arrays
    std::vector<u8> chosen, refused, vertex_alive, triangle_alive;
    std::vector<u8> changed(in.vertex_count(), 0);
    std::vector<u32> refused_slots(in.vertex_count(), 0);
    std::vector<i32> candidate_list, flip_list, to_move;
    SelectScratch select_scratch;
    int idle_rounds = 0;
    Samples samples;
    if (options.max_error > 0) samples.build(in);

    ReduceStageSeconds& st = rep.stages;
    auto now = [] { return std::chrono::steady_clock::now(); };
    auto since = [&](auto t) { return std::chrono::duration<double>(now() - t).count(); };

    // The first build_fans validates the input: it throws on non-manifold or
    // misoriented input before anything is changed.
    for (int round = 0;; ++round) {
        if (options.more_threads)
            if (const int offered = options.more_threads(); offered > 0) available = offered;
        const int threads = std::min(available, kMaxRoundThreads);
        const auto round_start = now();
        auto t0 = round_start;
        build_fans(s, threads, round == 0, fans, scratch_a, scratch_b);
        st.fans += since(t0);
        if (round >= options.max_rounds) break;
        t0 = now();
        build_edges(fans, threads, edges, scratch_a);
        st.edges += since(t0);
        t0 = now();
        build_geometry(s, threads, geometry);
        st.geometry += since(t0);
        t0 = now();
        const i32 ne = edges.count();
        ops.resize(static_cast<std::size_t>(ne));
        refused.assign(static_cast<std::size_t>(ne), 0);
        if (samples.on()) samples.sort(geometry, threads);
        build_cones(s, fans, geometry, threads, cones);
        const Evaluator evaluator(s, fans, edges, geometry, cones, samples.on() ? &samples : nullptr, params, round);
        parallel_for(threads, ne, [&](i64 ei) {
            const auto e = static_cast<std::size_t>(ei);
            if (known_refused(refused_slots, edges, e) && unchanged(fans, edges, changed, e)) ops.kind[e] = kQuiet;
            else evaluator.classify(static_cast<i32>(e), ops);
        });
        chosen.assign(static_cast<std::size_t>(ne), 0);
        parallel_filter(threads, ne, [&](i64 e) {
            const u8 kind = ops.kind[static_cast<std::size_t>(e)];
            return kind == kPending || kind == kCollapse;
        }, candidate_list);
        st.propose += since(t0);
        ReduceRound stats;
        stats.round = round;
        stats.vertices = static_cast<std::size_t>(s.vertices());
        stats.triangles = static_cast<std::size_t>(s.triangles());
        t0 = now();
        // Collapses. The selection places a pending collapse (Φ, position)
        // only when it reaches it unblocked: most are blocked by a chosen
        // neighbour and never need their Φ this round.
        const Selector selector(s, fans, edges, ops, cones, select_scratch);
        selector.select(threads, candidate_list, chosen, refused,
                        [&](i32 e, const auto& free_corners) {
                            return evaluator.legal(e, ops, samples.on() ? &samples.owner : nullptr, free_corners);
                        });
        // Flips: for the interior edges with no collapse that no chosen
        // collapse blocks. refused[e] (set by the selection for a collapse
        // found impossible or illegal) ends as "no operation is possible on
        // e", the answer refused_slots keeps; a blocked edge's answer is
        // unknown.
        selector.claim_chosen(threads, candidate_list, chosen);
        parallel_for(threads, ne, [&](i64 e) {
            const auto i = static_cast<std::size_t>(e);
            if (ops.kind[i] == kNone) refused[i] = !params.flips || edges.border(fans, static_cast<i32>(e));
        });
        parallel_filter(threads, ne, [&](i64 e) {
            const auto i = static_cast<std::size_t>(e);
            return ops.kind[i] == kNone && !refused[i] && selector.clear(static_cast<i32>(e));
        }, flip_list);
        parallel_for(threads, static_cast<i64>(flip_list.size()), [&](i64 fi) {
            const i32 e = flip_list[static_cast<std::size_t>(fi)];
            if (!evaluator.propose_flip(e, ops)) refused[static_cast<std::size_t>(e)] = 1;
        });
        std::size_t evaluated = flip_list.size();
        std::erase_if(flip_list, [&](i32 e) { return ops.kind[static_cast<std::size_t>(e)] != kFlip; });
        const std::size_t flips_offered = flip_list.size();
        selector.choose_flips(flip_list, chosen);
        parallel_for(threads, s.vertices(), [&](i64 v) {
            u32 mask = 0;
            for (i32 e = edges.first[static_cast<std::size_t>(v)]; e < edges.first[static_cast<std::size_t>(v) + 1]; ++e) {
                const auto i = static_cast<std::size_t>(e);
                if ((ops.kind[i] == kQuiet || refused[i]) && edges.s0[i] < kRefusedSlots) mask |= u32{1} << edges.s0[i];
            }
            refused_slots[static_cast<std::size_t>(v)] = mask;
        });
        evaluated += static_cast<std::size_t>(parallel_count(threads, static_cast<i64>(candidate_list.size()), [&](i64 k) {
            return ops.kind[static_cast<std::size_t>(candidate_list[static_cast<std::size_t>(k)])] != kPending;
        }));
        stats.candidates = candidate_list.size() + flips_offered;
        stats.evaluated = evaluated;
        st.select += since(t0);
        t0 = now();
        // Samples still to move: those of the flips (a collapse's test moved
        // its samples when it was chosen).
        stats.collapses = static_cast<std::size_t>(parallel_count(threads, ne, [&](i64 e) {
            return chosen[static_cast<std::size_t>(e)] && ops.kind[static_cast<std::size_t>(e)] == kCollapse;
        }));
        parallel_filter(threads, ne, [&](i64 e) {
            return chosen[static_cast<std::size_t>(e)] && ops.kind[static_cast<std::size_t>(e)] == kFlip;
        }, to_move);
        stats.flips = to_move.size();
        if (stats.collapses == 0 && stats.flips == 0) { // the next round would find what this one did
            stats.seconds = since(round_start);
            rep.rounds.push_back(stats);
            break;
        }
        // The samples move first: they are placed on the new faces by
        // reading the fans and positions that their legality test read. Each
        // move costs about what a legality test does.
        if (samples.on())
            parallel_for_tests(threads, static_cast<i64>(to_move.size()), [&](i64 m) {
                evaluator.move_flip_samples(to_move[static_cast<std::size_t>(m)], samples.owner);
            });
        apply(s, fans, edges, ops, chosen, threads, vertex_alive, triangle_alive, changed);
        stats.changed_vertices = static_cast<std::size_t>(parallel_count(threads, static_cast<i64>(changed.size()), [&](i64 v) {
            return (changed[static_cast<std::size_t>(v)] & vertex_alive[static_cast<std::size_t>(v)]) != 0;
        }));
        st.apply += since(t0);
        t0 = now();
        if (stats.collapses > 0) compact(s, vertex_alive, triangle_alive, threads, changed, refused_slots, samples.owner, remap, scratch_a, spare);
        st.compact += since(t0);
        stats.seconds = since(round_start);
        rep.rounds.push_back(stats);
        idle_rounds = stats.collapses == 0 ? idle_rounds + 1 : 0;
        if (idle_rounds >= 2) break;
    }
    Piece out;
    const std::size_t nv_out = s.key.size();
    out.x.resize(nv_out);
    out.y.resize(nv_out);
    out.z.resize(nv_out);
    for (std::size_t v = 0; v < nv_out; ++v) {
        out.x[v] = s.xyz[3 * v];
        out.y[v] = s.xyz[3 * v + 1];
        out.z[v] = s.xyz[3 * v + 2];
    }
    out.key = std::move(s.key);
    out.flags = std::move(s.flags);
    out.triangles = std::move(s.tri);
    out.error = std::move(s.err);
    out.domains = in.domains;
    if (options.keep_samples && samples.on()) samples.hand_on(out);
    rep.triangles_out = out.triangle_count();
    rep.vertices_out = out.vertex_count();
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
    return out;
}

} // namespace tetiso
