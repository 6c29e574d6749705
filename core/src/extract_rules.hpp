// What marching tetrahedra on every backend (extract.cpp, marching_tets.hpp) must agree
// on bit for bit, written once: the marching-tetrahedra case table, the
// placement of a crossing, the quad's split, the checks of a domain and their
// messages. The arithmetic functions compile for the host and the device;
// under nvcc they are built with --fmad=false, as the host code is with
// -ffp-contract=off, so each operation rounds once, the same on both.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "hd.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::extract_rules {

constexpr int kEdgesOfTet[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// For each of the 16 above/below patterns of a tetrahedron: its crossing
// edges (tet-edge numbers), in the order that makes the triangle, or the
// quad's cycle, counter-clockwise seen from the side of increasing field for
// a positively oriented tetrahedron.
struct MarchCase {
    int crossings = 0; // 0, 3 (one triangle) or 4 (a quad, two triangles)
    std::array<int, 4> edge{};
};

// A constexpr swap (std::swap is one only from C++20, and the CUDA unit that
// includes this is C++17).
constexpr void swap_ints(int& a, int& b) {
    const int t = a;
    a = b;
    b = t;
}

constexpr std::array<MarchCase, 16> build_cases() {
    // Reference tetrahedron with positive orientation; above nodes get +1,
    // below -1, so crossings are edge midpoints and the above side is where
    // the above nodes' centroid is.
    constexpr double corner[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    std::array<MarchCase, 16> cases{};
    for (int pattern = 1; pattern < 15; ++pattern) {
        auto above = [&](int v) { return (pattern >> v) & 1; };
        std::array<int, 4> cut{};
        int count = 0;
        for (int e = 0; e < 6; ++e)
            if (above(kEdgesOfTet[e][0]) != above(kEdgesOfTet[e][1])) cut[static_cast<std::size_t>(count++)] = e;
        if (count == 4) {
            // Order the quad as a cycle: consecutive edges share a tet node.
            auto share = [](int e, int f) {
                return kEdgesOfTet[e][0] == kEdgesOfTet[f][0] || kEdgesOfTet[e][0] == kEdgesOfTet[f][1] ||
                       kEdgesOfTet[e][1] == kEdgesOfTet[f][0] || kEdgesOfTet[e][1] == kEdgesOfTet[f][1];
            };
            if (!share(cut[0], cut[1])) swap_ints(cut[1], cut[2]);
            if (!share(cut[1], cut[2])) swap_ints(cut[2], cut[3]);
        }
        auto midpoint = [&](int e, int axis) {
            return 0.5 * (corner[kEdgesOfTet[e][0]][axis] + corner[kEdgesOfTet[e][1]][axis]);
        };
        double a[3]{}, b[3]{}, normal[3]{}, up[3] = {0, 0, 0};
        for (int axis = 0; axis < 3; ++axis) {
            a[axis] = midpoint(cut[1], axis) - midpoint(cut[0], axis);
            b[axis] = midpoint(cut[2], axis) - midpoint(cut[0], axis);
        }
        normal[0] = a[1] * b[2] - a[2] * b[1];
        normal[1] = a[2] * b[0] - a[0] * b[2];
        normal[2] = a[0] * b[1] - a[1] * b[0];
        for (int v = 0; v < 4; ++v)
            for (int axis = 0; axis < 3; ++axis) up[axis] += (above(v) ? 1.0 : -1.0) * corner[v][axis];
        if (normal[0] * up[0] + normal[1] * up[1] + normal[2] * up[2] < 0)
            for (int i = 0, j = count - 1; i < j; ++i, --j)
                swap_ints(cut[static_cast<std::size_t>(i)], cut[static_cast<std::size_t>(j)]);
        cases[static_cast<std::size_t>(pattern)] = MarchCase{count, cut};
    }
    return cases;
}

inline constexpr std::array<MarchCase, 16> kCases = build_cases();

// How near one of its ends a crossing of edge (a, b) may lie, as a
// parameter: kNodeClearanceUlps units in the last place of the edge's largest
// coordinate (or of its extent, if that is larger), measured along the axis
// it runs furthest in. A crossing nearer its node than float can tell apart
// would be written at the node's own position, or a few ulps off it, by every
// edge through that node: vertices of different keys at one position,
// zero-area triangles, and faces whose normals rounding chose. Reduction
// cannot be relied on to merge such a cluster: those normals refuse its
// collapses (the paper's N = 500 surface kept one inside a domain), locked
// vertices refuse them all, and `extract` and --no-reduce write it as it is.
// Kept this far off, the crossings of the edges through one node are
// distinct points (on a lattice, each moves in every coordinate its edge
// runs in), each on its own edge, each within its own tetrahedron: a small,
// resolved copy of the node's link, which rounding moves by a small fraction
// of its size.
// Only the edge's own data enter, so every domain holding the edge computes
// the same bits; each step is IEEE arithmetic (a multiplication by a power of
// two, one division), the same on the host and the device. An edge too short
// for the clearance (under 4 × kNodeClearanceUlps ulps) keeps its crossings
// in its middle half.
constexpr float kNodeClearanceUlps = 32.0f;

TETISO_HD inline float node_clearance(float ax, float ay, float az, float bx, float by, float bz) {
    auto larger = [](float a, float b) { return a > b ? a : b; };
    auto magnitude = [](float a) { return a < 0.0f ? -a : a; };
    const float extent = larger(magnitude(bx - ax), larger(magnitude(by - ay), magnitude(bz - az)));
    const float largest = larger(extent, larger(larger(larger(magnitude(ax), magnitude(bx)),
                                                       larger(magnitude(ay), magnitude(by))),
                                                larger(magnitude(az), magnitude(bz))));
    constexpr float kMostClearance = 0.25f;
    if (!(extent > 0.0f)) return kMostClearance;
    // largest × 2^-23 is within a factor 2 above the ulp of `largest`.
    const float clearance = kNodeClearanceUlps * 0x1p-23f * largest / extent;
    return clearance < kMostClearance ? clearance : kMostClearance;
}

// Where the crossing of edge (a, b) lies, as the parameter from a, where a is
// the end with the smaller global id (so that every domain holding the edge
// computes the same bits): fa >= level > fb or the reverse. Kept within
// [clearance, 1 - clearance] (node_clearance); monotone in the level.
TETISO_HD inline float crossing_parameter(float fa, float fb, float level, float clearance) {
    const float t = (level - fa) / (fb - fa);
    const float highest = 1.0f - clearance;
    return t < clearance ? clearance : (t > highest ? highest : t);
}

TETISO_HD inline float interpolate(float a, float b, float t) { return a + t * (b - a); }

// Which of the quad's two diagonals splits it: the one through the crossing of
// the edge with the smallest global key (the first such, of the quad's four
// in case order) — a combinatorial rule, the same in every domain, node
// numbering and backend. True: triangles (0, 1, 2) and (0, 2, 3); false:
// (1, 2, 3) and (1, 3, 0).
TETISO_HD inline bool split_through_first(const EdgeKey order[4]) {
    int first_min = 0;
    for (int k = 1; k < 4; ++k)
        if (order[k] < order[first_min]) first_min = k;
    return first_min % 2 == 0;
}

// Which of a tetrahedron's triangles a cut emits, as corners named by the
// crossings' codes (whatever the caller numbers them by: bucket slots,
// vertex numbers, edge codes): one triangle for 3 crossings, the quad split
// by split_through_first for 4 (order: the crossings' global keys). Returns
// the number of corners written to out (3 or 6).
template <class Code>
TETISO_HD inline int emit_triangles(int crossings, const Code code[4], const EdgeKey order[4], Code* out) {
    if (crossings == 3) {
        out[0] = code[0], out[1] = code[1], out[2] = code[2];
        return 3;
    }
    if (split_through_first(order)) {
        out[0] = code[0], out[1] = code[1], out[2] = code[2];
        out[3] = code[0], out[4] = code[2], out[5] = code[3];
    } else {
        out[0] = code[1], out[1] = code[2], out[2] = code[3];
        out[3] = code[1], out[4] = code[3], out[5] = code[0];
    }
    return 6;
}

// A domain's node arrays as the placement reads them, on the host or the
// device; shared: the domain's sorted shared-edge keys (none for a box,
// whose node masks tell its shared edges).
struct NodeView {
    const float *x, *y, *z, *f;
    const GlobalId* gid;
    const std::uint8_t* interface;
    const EdgeKey* shared;
    std::size_t shared_count;
};

struct CrossingVertex {
    float x, y, z;
    EdgeKey key;
    std::uint8_t flags;
};

TETISO_HD inline bool contains(const EdgeKey* sorted, std::size_t n, EdgeKey key) {
    std::size_t lo = 0, hi = n;
    while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (sorted[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return lo < n && sorted[lo] == key;
}

// The vertex of the crossing on edge (lo, hi) (local node numbers): its
// position, interpolated from the end with the smaller global id so that
// every domain holding the edge computes the same bits; its key; locked when
// the edge lies on an interface of the domain.
TETISO_HD inline CrossingVertex place_crossing(const NodeView& node, std::size_t lo, std::size_t hi, float level) {
    const bool lo_first = node.gid[lo] < node.gid[hi];
    const std::size_t a = lo_first ? lo : hi, b = lo_first ? hi : lo;
    const float clearance =
        node_clearance(node.x[a], node.y[a], node.z[a], node.x[b], node.y[b], node.z[b]);
    const float t = crossing_parameter(node.f[a], node.f[b], level, clearance);
    CrossingVertex v;
    v.x = interpolate(node.x[a], node.x[b], t);
    v.y = interpolate(node.y[a], node.y[b], t);
    v.z = interpolate(node.z[a], node.z[b], t);
    v.key = edge_key(node.gid[a], node.gid[b]);
    const bool on_interface = (node.interface[a] & node.interface[b]) != 0 &&
                              (node.shared_count == 0 || contains(node.shared, node.shared_count, v.key));
    v.flags = on_interface ? static_cast<std::uint8_t>(kLocked) : std::uint8_t{0};
    return v;
}

// The most nodes a domain may have: the host's buckets (8 slots per node) are
// addressed by int32.
inline constexpr int kBucket = 8;

inline std::string domain_name(int id) { return "domain " + std::to_string(id); }

// The checks made before any work, the same for every backend.
void check_domain(const Domain& domain);

inline void check_level(float level) {
    if (!std::isfinite(level)) throw Error("isosurface level is not a finite number");
}

[[noreturn]] inline void throw_bad_value(int domain, GlobalId node) {
    throw Error(domain_name(domain) + ": node " + std::to_string(node) + " has a field value that is not finite");
}

[[noreturn]] inline void throw_bad_tet(int domain, std::int64_t tet) {
    throw Error(domain_name(domain) + ": tetrahedron " + std::to_string(tet) + " refers to a node that does not exist");
}

[[noreturn]] inline void throw_too_large(int domain) {
    throw Error(domain_name(domain) + ": surface too large for 32-bit indices");
}

} // namespace tetiso::extract_rules
