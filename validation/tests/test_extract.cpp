// Marching tetrahedra: closed surfaces of the right topology and size, every
// vertex on its mesh edge at the level, pieces of any decomposition fitting
// together exactly, and output independent of the thread count. Built again
// for the GPU (test_extract_gpu): every extraction here then runs on both
// devices, which must give the same bytes and errors (extract_under_test.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>

#include "extract_under_test.hpp"
#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/device.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

using test::extract_under_test;
using test::lattice_surface;
using test::error_of;

TEST(Extract, SphereIsOneClosedOrientedGenusZeroComponentOfTheRightArea) {
    const Piece sphere = lattice_surface(100, 1, "sphere");
    const TopologyReport report = check_topology(sphere);
    EXPECT_EQ(report.components, 1);
    EXPECT_EQ(report.euler, 2);
    EXPECT_TRUE(report.closed);
    EXPECT_TRUE(report.manifold);
    EXPECT_TRUE(report.oriented);
    EXPECT_EQ(report.non_manifold_edges, 0);
    const double radius = 2.0;
    EXPECT_NEAR(test::area(sphere), 4 * std::numbers::pi * radius * radius, 0.01 * 4 * std::numbers::pi * radius * radius);
    // Normals towards increasing distance from the centre: outwards.
    EXPECT_NEAR(test::signed_volume(sphere), 4.0 / 3.0 * std::numbers::pi * radius * radius * radius,
                0.01 * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius);
}

TEST(Extract, TorusHasEulerCharacteristicZero) {
    const Piece torus = lattice_surface(60, 1, "torus");
    const TopologyReport report = check_topology(torus);
    EXPECT_EQ(report.components, 1);
    EXPECT_EQ(report.euler, 0);
    EXPECT_TRUE(report.closed);
    EXPECT_TRUE(report.manifold);
    EXPECT_TRUE(report.oriented);
    ASSERT_EQ(report.per_component.size(), 1u);
    EXPECT_EQ(report.per_component[0].genus, 1);
}

TEST(Extract, OpenSurfacesAreManifoldAndOriented) {
    for (const char* field : {"gyroid", "paper"}) {
        const TopologyReport report = check_topology(lattice_surface(40, 1, field));
        EXPECT_TRUE(report.manifold) << field;
        EXPECT_TRUE(report.oriented) << field;
        EXPECT_GT(report.boundary_loops, 0) << field << " is cut open by the cube's faces";
    }
}

TEST(Extract, EveryVertexLiesOnItsEdgeWhereTheLinearFieldEqualsTheLevel) {
    const Lattice lattice(30);
    const auto field = make_field("paper");
    const Piece surface = lattice_surface(30, 1, "paper");
    ASSERT_GT(surface.vertex_count(), 0u);
    for (std::size_t v = 0; v < surface.vertex_count(); ++v) {
        const GlobalId ends[2] = {edge_key_low(surface.key[v]), edge_key_high(surface.key[v])};
        double p[2][3];
        float f[2];
        for (int e = 0; e < 2; ++e) {
            const auto ijk = lattice.node_index(ends[e]);
            for (int axis = 0; axis < 3; ++axis) p[e][axis] = lattice.coordinate(ijk[static_cast<std::size_t>(axis)]);
            field->evaluate(&p[e][0], &p[e][1], &p[e][2], 1, &f[e]);
        }
        // A mesh edge joins lattice neighbours, and the field crosses the level on it.
        for (int axis = 0; axis < 3; ++axis) ASSERT_LE(std::abs(p[1][axis] - p[0][axis]), lattice.spacing() * 1.0001);
        ASSERT_NE(f[0] >= 0.5f, f[1] >= 0.5f);
        const double q[3] = {surface.x[v], surface.y[v], surface.z[v]};
        const double d[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const double length2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double t = ((q[0] - p[0][0]) * d[0] + (q[1] - p[0][1]) * d[1] + (q[2] - p[0][2]) * d[2]) / length2;
        ASSERT_GE(t, -1e-6);
        ASSERT_LE(t, 1 + 1e-6);
        double off = 0;
        for (int axis = 0; axis < 3; ++axis) off += std::pow(q[axis] - (p[0][axis] + t * d[axis]), 2);
        ASSERT_LE(std::sqrt(off), 1e-5) << "vertex " << v << " is off its edge";
        const double interpolated = f[0] + t * (f[1] - f[0]);
        ASSERT_NEAR(interpolated, 0.5, 1e-4 * std::abs(f[1] - f[0]) + 1e-5) << "vertex " << v;
    }
}

class Decomposed : public ::testing::TestWithParam<int> {};

TEST_P(Decomposed, PiecesCombineToTheSingleDomainSurfaceExactly) {
    const Piece whole = lattice_surface(41, 1, "paper");
    const Piece combined = lattice_surface(41, GetParam(), "paper");
    EXPECT_TRUE(test::same_surface(whole, combined));
    EXPECT_EQ(whole.triangle_count(), combined.triangle_count());
}

INSTANTIATE_TEST_SUITE_P(Domains, Decomposed, ::testing::Values(2, 8, 27, 63));

TEST(Extract, LockedVerticesAreExactlyThoseOnSharedEdges) {
    const Lattice lattice(25);
    const Decomposition decomposition(lattice, 8);
    const auto field = make_field("gyroid");
    std::size_t locked = 0;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const Piece piece = extract_under_test(decomposition.make_domain(d, *field), 0.0f);
        EXPECT_EQ(piece.domains, std::vector<int>{d});
        for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
            const auto holders = decomposition.domains_of_edge(edge_key_low(piece.key[v]), edge_key_high(piece.key[v]));
            ASSERT_EQ((piece.flags[v] & kLocked) != 0, holders.size() > 1) << "domain " << d << " vertex " << v;
            locked += piece.flags[v] & kLocked;
        }
    }
    EXPECT_GT(locked, 0u);
    const Piece combined = lattice_surface(25, 8, "gyroid");
    EXPECT_TRUE(std::none_of(combined.flags.begin(), combined.flags.end(), [](std::uint8_t f) { return f & kLocked; }));
}

