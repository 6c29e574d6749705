// Tests of the topology checker and the Hausdorff estimate (check.hpp) on
// tiny meshes built here, whose answers follow from V - E + F and from how
// the triangles were laid out, not from running the checker.
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

namespace {

using tetiso::Piece;

Piece make_mesh(const std::vector<std::array<float, 3>>& points, const std::vector<std::array<int, 3>>& triangles) {
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
Piece tetrahedron(float shift = 0.0f) {
    return make_mesh({{shift, 0, 0}, {shift + 1, 0, 0}, {shift, 1, 0}, {shift, 0, 1}},
                     {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

Piece append(Piece a, const Piece& b) {
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
Piece torus(int n, int m, double major = 1.0, double minor = 0.35) {
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
Piece fan(int rim, float apex = 0.0f, float radius = 1.0f) {
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
Piece mobius(int n) {
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

TEST(CheckTopology, TetrahedronIsAClosedOrientedSphere) {
    const tetiso::TopologyReport r = tetiso::check_topology(tetrahedron());
    EXPECT_EQ(r.vertices, 4);
    EXPECT_EQ(r.referenced_vertices, 4);
    EXPECT_EQ(r.edges, 6);
    EXPECT_EQ(r.triangles, 4);
    EXPECT_EQ(r.euler, 2);
    EXPECT_EQ(r.components, 1);
    EXPECT_EQ(r.boundary_edges, 0);
    EXPECT_EQ(r.boundary_loops, 0);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.oriented);
    EXPECT_TRUE(r.orientable);
    EXPECT_EQ(r.misoriented_edges, 0);
    EXPECT_EQ(r.degenerate_triangles, 0);
    EXPECT_EQ(r.duplicate_positions, 0);
    EXPECT_EQ(r.duplicate_triangles, 0);
    ASSERT_EQ(r.per_component.size(), 1u);
    EXPECT_EQ(r.per_component[0].euler, 2);
    EXPECT_EQ(r.per_component[0].genus, 0);
    ASSERT_EQ(r.signatures.size(), 1u);
    EXPECT_EQ(r.signatures[0], (tetiso::TopologySignature{0, 0, true}));
    // Three right-angled faces (min angle 45) and one equilateral one (60).
    EXPECT_NEAR(r.min_angle.min, 45.0, 1e-4);
    EXPECT_NEAR(r.min_angle.mean, (3 * 45.0 + 60.0) / 4, 1e-4);
    EXPECT_EQ(r.min_angle.below_10, 0);
}

TEST(CheckTopology, FlippedTriangleMisorientsItsThreeEdges) {
    // Each edge of the flipped face is now run the same way by the face and
    // by its neighbour; the other three edges are untouched.
    Piece m = tetrahedron();
    std::swap(m.triangles[10], m.triangles[11]);
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.misoriented_edges, 3);
    EXPECT_FALSE(r.oriented);
    EXPECT_TRUE(r.orientable); // flipping it back fixes it
    EXPECT_EQ(r.euler, 2);
    EXPECT_EQ(r.per_component[0].genus, 0);
    EXPECT_FALSE(r.per_component[0].oriented);
    // Where: the flipped face's three edges, by smaller then larger end.
    const std::array<std::int32_t, 3> f = {m.triangles[9], m.triangles[10], m.triangles[11]};
    std::vector<std::vector<std::int32_t>> expected;
    for (int i = 0; i < 3; ++i)
        expected.push_back({std::min(f[i], f[(i + 1) % 3]), std::max(f[i], f[(i + 1) % 3])});
    std::sort(expected.begin(), expected.end());
    ASSERT_EQ(r.where.misoriented_edges.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(r.where.misoriented_edges[i].vertices, expected[i]);
    EXPECT_TRUE(r.where.non_manifold_edges.empty());
    EXPECT_TRUE(r.where.degenerate_triangles.empty());
}

TEST(CheckTopology, TorusHasGenusOne) {
    const int n = 24, m = 12;
    const tetiso::TopologyReport r = tetiso::check_topology(torus(n, m));
    EXPECT_EQ(r.referenced_vertices, n * m);
    EXPECT_EQ(r.edges, 3 * n * m);
    EXPECT_EQ(r.euler, 0);
    EXPECT_EQ(r.components, 1);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.oriented);
    ASSERT_EQ(r.per_component.size(), 1u);
    EXPECT_EQ(r.per_component[0].genus, 1);
    EXPECT_EQ(r.signatures[0], (tetiso::TopologySignature{1, 0, true}));
    EXPECT_FALSE(tetiso::same_signatures(r, tetiso::check_topology(tetrahedron())));
}

TEST(CheckTopology, ReportDoesNotDependOnTriangleOrderOrStartCorner) {
    // Same surface, triangles reversed and each rotated: every count and
    // signature must stay.
    const Piece a = torus(10, 7);
    Piece b = a;
    const std::size_t nt = a.triangle_count();
    for (std::size_t t = 0; t < nt; ++t) {
        const std::size_t s = nt - 1 - t;
        b.triangles[3 * t] = a.triangles[3 * s + 1];
        b.triangles[3 * t + 1] = a.triangles[3 * s + 2];
        b.triangles[3 * t + 2] = a.triangles[3 * s];
    }
    EXPECT_EQ(tetiso::to_json(tetiso::check_topology(a)), tetiso::to_json(tetiso::check_topology(b)));
}

TEST(CheckTopology, TwoDisjointTetrahedraAreTwoComponents) {
    const tetiso::TopologyReport r = tetiso::check_topology(append(tetrahedron(), tetrahedron(5.0f)));
    EXPECT_EQ(r.components, 2);
    EXPECT_EQ(r.euler, 4);
    ASSERT_EQ(r.per_component.size(), 2u);
    EXPECT_EQ(r.per_component[0].first_vertex, 0);
    EXPECT_EQ(r.per_component[1].first_vertex, 4);
    for (const auto& c : r.per_component) {
        EXPECT_EQ(c.vertices, 4);
        EXPECT_EQ(c.edges, 6);
        EXPECT_EQ(c.triangles, 4);
        EXPECT_EQ(c.euler, 2);
        EXPECT_EQ(c.genus, 0);
    }
    EXPECT_FALSE(tetiso::same_signatures(r, tetiso::check_topology(tetrahedron())));
    EXPECT_TRUE(tetiso::same_signatures(r, tetiso::check_topology(append(tetrahedron(1.0f), tetrahedron(-3.0f)))));
}

TEST(CheckTopology, IsolatedVerticesAreNotComponents) {
    Piece m = tetrahedron();
    m.x.push_back(9), m.y.push_back(9), m.z.push_back(9), m.key.push_back(4), m.flags.push_back(0);
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.vertices, 5);
    EXPECT_EQ(r.referenced_vertices, 4);
    EXPECT_EQ(r.components, 1);
    EXPECT_EQ(r.euler, 2);
}

TEST(CheckTopology, BowTieHasOneNonManifoldVertex) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.non_manifold_vertices, 1);
    EXPECT_EQ(r.non_manifold_edges, 0);
    EXPECT_FALSE(r.manifold);
    EXPECT_EQ(r.components, 1); // joined through the shared vertex
    EXPECT_EQ(r.boundary_edges, 6);
    EXPECT_EQ(r.boundary_loops, 2); // one per triangle, not a figure eight
    EXPECT_EQ(r.euler, 5 - 6 + 2);
    ASSERT_EQ(r.where.non_manifold_vertices.size(), 1u);
    EXPECT_EQ(r.where.non_manifold_vertices[0].vertices, std::vector<std::int32_t>{0});
    EXPECT_EQ(r.where.non_manifold_vertices[0].at, (std::array<double, 3>{0, 0, 0}));
}

TEST(CheckTopology, LoopsTouchingAtARimVertexStaySeparate) {
    // Two square disks (fans around centres 6 and 7) sharing rim vertex 0.
    // Around vertex 0 the boundary neighbours sort as 1, 2, 3, 4 while the
    // loops are {1, 3} and {2, 4}: pairing by sorted neighbour would merge
    // them; pairing inside each fan keeps two loops.
    const Piece m = make_mesh({{0, 0, 0}, {1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, {2, 0, 0}, {1, 0, 0},
                               {-1, 0, 0}, {-2, 0, 0}},
                              {{6, 0, 1}, {6, 1, 5}, {6, 5, 3}, {6, 3, 0}, {7, 0, 2}, {7, 2, 8}, {7, 8, 4}, {7, 4, 0}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.boundary_edges, 8);
    EXPECT_EQ(r.boundary_loops, 2);
    EXPECT_EQ(r.non_manifold_vertices, 1);
    EXPECT_EQ(r.components, 1);
    EXPECT_EQ(r.euler, 9 - 16 + 8);
}

TEST(CheckTopology, ThreeTrianglesOnOneEdge) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.non_manifold_edges, 1);
    EXPECT_EQ(r.edges, 7);
    EXPECT_EQ(r.boundary_edges, 6);
    EXPECT_FALSE(r.manifold);
    EXPECT_FALSE(r.per_component[0].manifold);
    // The edge's ends are one fan each (joined across the edge): flagged
    // through the edge, not as non-manifold vertices.
    EXPECT_EQ(r.non_manifold_vertices, 0);
    ASSERT_EQ(r.where.non_manifold_edges.size(), 1u);
    EXPECT_EQ(r.where.non_manifold_edges[0].vertices, (std::vector<std::int32_t>{0, 1}));
    EXPECT_EQ(r.where.non_manifold_edges[0].at, (std::array<double, 3>{0.5, 0, 0})); // its midpoint
    EXPECT_TRUE(r.where.non_manifold_vertices.empty());
}

TEST(CheckTopology, MobiusStripIsNonOrientableWithOneBoundaryLoop) {
    const int n = 12;
    const tetiso::TopologyReport r = tetiso::check_topology(mobius(n));
    EXPECT_EQ(r.referenced_vertices, 2 * n);
    EXPECT_EQ(r.edges, 4 * n);
    EXPECT_EQ(r.euler, 0);
    EXPECT_EQ(r.boundary_edges, 2 * n);
    EXPECT_EQ(r.boundary_loops, 1); // the single boundary runs around twice
    EXPECT_TRUE(r.manifold);
    EXPECT_FALSE(r.orientable);
    EXPECT_FALSE(r.oriented);
    // Built with one orientation per quad, only the rung where the ends are
    // glued with a twist is run the same way by both of its triangles.
    EXPECT_EQ(r.misoriented_edges, 1);
    ASSERT_EQ(r.per_component.size(), 1u);
    EXPECT_FALSE(r.per_component[0].orientable);
    EXPECT_EQ(r.per_component[0].genus, 1); // one cross-cap: 2 - 0 - 1
    EXPECT_EQ(r.signatures[0], (tetiso::TopologySignature{1, 1, false}));
}

TEST(CheckTopology, OpenDiskHasOneBoundaryLoop) {
    const tetiso::TopologyReport r = tetiso::check_topology(fan(6));
    EXPECT_EQ(r.euler, 1);
    EXPECT_EQ(r.boundary_edges, 6);
    EXPECT_EQ(r.boundary_loops, 1);
    EXPECT_FALSE(r.closed);
    EXPECT_TRUE(r.manifold);
    EXPECT_TRUE(r.oriented);
    EXPECT_EQ(r.per_component[0].genus, 0);
    EXPECT_EQ(r.signatures[0], (tetiso::TopologySignature{0, 1, true}));
    // Equilateral-ish fan of 6: every triangle has 60 degree angles.
    EXPECT_NEAR(r.min_angle.min, 60.0, 1e-3);
}

TEST(CheckTopology, AnnulusHasTwoBoundaryLoops) {
    // A torus with one ring of quads removed would be a cylinder: V = nm,
    // E = 3nm - n, F = 2nm - 2n, chi = 0, b = 2, genus 0.
    const int n = 9, m = 8;
    Piece t = torus(n, m);
    // Quads of the last row (i = n-1) are the last 2m triangles.
    t.triangles.resize(t.triangles.size() - 6 * m);
    const tetiso::TopologyReport r = tetiso::check_topology(t);
    EXPECT_EQ(r.euler, 0);
    EXPECT_EQ(r.boundary_loops, 2);
    EXPECT_EQ(r.boundary_edges, 2 * m);
    EXPECT_EQ(r.per_component[0].genus, 0);
    EXPECT_EQ(r.signatures[0], (tetiso::TopologySignature{0, 2, true}));
}

TEST(CheckTopology, DegenerateTriangles) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {10, 0.05f, 0}, {5, 5, 5}},
                              {
                                  {0, 1, 3}, // right isosceles: min angle 45
                                  {0, 0, 1}, // repeated index: collapsed
                                  {0, 1, 2}, // collinear: zero area
                                  {0, 2, 4}, // a sliver: min angle about 0.29 degrees
                              });
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.collapsed_triangles, 1);
    EXPECT_EQ(r.zero_area_triangles, 1);
    EXPECT_EQ(r.degenerate_triangles, 2);
    EXPECT_EQ(r.near_degenerate_triangles, 1);
    EXPECT_EQ(r.min_angle.triangles, 2);
    EXPECT_EQ(r.min_angle.below_1, 1);
    // The sliver's smallest angle is at vertex 4, facing its shortest edge 0-2.
    const double sliver = (std::atan2(0.05, 8.0) - std::atan2(0.05, 10.0)) * 180 / std::numbers::pi;
    EXPECT_NEAR(r.min_angle.min, sliver, 1e-4);
    EXPECT_NEAR(r.min_angle.mean, (45.0 + sliver) / 2, 1e-4);
    EXPECT_NEAR(r.min_angle.p01, r.min_angle.min, 1e-9);
    EXPECT_EQ(r.referenced_vertices, 5); // vertex 5 is used by nobody
    // The collapsed triangle adds no edge: edges are 01 13 30 12 20 24 40.
    EXPECT_EQ(r.edges, 7);
    // Where: the collapsed and the collinear triangle, in triangle order,
    // each at its corners' centroid; the sliver is near-degenerate only.
    ASSERT_EQ(r.where.degenerate_triangles.size(), 2u);
    EXPECT_EQ(r.where.degenerate_triangles[0].triangle, 1);
    EXPECT_EQ(r.where.degenerate_triangles[0].vertices, (std::vector<std::int32_t>{0, 0, 1}));
    EXPECT_EQ(r.where.degenerate_triangles[1].triangle, 2);
    EXPECT_EQ(r.where.degenerate_triangles[1].vertices, (std::vector<std::int32_t>{0, 1, 2}));
    EXPECT_NEAR(r.where.degenerate_triangles[1].at[0], 1.0, 1e-12);
    EXPECT_EQ(r.where.degenerate_triangles[1].at[1], 0.0);

