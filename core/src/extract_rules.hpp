// What the CPU (extract.cpp) and GPU (extract_gpu.cu) extractions must agree
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

#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

#ifdef __CUDACC__
#define TETISO_HOST_DEVICE __host__ __device__
#else
#define TETISO_HOST_DEVICE
#endif

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

// Where the crossing of edge (a, b) lies, as the parameter from a, where a is
// the end with the smaller global id (so that every domain holding the edge
// computes the same bits): fa >= level > fb or the reverse.
TETISO_HOST_DEVICE inline float crossing_parameter(float fa, float fb, float level) {
    float t = (level - fa) / (fb - fa);
    t = t < 0.0f ? 0.0f : (t > 1.0f ? 1.0f : t);
    // A crossing closer to a node than float resolves along its edge is the
    // node itself. Interpolated from a node at coordinate 0 it would land a
    // denormal-sized step off it instead (3e-16 on meshes/cube.1), so that
    // the vertices of all edges through that node, which ought to coincide
    // and be merged by the reducer's zero-length collapses, form a triangle
    // too small for the float normal and not short against its own edges.
    constexpr float kResolved = 0x1p-24f;
    if (t < kResolved) t = 0.0f;
    else if (t > 1.0f - kResolved) t = 1.0f;
    return t;
}

TETISO_HOST_DEVICE inline float interpolate(float a, float b, float t) { return a + t * (b - a); }

// Which of the quad's two diagonals splits it: the one through the crossing of
// the edge with the smallest global key (the first such, of the quad's four
// in case order) — a combinatorial rule, the same in every domain, node
// numbering and backend. True: triangles (0, 1, 2) and (0, 2, 3); false:
// (1, 2, 3) and (1, 3, 0).
TETISO_HOST_DEVICE inline bool split_through_first(const EdgeKey order[4]) {
    int first_min = 0;
    for (int k = 1; k < 4; ++k)
        if (order[k] < order[first_min]) first_min = k;
    return first_min % 2 == 0;
}

// The most nodes a domain may have: the CPU's buckets (8 slots per node) are
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