// The combined surface is the same arrays for any number of domains, as the
// README promises of `tetiso extract`: the triangles used to come in the
// domains' order (the same set, the same orientation, other bytes).
TEST(Extract, CombinedSurfaceIsTheSameBytesForAnyDomainCount) {
    for (const char* field : {"paper", "gyroid"}) {
        const Piece one = lattice_surface(40, 1, field);
        for (const int domains : {8, 27}) {
            const Piece many = lattice_surface(40, domains, field);
            EXPECT_EQ(many.key, one.key) << field << ", " << domains << " domains";
            EXPECT_EQ(many.x, one.x) << field << ", " << domains << " domains";
            EXPECT_EQ(many.flags, one.flags) << field << ", " << domains << " domains";
            EXPECT_EQ(many.triangles, one.triangles) << field << ", " << domains << " domains";
        }
    }
}

TEST(Extract, SurfaceThroughMeshNodesIsConsistentAndManifold) {
    // x = 2.5 at level 0 passes through a whole plane of nodes (i = 5 of 11):
    // every domain must classify them alike.
    const Piece whole = lattice_surface(11, 1, "x-2.5", 0.0);
    for (const int domains : {2, 8, 27, 63}) EXPECT_TRUE(test::same_surface(whole, lattice_surface(11, domains, "x-2.5", 0.0)));
    const TopologyReport report = check_topology(whole);
    EXPECT_EQ(report.non_manifold_edges, 0);
    EXPECT_EQ(report.non_manifold_vertices, 0);
    EXPECT_TRUE(report.oriented);
    EXPECT_EQ(report.components, 1);
    EXPECT_EQ(report.boundary_loops, 1);
    EXPECT_EQ(report.euler, 1); // a disk
    // The nodes of the plane count as above: each vertex is a crossing kept
    // off its node on the side below (extract_rules.hpp, node_clearance: 32
    // units of 2^-23 of the largest coordinate, here at most 5), so that the
    // vertices of different edges through one node have different positions.
    const float clearance = 32.0f * 0x1p-23f * 5.0f;
    for (std::size_t v = 0; v < whole.vertex_count(); ++v) {
        ASSERT_LT(whole.x[v], 2.5f);
        ASSERT_GE(whole.x[v], 2.5f - clearance);
    }
    EXPECT_EQ(report.duplicate_positions, 0);
    EXPECT_EQ(report.zero_area_triangles, 0);
}

TEST(Extract, OutputDoesNotDependOnThreadCount) {
#ifndef _OPENMP
    GTEST_SKIP() << "built without OpenMP: one thread whatever is asked";
#endif
    const Lattice lattice(60);
    const Decomposition one(lattice, 1);
    const Domain domain = one.make_domain(0, *make_field("paper"));
    const Piece serial = extract_under_test(domain, 0.5f, ExtractOptions{1});
    const Piece parallel = extract_under_test(domain, 0.5f, ExtractOptions{2});
    EXPECT_EQ(serial.key, parallel.key);
    EXPECT_TRUE(test::same_bits(serial.x, parallel.x));
    EXPECT_TRUE(test::same_bits(serial.y, parallel.y));
    EXPECT_TRUE(test::same_bits(serial.z, parallel.z));
    EXPECT_EQ(serial.flags, parallel.flags);
    EXPECT_EQ(serial.triangles, parallel.triangles) << "triangle order must not depend on threads either";
}