    tetiso::CheckOptions strict;
    strict.near_degenerate_angle_deg = 50.0;
    EXPECT_EQ(tetiso::check_topology(m, strict).near_degenerate_triangles, 2);
}

TEST(CheckTopology, ProblemSpotsStopAtTheLimitAndKeepTheFirst) {
    // 20 collinear triangles along the x axis: all of zero area; the report
    // counts all and locates the first kMaxProblemSpots, in triangle order.
    std::vector<std::array<float, 3>> points;
    std::vector<std::array<int, 3>> triangles;
    for (int i = 0; i < 22; ++i) points.push_back({static_cast<float>(i), 0, 0});
    for (int i = 0; i < 20; ++i) triangles.push_back({i, i + 1, i + 2});
    const tetiso::TopologyReport r = tetiso::check_topology(make_mesh(points, triangles));
    EXPECT_EQ(r.zero_area_triangles, 20);
    ASSERT_EQ(r.where.degenerate_triangles.size(), tetiso::kMaxProblemSpots);
    for (std::size_t k = 0; k < tetiso::kMaxProblemSpots; ++k) {
        EXPECT_EQ(r.where.degenerate_triangles[k].triangle, static_cast<std::int64_t>(k));
        EXPECT_EQ(r.where.degenerate_triangles[k].at[0], static_cast<double>(k) + 1.0);
    }
}

