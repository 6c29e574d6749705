// Tests of the topology checker (check.hpp) on
// tiny meshes built here, whose answers follow from V - E + F and from how
// the triangles were laid out, not from running the checker.
#include <gtest/gtest.h>

#include "check_meshes.hpp"

namespace {

using namespace tetiso::check_meshes;


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

} // namespace