TEST(Extract, UnstructuredNodeOrderGivesTheSameSurface) {
    // A general mesh numbers its nodes in any order; the piece must not care,
    // whether the buckets suffice or overflow into the sorting path.
    const Lattice lattice(16);
    const Decomposition one(lattice, 1);
    const Domain domain = one.make_domain(0, *make_field("gyroid"));
    const Piece reference = extract_under_test(domain, 0.0f);

    std::vector<std::int32_t> order(domain.node_count());
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 random(7);
    std::shuffle(order.begin(), order.end(), random);
    EXPECT_TRUE(test::same_surface(reference, extract_under_test(test::renumbered(domain, order), 0.0f)));

    // A tiny sphere around one node, numbered first: all 14 of its edges
    // cross and go into one bucket of 8.
    const auto dot = make_field("sqrt((x-2)^2+(y-2)^2+(z-2)^2)");
    const Domain small = one.make_domain(0, *dot);
    const float level = static_cast<float>(0.5 * lattice.spacing());
    const auto centre = static_cast<std::int32_t>(
        std::min_element(small.f.begin(), small.f.end()) - small.f.begin());
    std::iota(order.begin(), order.end(), 0);
    std::swap(order[0], order[static_cast<std::size_t>(centre)]);
    const Piece plain = extract_under_test(small, level);
    const Piece overflowed = extract_under_test(test::renumbered(small, order), level);
    EXPECT_EQ(plain.vertex_count(), 14u);
    EXPECT_TRUE(test::same_surface(plain, overflowed));
}

TEST(Extract, LevelOutsideTheRangeGivesAnEmptySurface) {
    const Piece empty = lattice_surface(10, 2, "sphere", 100.0);
    EXPECT_EQ(empty.triangle_count(), 0u);
    EXPECT_EQ(empty.vertex_count(), 0u);
}

// OpenMP takes any thread count; libgomp overflowed its stack at 10^5
// (SIGSEGV) and could not create 5 * 10^4. Above kMaxThreads it is an error.
TEST(Extract, ThreadCountsAboveTheLimitAreRefused) {
    const Lattice lattice(6); // Decomposition keeps a reference to it
    const Decomposition one(lattice, 1);
    const Domain domain = one.make_domain(0, *make_field("sphere"));
    EXPECT_NO_THROW(extract_under_test(domain, 2.0f, ExtractOptions{2}));
    for (const int threads : {kMaxThreads + 1, 50000, 100000}) {
        try {
            extract_under_test(domain, 2.0f, ExtractOptions{threads});
            ADD_FAILURE() << threads << " threads were accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("at most " + std::to_string(kMaxThreads)), std::string::npos) << e.what();
        }
    }
}

TEST(Extract, BadDomainsAreRefusedWithAClearError) {
    const Lattice lattice(4);
    const Decomposition one(lattice, 1);
    Domain domain = one.make_domain(0, *make_field("paper"));
    Domain nan = domain;
    nan.f[5] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(extract_under_test(nan, 0.5f), Error);
    Domain dangling = domain;
    dangling.tets[7] = static_cast<std::int32_t>(domain.node_count());
    try {
        extract_under_test(dangling, 0.5f);
        FAIL() << "a tetrahedron with a missing node was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("tetrahedron 1"), std::string::npos) << e.what();
    }
}


// Keys ascending and unique, every triangle naming three distinct vertices
// that exist: what the reduction and the seams rely on.
::testing::AssertionResult well_formed(const Piece& piece) {
    for (std::size_t v = 1; v < piece.vertex_count(); ++v)
        if (!(piece.key[v - 1] < piece.key[v])) return ::testing::AssertionFailure() << "keys out of order at " << v;
    const auto n = static_cast<std::int32_t>(piece.vertex_count());
    for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
        const std::int32_t a = piece.triangles[3 * t], b = piece.triangles[3 * t + 1], c = piece.triangles[3 * t + 2];
        if (a < 0 || b < 0 || c < 0 || a >= n || b >= n || c >= n || a == b || b == c || a == c)
            return ::testing::AssertionFailure() << "triangle " << t << " is not three vertices";
    }
    return ::testing::AssertionSuccess();
}

// The lattice's connectivity with random values, a tenth of them exactly at
// the level: every case pattern and every tie.
TEST(Extract, RandomValuesGiveWellFormedPieces) {
    const Lattice lattice(24);
    const Decomposition one(lattice, 1);
    Domain domain = one.make_domain(0, *make_field("paper"));
    for (unsigned seed = 1; seed <= 5; ++seed) {
        std::mt19937 random(seed);
        std::uniform_real_distribution<float> value(-1.0f, 1.0f);
        const float level = seed == 1 ? 0.0f : value(random) * 0.5f;
        for (float& f : domain.f) f = random() % 10 == 0 ? level : value(random);
        const Piece piece = extract_under_test(domain, level);
        EXPECT_GT(piece.triangle_count(), 0u) << "seed " << seed;
        EXPECT_TRUE(well_formed(piece)) << "seed " << seed;
    }
}