TEST(CheckTopology, DuplicatePositionsAreBitIdentical) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, -0.0f}},
                              {{0, 1, 2}, {3, 4, 2}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    // 3 repeats 0 and 4 repeats 1; 5 is (0, 0, -0): equal in value, not in bits.
    EXPECT_EQ(r.duplicate_positions, 2);
    // Triangles are told apart by index: {3, 4, 2} covers {0, 1, 2} in space
    // but is no duplicate triangle, and it touches {0, 1, 2} at vertex 2 only.
    EXPECT_EQ(r.duplicate_triangles, 0);
    EXPECT_EQ(r.non_manifold_vertices, 1);
}

TEST(CheckTopology, DuplicatePositionsAreLocatedByGroup) {
    // Vertices 0, 3 and 5 share one position, 1 and 4 another: two groups,
    // in the order of their first vertex, each listing its vertices.
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}, {2, 2, 2}},
                              {{0, 1, 2}, {3, 4, 6}, {5, 2, 6}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.duplicate_positions, 3);
    ASSERT_EQ(r.where.duplicate_positions.size(), 2u);
    EXPECT_EQ(r.where.duplicate_positions[0].vertices, (std::vector<std::int32_t>{0, 3, 5}));
    EXPECT_EQ(r.where.duplicate_positions[0].at, (std::array<double, 3>{0, 0, 0}));
    EXPECT_EQ(r.where.duplicate_positions[1].vertices, (std::vector<std::int32_t>{1, 4}));
    EXPECT_EQ(r.where.duplicate_positions[1].at, (std::array<double, 3>{1, 0, 0}));
    const nlohmann::json j = tetiso::to_json(r);
    EXPECT_EQ(j["where"]["duplicate_positions"].size(), 2u);
    EXPECT_EQ(j["where"]["duplicate_positions"][0]["vertices"], nlohmann::json({0, 3, 5}));
}

