// The meshes the checker's tests (test_check.cpp, test_check_geometry.cpp)
// build in code, with answers that follow from how they are laid out.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "tetiso/check.hpp"
#include "tetiso/error.hpp"

namespace tetiso::check_meshes {


using tetiso::Piece;

inline Piece make_mesh(const std::vector<std::array<float, 3>>& points, const std::vector<std::array<int, 3>>& triangles) {
    Piece m;
    for (std::size_t i = 0; i < points.size(); ++i) {
        m.x.push_back(points[i][0]);
        m.y.push_back(points[i][1]);
        m.z.push_back(points[i][2]);
        m.key.push_back(i);
        m.flags.push_back(0);
    }
    for (const auto& t : triangles) m.triangles.insert(m.triangles.end(), t.begin(), t.end());
    return m;
}

// Outward normals: every edge is run once each way.
inline Piece tetrahedron(float shift = 0.0f) {
    return make_mesh({{shift, 0, 0}, {shift + 1, 0, 0}, {shift, 1, 0}, {shift, 0, 1}},
                     {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

inline Piece append(Piece a, const Piece& b) {
    const int offset = static_cast<int>(a.x.size());
    a.x.insert(a.x.end(), b.x.begin(), b.x.end());
    a.y.insert(a.y.end(), b.y.begin(), b.y.end());
    a.z.insert(a.z.end(), b.z.begin(), b.z.end());
    for (std::size_t i = 0; i < b.x.size(); ++i) a.key.push_back(a.key.size()), a.flags.push_back(0);
    for (int v : b.triangles) a.triangles.push_back(v + offset);
    return a;
}

// A parametric torus, n x m quads each split into two triangles with the
// same orientation: V = nm, E = 3nm, F = 2nm, so chi = 0.
inline Piece torus(int n, int m, double major = 1.0, double minor = 0.35) {
    std::vector<std::array<float, 3>> p;
    std::vector<std::array<int, 3>> t;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            const double u = 2 * std::numbers::pi * i / n, v = 2 * std::numbers::pi * j / m;
            p.push_back({static_cast<float>((major + minor * std::cos(v)) * std::cos(u)),
                         static_cast<float>((major + minor * std::cos(v)) * std::sin(u)),
                         static_cast<float>(minor * std::sin(v))});
        }
    auto id = [&](int i, int j) { return ((i % n) * m) + (j % m); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return make_mesh(p, t);
}

// A disk: a centre and `rim` vertices around it, at height `apex` for the
// centre (a cone when apex != 0). V = rim + 1, E = 2 rim, F = rim: chi = 1.
inline Piece fan(int rim, float apex = 0.0f, float radius = 1.0f) {
    std::vector<std::array<float, 3>> p{{0, 0, apex}};
    std::vector<std::array<int, 3>> t;
    for (int i = 0; i < rim; ++i) {
        const double a = 2 * std::numbers::pi * i / rim;
        p.push_back({static_cast<float>(radius * std::cos(a)), static_cast<float>(radius * std::sin(a)), 0.0f});
        t.push_back({0, 1 + i, 1 + (i + 1) % rim});
    }
    return make_mesh(p, t);
}

// A Möbius strip of n quads: the last quad joins column n-1 to column 0 with
// top and bottom swapped, which is also where the geometry closes up
// (w -> -w after a full turn). V = 2n, E = 4n, F = 2n: chi = 0.
inline Piece mobius(int n) {
    std::vector<std::array<float, 3>> p;
    for (int i = 0; i < n; ++i)
        for (float w : {0.3f, -0.3f}) {
            const double a = 2 * std::numbers::pi * i / n;
            const double r = 1.0 + w * std::cos(a / 2);
            p.push_back({static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                         static_cast<float>(w * std::sin(a / 2))});
        }
    std::vector<std::array<int, 3>> t;
    for (int i = 0; i < n; ++i) {
        const int top = 2 * i, bottom = 2 * i + 1;
        const bool last = i == n - 1;
        const int next_top = last ? 1 : 2 * (i + 1), next_bottom = last ? 0 : 2 * (i + 1) + 1;
        t.push_back({top, bottom, next_bottom});
        t.push_back({top, next_bottom, next_top});
    }
    return make_mesh(p, t);
}
} // namespace tetiso::check_meshes