// The unstructured cube mesh in 8 domains by the octant of each
// tetrahedron's centroid: interface vertices are locked through the shared
// edge lists, and local numbering is not global.
TEST(Extract, UnstructuredDomainsLockTheirSharedEdges) {
    const auto field = make_field("sphere");
    Domain mesh = read_tetgen(TetgenSource{std::filesystem::path(TETISO_MESHES_DIR) / "cube.1", std::nullopt,
                                           field.get()});
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) {
        int octant = 0;
        for (int axis = 0; axis < 3; ++axis) {
            double centre = 0.0;
            for (int k = 0; k < 4; ++k) {
                const auto v = static_cast<std::size_t>(mesh.tets[4 * t + static_cast<std::size_t>(k)]);
                centre += axis == 0 ? mesh.x[v] : (axis == 1 ? mesh.y[v] : mesh.z[v]);
            }
            octant |= (centre / 4 > 2.5 ? 1 : 0) << axis;
        }
        part[t] = octant;
    }
    const MeshPartition partition(std::move(mesh), part, "octants");
    std::size_t locked = 0;
    for (const float level : {2.0f, 1.0f}) {
        for (int d = 0; d < partition.domain_count(); ++d) {
            const Piece piece = extract_under_test(partition.make_domain(d), level);
            EXPECT_TRUE(well_formed(piece)) << "domain " << d << ", level " << level;
            locked += static_cast<std::size_t>(std::count(piece.flags.begin(), piece.flags.end(), kLocked));
        }
    }
    EXPECT_GT(locked, 0u); // the interfaces were crossed
}

// The element a bad domain's error names: the last node with a value that is
// not finite, the first tetrahedron naming a node that does not exist.
TEST(Extract, BadDomainsNameTheirElement) {
    const Lattice lattice(6);
    const Decomposition two(lattice, 2);
    const Domain domain = two.make_domain(1, *make_field("paper"));
    Domain nan = domain;
    nan.f[5] = std::numeric_limits<float>::quiet_NaN();
    nan.f[9] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(error_of([&] { extract_under_test(nan, 0.5f); }),
              "domain 1: node " + std::to_string(domain.gid[9]) + " has a field value that is not finite");
    Domain dangling = domain;
    dangling.tets[4 * 30 + 2] = static_cast<std::int32_t>(domain.node_count());
    dangling.tets[4 * 77 + 1] = -3;
    EXPECT_EQ(error_of([&] { extract_under_test(dangling, 0.5f); }),
              "domain 1: tetrahedron 30 refers to a node that does not exist");
    Domain ragged = domain;
    ragged.f.pop_back();
    EXPECT_EQ(error_of([&] { extract_under_test(ragged, 0.5f); }), "domain 1: node arrays differ in length");
    EXPECT_EQ(error_of([&] { extract_under_test(domain, std::numeric_limits<float>::infinity()); }),
              "isosurface level is not a finite number");
    // A failed call leaves the extraction usable.
    EXPECT_TRUE(well_formed(extract_under_test(domain, 0.5f)));
}

TEST(Extract, EmptyDomainsAndLevelsOutsideTheRangeGiveEmptyPieces) {
    const Lattice lattice(8);
    const Decomposition one(lattice, 1);
    const Domain domain = one.make_domain(0, *make_field("sphere"));
    const Piece outside = extract_under_test(domain, 100.0f);
    EXPECT_EQ(outside.vertex_count(), 0u);
    EXPECT_EQ(outside.triangle_count(), 0u);
    Domain no_tets = domain;
    no_tets.tets.clear();
    EXPECT_EQ(extract_under_test(no_tets, 2.0f).vertex_count(), 0u);
    EXPECT_EQ(extract_under_test(Domain{}, 2.0f).vertex_count(), 0u);
}

#ifndef TETISO_TEST_GPU
// What CI sees: no device, and a clear error for whoever asks for one.
TEST(Extract, WithoutAGpuAskingForOneIsAClearError) {
    const GpuInfo info = gpu_info();
    if (info.available) GTEST_SKIP() << "a GPU is present: " << info.description;
    EXPECT_FALSE(info.description.empty());
    const std::string message = error_of([] { Device::cuda(); });
    EXPECT_EQ(message.rfind("GPU: ", 0), 0u) << message;
}
#endif

} // namespace
} // namespace tetiso