TEST(CheckTopology, DuplicateTriangles) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {1, 2, 0}, {2, 1, 0}});
    const tetiso::TopologyReport r = tetiso::check_topology(m);
    EXPECT_EQ(r.duplicate_triangles, 2);
    EXPECT_EQ(r.non_manifold_edges, 3);
    EXPECT_EQ(r.edges, 3);
}

TEST(CheckTopology, TriangleSoupOfATorus) {
    // Every triangle with its own three vertices: 2nm disks, each chi = 1
    // with one boundary loop, and 6nm vertices on nm distinct positions.
    const int n = 7, m = 5;
    const Piece t = torus(n, m);
    Piece soup;
    for (std::int32_t v : t.triangles) {
        soup.x.push_back(t.x[v]), soup.y.push_back(t.y[v]), soup.z.push_back(t.z[v]);
        soup.triangles.push_back(static_cast<std::int32_t>(soup.triangles.size()));
    }
    const tetiso::TopologyReport r = tetiso::check_topology(soup);
    EXPECT_EQ(r.components, 2 * n * m);
    EXPECT_EQ(r.euler, 2 * n * m);
    EXPECT_EQ(r.boundary_loops, 2 * n * m);
    EXPECT_EQ(r.duplicate_positions, 6 * n * m - n * m);
    EXPECT_EQ(r.signatures.front(), (tetiso::TopologySignature{0, 1, true}));
    EXPECT_EQ(r.signatures.back(), (tetiso::TopologySignature{0, 1, true}));
    EXPECT_FALSE(tetiso::same_signatures(r, tetiso::check_topology(t)));
}

