// Tests of the checker's geometry (check.hpp): the Hausdorff estimate, the
// self-intersections and the contract's gate, on tiny meshes built in code
// (check_meshes.hpp) whose answers follow from how they were laid out.
#include <gtest/gtest.h>

#include "check_meshes.hpp"

namespace {

using namespace tetiso::check_meshes;

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
