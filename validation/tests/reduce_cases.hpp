// What the reduction suite (test_reduce.cpp, test_reduce_surfaces.cpp, each
// built for the CPU and again for the GPU) shares: meshes built in code and
// the checks every reduced surface must pass.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "reduce_under_test.hpp"
#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/detail/reduce_policy.hpp"
#include "tetiso/error.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::reduce_cases {


using test::lattice_surface;
using test::reduce_under_test;

// ---------------------------------------------------------------------------
// Meshes built in code. Keys are 0..n-1, flags 0.

struct Builder {
    Piece piece;
    std::int32_t add(double x, double y, double z) {
        piece.x.push_back(static_cast<float>(x));
        piece.y.push_back(static_cast<float>(y));
        piece.z.push_back(static_cast<float>(z));
        piece.key.push_back(piece.key.size());
        piece.flags.push_back(0);
        return static_cast<std::int32_t>(piece.key.size() - 1);
    }
    void tri(std::int32_t a, std::int32_t b, std::int32_t c) { piece.triangles.insert(piece.triangles.end(), {a, b, c}); }
};

// Unit icosphere, normals outwards.
inline Piece icosphere(int levels) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                         {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                         {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (auto& p : v) {
        const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (auto& c : p) c /= n;
    }
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<int, int>, int> mid;
        auto midpoint = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            if (auto it = mid.find(key); it != mid.end()) return it->second;
            std::array<double, 3> m{};
            for (int i = 0; i < 3; ++i) m[static_cast<std::size_t>(i)] = (v[static_cast<std::size_t>(a)][static_cast<std::size_t>(i)] + v[static_cast<std::size_t>(b)][static_cast<std::size_t>(i)]) / 2;
            const double n = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            for (auto& c : m) c /= n;
            v.push_back(m);
            return mid[key] = static_cast<int>(v.size() - 1);
        };
        std::vector<std::array<int, 3>> g;
        for (const auto& [a, b, c] : f) {
            const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            g.push_back({a, ab, ca});
            g.push_back({b, bc, ab});
            g.push_back({c, ca, bc});
            g.push_back({ab, bc, ca});
        }
        f = g;
    }
    Builder b;
    for (const auto& p : v) b.add(p[0], p[1], p[2]);
    for (const auto& [x, y, z] : f) b.tri(x, y, z);
    return b.piece;
}

// Torus around the z axis: nu segments along the ring, nv around the tube.
inline Piece torus(int nu, int nv, double ring, double tube) {
    Builder b;
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            const double u = 2 * std::numbers::pi * i / nu, w = 2 * std::numbers::pi * j / nv;
            b.add((ring + tube * std::cos(w)) * std::cos(u), (ring + tube * std::cos(w)) * std::sin(u), tube * std::sin(w));
        }
    auto id = [&](int i, int j) { return static_cast<std::int32_t>(((i + nu) % nu) * nv + (j + nv) % nv); };
    for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
            b.tri(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            b.tri(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    return b.piece;
}

// Flat n x n grid of unit squares in z = 0, x' = x + shear * y, each square
// split along the diagonal from (i, j) to (i + 1, j + 1).
inline Piece grid(int n, double shear = 0.0, double scale = 1.0) {
    Builder b;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) b.add(scale * (i + shear * j), scale * j, 0.0);
    auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            b.tri(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            b.tri(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    return b.piece;
}

// ---------------------------------------------------------------------------
// What every reduction must keep.

inline void expect_valid(const Piece& in, const Piece& out, const std::string& what) {
    SCOPED_TRACE(what);
    const TopologyReport a = check_topology(in), b = check_topology(out);
    EXPECT_TRUE(same_signatures(a, b));
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.boundary_loops, b.boundary_loops);
    EXPECT_EQ(a.euler, b.euler);
    EXPECT_EQ(b.non_manifold_edges, 0);
    EXPECT_EQ(b.non_manifold_vertices, 0);
    EXPECT_EQ(b.degenerate_triangles, 0);
    EXPECT_EQ(b.duplicate_triangles, 0);
    EXPECT_TRUE(b.oriented);
    EXPECT_EQ(b.referenced_vertices, b.vertices) << "every vertex left is used";
    // Keys: sorted, unique, a subset of the input's, with the same flags.
    EXPECT_TRUE(std::is_sorted(out.key.begin(), out.key.end()));
    EXPECT_EQ(std::adjacent_find(out.key.begin(), out.key.end()), out.key.end());
    ASSERT_EQ(out.flags.size(), out.key.size());
    for (std::size_t v = 0; v < out.key.size(); ++v) {
        const auto it = std::lower_bound(in.key.begin(), in.key.end(), out.key[v]);
        ASSERT_TRUE(it != in.key.end() && *it == out.key[v]);
        EXPECT_EQ(out.flags[v], in.flags[static_cast<std::size_t>(it - in.key.begin())]);
    }
    // Locked vertices: all there, bit for bit.
    for (std::size_t v = 0; v < in.key.size(); ++v) {
        if (!(in.flags[v] & kLocked)) continue;
        const auto it = std::lower_bound(out.key.begin(), out.key.end(), in.key[v]);
        ASSERT_TRUE(it != out.key.end() && *it == in.key[v]) << "locked vertex " << in.key[v] << " removed";
        const auto w = static_cast<std::size_t>(it - out.key.begin());
        EXPECT_EQ(std::bit_cast<std::uint32_t>(in.x[v]), std::bit_cast<std::uint32_t>(out.x[w]));
        EXPECT_EQ(std::bit_cast<std::uint32_t>(in.y[v]), std::bit_cast<std::uint32_t>(out.y[w]));
        EXPECT_EQ(std::bit_cast<std::uint32_t>(in.z[v]), std::bit_cast<std::uint32_t>(out.z[w]));
    }
}

// Everything a reduction writes, the error bounds and the raw vertices kept
// for later seams included.
inline bool identical(const Piece& a, const Piece& b) {
    return a.key == b.key && a.flags == b.flags && a.triangles == b.triangles && test::same_bits(a.x, b.x) &&
           test::same_bits(a.y, b.y) && test::same_bits(a.z, b.z) && test::same_bits(a.error, b.error) &&
           a.sampled == b.sampled && a.sample_triangle == b.sample_triangle &&
           test::same_bits(a.sample_xyz, b.sample_xyz);
}

inline std::size_t interior_valence3(const Piece& p) {
    std::map<std::pair<int, int>, int> edges;
    std::vector<std::set<int>> nbr(p.vertex_count());
    for (std::size_t t = 0; t < p.triangle_count(); ++t)
        for (int r = 0; r < 3; ++r) {
            const int a = p.triangles[3 * t + static_cast<std::size_t>(r)], b = p.triangles[3 * t + static_cast<std::size_t>((r + 1) % 3)];
            ++edges[std::minmax(a, b)];
            nbr[static_cast<std::size_t>(a)].insert(b);
            nbr[static_cast<std::size_t>(b)].insert(a);
        }
    std::vector<bool> border(p.vertex_count(), false);
    for (const auto& [e, n] : edges)
        if (n == 1) border[static_cast<std::size_t>(e.first)] = border[static_cast<std::size_t>(e.second)] = true;
    std::size_t count = 0;
    for (std::size_t v = 0; v < p.vertex_count(); ++v) count += !border[v] && nbr[v].size() == 3;
    return count;
}

} // namespace tetiso::reduce_cases