TEST(CheckTopology, EmptyMesh) {
    const tetiso::TopologyReport r = tetiso::check_topology(Piece{});
    EXPECT_EQ(r.components, 0);
    EXPECT_EQ(r.euler, 0);
    EXPECT_TRUE(r.signatures.empty());
    EXPECT_TRUE(tetiso::to_json(r)["min_angle_deg"]["min"].is_null());
}

TEST(CheckTopology, MalformedInputThrows) {
    Piece m = tetrahedron();
    m.triangles[5] = 4;
    EXPECT_THROW(tetiso::check_topology(m), tetiso::Error);
    m = tetrahedron();
    m.triangles.pop_back();
    EXPECT_THROW(tetiso::check_topology(m), tetiso::Error);
    m = tetrahedron();
    m.y.pop_back();
    EXPECT_THROW(tetiso::check_topology(m), tetiso::Error);
    m = tetrahedron();
    m.z[2] = std::nanf("");
    EXPECT_THROW(tetiso::check_topology(m), tetiso::Error);
}

TEST(CheckTopology, JsonCarriesTheReport) {
    const nlohmann::json j = tetiso::to_json(tetiso::check_topology(append(torus(8, 6), tetrahedron(5.0f))));
    EXPECT_EQ(j["components"], 2);
    EXPECT_EQ(j["euler"], 2);
    ASSERT_EQ(j["per_component"].size(), 2u);
    EXPECT_EQ(j["per_component"][0]["genus"], 1);
    EXPECT_EQ(j["per_component"][1]["genus"], 0);
    ASSERT_EQ(j["signatures"].size(), 2u);
    EXPECT_EQ(j["signatures"][0]["genus"], 0); // sorted
    EXPECT_EQ(j["signatures"][1]["genus"], 1);
    EXPECT_EQ(j["closed"], true);
    EXPECT_TRUE(j["min_angle_deg"]["mean"].is_number());
    EXPECT_TRUE(j["where"]["degenerate_triangles"].empty());
    EXPECT_TRUE(j["where"]["non_manifold_edges"].empty());

    // A bow tie: its pinched vertex, where it is.
    const nlohmann::json bow = tetiso::to_json(
        tetiso::check_topology(make_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}})));
    ASSERT_EQ(bow["where"]["non_manifold_vertices"].size(), 1u);
    EXPECT_EQ(bow["where"]["non_manifold_vertices"][0]["vertices"], nlohmann::json::array({0}));
    EXPECT_EQ(bow["where"]["non_manifold_vertices"][0]["at"], nlohmann::json::array({0.0, 0.0, 0.0}));
    EXPECT_FALSE(bow["where"]["non_manifold_vertices"][0].contains("triangle"));
}

// ---------------------------------------------------------------- Hausdorff

Piece unit_square(float z) { return make_mesh({{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}}, {{0, 1, 2}, {0, 2, 3}}); }

TEST(Hausdorff, MeshAgainstItselfIsZero) {
    const Piece t = torus(30, 12);
    const tetiso::HausdorffReport r = tetiso::hausdorff(t, t);
    // Samples inside triangles are rounded to double: zero up to that.
    EXPECT_NEAR(r.forward, 0.0, 1e-9);
    EXPECT_NEAR(r.backward, 0.0, 1e-9);
    EXPECT_NEAR(r.mean, 0.0, 1e-12);
    EXPECT_GT(r.samples_a, static_cast<std::int64_t>(t.x.size()));
    EXPECT_NEAR(r.diagonal, std::sqrt(2.7 * 2.7 * 2 + 0.7 * 0.7), 0.05);
}

TEST(Hausdorff, ShiftedSquareIsAtItsShift) {
    const tetiso::HausdorffReport r = tetiso::hausdorff(unit_square(0.0f), unit_square(0.1f));
    EXPECT_NEAR(r.forward, 0.1, 1e-6);
    EXPECT_NEAR(r.backward, 0.1, 1e-6);
    EXPECT_NEAR(r.symmetric, 0.1, 1e-6);
    EXPECT_NEAR(r.mean, 0.1, 1e-6);
    EXPECT_NEAR(r.diagonal, std::sqrt(2.0), 1e-6);
    EXPECT_NEAR(r.relative, 0.1 / std::sqrt(2.0), 1e-6);
}

TEST(Hausdorff, SampleCountFollowsTheSpacing) {
    // Longest edge sqrt 2; spacing sqrt 2 / (3 sqrt 3) gives k = 3, so 9
    // samples per triangle plus the 4 vertices.
    tetiso::HausdorffOptions o;
    o.spacing = std::sqrt(2.0) / (3 * std::sqrt(3.0));
    const tetiso::HausdorffReport r = tetiso::hausdorff(unit_square(0.0f), unit_square(0.1f), o);
    EXPECT_EQ(r.samples_a, 4 + 2 * 9);
    EXPECT_EQ(r.samples_b, 4 + 2 * 9);
    o.max_subdivisions = 2;
    EXPECT_EQ(tetiso::hausdorff(unit_square(0.0f), unit_square(0.1f), o).samples_a, 4 + 2 * 4);
    o.max_subdivisions = 0;
    EXPECT_THROW(tetiso::hausdorff(unit_square(0.0f), unit_square(0.1f), o), tetiso::Error);
}

TEST(Hausdorff, BumpIsAsymmetric) {
    // a: a flat disk of 8 triangles; b: the same with its centre raised by
    // H. From b, the apex is H above a. From a, the farthest point is the
    // centre, at the distance from the base centre to a face plane of the
    // pyramid: H d / sqrt(H^2 + d^2), d = r cos(pi / 8) the apothem.
    const double h = 0.3, d = std::cos(std::numbers::pi / 8);
    const tetiso::HausdorffReport r = tetiso::hausdorff(fan(8), fan(8, static_cast<float>(h)));
    EXPECT_NEAR(r.backward, h, 1e-6);
    EXPECT_NEAR(r.forward, h * d / std::sqrt(h * h + d * d), 1e-5);
    EXPECT_LT(r.forward, r.backward - 0.01);
    EXPECT_EQ(r.symmetric, r.backward);
    EXPECT_NEAR(r.backward_at[2], h, 1e-6);
    EXPECT_NEAR(r.forward_at[0], 0.0, 1e-6);
}

TEST(Hausdorff, DenserSamplingFindsTheMaximumInsideATriangle) {
    // One big triangle vs a tent whose ridge is inside it: the vertices of
    // the big triangle are all on the tent, so only interior samples see the
    // gap. The estimate must be close to the true 0.2.
    const Piece flat = make_mesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}, {{0, 1, 2}});
    const Piece tent = make_mesh({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {1, 1, 0.2f}}, {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}});
    tetiso::HausdorffOptions fine;
    fine.spacing = 0.05;
    const tetiso::HausdorffReport r = tetiso::hausdorff(tent, flat, fine);
    EXPECT_NEAR(r.forward, 0.2, 1e-6); // the tent's apex is a vertex
    // Under the apex, the flat triangle is about 0.196 from the tent's
    // nearest face. One sample per triangle (the centroid, where the tent is
    // 0.133 high) misses it; fine samples get within their spacing.
    tetiso::HausdorffOptions coarse;
    coarse.spacing = 100.0;
    EXPECT_LT(tetiso::hausdorff(tent, flat, coarse).backward, 0.14);
    EXPECT_GT(r.backward, 0.19);
    EXPECT_LT(r.backward, 0.2);
}

TEST(Hausdorff, ResultDoesNotDependOnThreadCount) {
    const Piece a = torus(120, 40), b = torus(37, 13, 1.0, 0.33);
#if defined(_OPENMP)
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const nlohmann::json one = tetiso::to_json(tetiso::hausdorff(a, b));
    omp_set_num_threads(std::max(3, threads));
    const nlohmann::json many = tetiso::to_json(tetiso::hausdorff(a, b));
    omp_set_num_threads(threads);
    EXPECT_EQ(one, many);
#else
    EXPECT_EQ(tetiso::to_json(tetiso::hausdorff(a, b)), tetiso::to_json(tetiso::hausdorff(a, b)));
#endif
    // A coarse torus lies inside the fine one's tube, chords cut corners:
    // the distance is nonzero but below the minor radius difference + sag.
    const tetiso::HausdorffReport r = tetiso::hausdorff(a, b);
    EXPECT_GT(r.symmetric, 0.02);
    EXPECT_LT(r.symmetric, 0.2);
}

TEST(Hausdorff, EmptyMeshes) {
    const tetiso::HausdorffReport zero = tetiso::hausdorff(Piece{}, Piece{});
    EXPECT_EQ(zero.symmetric, 0.0);
    EXPECT_EQ(zero.samples_a, 0);
    EXPECT_THROW(tetiso::hausdorff(tetrahedron(), Piece{}), tetiso::Error);
    EXPECT_THROW(tetiso::hausdorff(Piece{}, tetrahedron()), tetiso::Error);
    Piece bad = tetrahedron();
    bad.triangles[0] = -1;
    EXPECT_THROW(tetiso::hausdorff(bad, tetrahedron()), tetiso::Error);
}

TEST(Hausdorff, JsonCarriesTheReport) {
    const nlohmann::json j = tetiso::to_json(tetiso::hausdorff(unit_square(0.0f), unit_square(0.1f)));
    EXPECT_NEAR(j["symmetric"].get<double>(), 0.1, 1e-6);
    EXPECT_EQ(j["forward_at"].size(), 3u);
    EXPECT_GT(j["samples_a"].get<int>(), 4);
}

// -------------------------------------------------------- self-intersections

TEST(SelfIntersections, CountsCrossingPairsOnly) {
    if (!tetiso::have_self_intersections()) GTEST_SKIP() << "built without CGAL";
    EXPECT_EQ(tetiso::count_self_intersections(tetrahedron()), std::optional<std::size_t>(0));
    EXPECT_EQ(tetiso::count_self_intersections(torus(20, 8)), std::optional<std::size_t>(0));
    // Two triangles crossing each other, sharing no vertex.
    const Piece cross = make_mesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {3, 3, 0.5f}},
                                  {{0, 1, 2}, {3, 4, 5}});
    EXPECT_EQ(tetiso::count_self_intersections(cross), std::optional<std::size_t>(1));
    // Two closed tetrahedra, the second's corner inside the first: each is
    // clean, but faces of one cross faces of the other.
    Piece inside = tetrahedron(0.25f);
    for (float& y : inside.y) y += 0.25f;
    for (float& z : inside.z) z += 0.25f;
    EXPECT_GT(tetiso::count_self_intersections(append(tetrahedron(), inside)).value_or(0), 0u);
    // No halfedge mesh exists for a Möbius strip without cutting it.
    EXPECT_EQ(tetiso::count_self_intersections(mobius(12)), std::nullopt);
}

TEST(SelfIntersections, PairsNameTheMeshsOwnTriangles) {
    if (!tetiso::have_self_intersections()) GTEST_SKIP() << "built without CGAL";
    // A collapsed triangle first (left out of CGAL's mesh) and a clean one
    // apart: the crossing pair is still named by the mesh's indices, 1 and 3.
    const Piece cross = make_mesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {3, 3, 0.5f},
                                   {9, 9, 9}, {10, 9, 9}, {9, 10, 9}},
                                  {{0, 0, 1}, {0, 1, 2}, {6, 7, 8}, {3, 4, 5}});
    const auto pairs = tetiso::find_self_intersections(cross);
    ASSERT_TRUE(pairs.has_value());
    EXPECT_EQ(*pairs, (std::vector<tetiso::TrianglePair>{{1, 3}}));
    const nlohmann::json j = tetiso::to_json(*pairs, cross);
    EXPECT_EQ(j[0]["triangles"], nlohmann::json({1, 3}));
    EXPECT_NEAR(j[0]["at"][0].get<double>(), 2.0 / 3.0, 1e-6);
    EXPECT_EQ(tetiso::find_self_intersections(mobius(12)), std::nullopt);
}

TEST(SelfIntersections, WithoutCgalTheAnswerIsEmpty) {
    if (tetiso::have_self_intersections()) GTEST_SKIP() << "built with CGAL";
    EXPECT_EQ(tetiso::count_self_intersections(tetrahedron()), std::nullopt);
}

// ------------------------------------------------------------------ contract

// The clause lines of a mesh, by their leading words.
std::vector<std::string> clauses(const Piece& m, const tetiso::TopologyReport* reference = nullptr) {
    const auto crossings =
        tetiso::have_self_intersections() ? tetiso::find_self_intersections(m) : std::nullopt;
    std::vector<std::string> out;
    for (const std::string& line : tetiso::contract_violations(m, tetiso::check_topology(m), crossings, reference))
        out.push_back(line.substr(0, line.find(':')));
    return out;
}

TEST(Contract, CleanSurfacesPass) {
    EXPECT_TRUE(clauses(tetrahedron()).empty());
    EXPECT_TRUE(clauses(torus(20, 8)).empty());
    EXPECT_TRUE(clauses(fan(6)).empty()); // a boundary is no violation
    const tetiso::TopologyReport itself = tetiso::check_topology(torus(20, 8));
    EXPECT_TRUE(clauses(torus(20, 8), &itself).empty());
}

TEST(Contract, EachViolatedClauseIsOneLine) {
    using Lines = std::vector<std::string>;
    // Zero area: three collinear corners.
    EXPECT_EQ(clauses(make_mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}})), Lines{"degenerate triangles"});
    // Two vertices at one position (two triangles meeting there would also
    // intersect: the second is left unreferenced).
    EXPECT_EQ(clauses(make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}}, {{0, 1, 2}})),
              Lines{"duplicate positions"});
    EXPECT_EQ(clauses(make_mesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}})),
              Lines{"non-manifold"});
    Piece flipped = tetrahedron();
    std::swap(flipped.triangles[10], flipped.triangles[11]);
    EXPECT_EQ(clauses(flipped), Lines{"orientation"});
    const tetiso::TopologyReport sphere = tetiso::check_topology(tetrahedron());
    EXPECT_EQ(clauses(torus(20, 8), &sphere), Lines{"signatures"});
    if (tetiso::have_self_intersections()) {
        const Piece cross = make_mesh({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5f, 0.5f, -1}, {0.5f, 0.5f, 1}, {3, 3, 0.5f}},
                                      {{0, 1, 2}, {3, 4, 5}});
        EXPECT_EQ(clauses(cross), Lines{"self-intersections"});
    }
}

TEST(Contract, LinesNameTheCountsAndTheFirstPlace) {
    const Piece m = make_mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}}, {{0, 1, 3}, {1, 0, 2}});
    const std::vector<std::string> lines = tetiso::contract_violations(m, tetiso::check_topology(m), std::nullopt);
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(lines[0], "degenerate triangles: 1 (0 collapsed, 1 of zero area); the first is triangle 1 at (1, 0, 0)");
    const tetiso::TopologyReport sphere = tetiso::check_topology(tetrahedron());
    const std::vector<std::string> signature =
        tetiso::contract_violations(torus(20, 8), tetiso::check_topology(torus(20, 8)), std::nullopt, &sphere);
    ASSERT_EQ(signature.size(), 1u);
    EXPECT_EQ(signature[0], "signatures: the components are 1 × (genus 1, 0 boundary loops), the reference's "
                            "1 × (genus 0, 0 boundary loops)");
}

} // namespace
