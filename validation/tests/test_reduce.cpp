// Reduction (core/src/reduce/): the reduced surface keeps the topology of
// every component, stays a consistently oriented manifold without degenerate
// triangles, keeps locked vertices bit for bit and border vertices on the
// border, stays within half a lattice spacing of the input, and does not
// depend on the thread count. Tiny exact meshes built here probe the branches
// (needles, zero-length edges, valence-3 vertices, flips, thin handles,
// minimal components); test_reduce_surfaces.cpp takes whole surfaces. Built a
// second time as test_reduce_gpu, where every reduction also runs on the GPU
// and must give the same bytes (reduce_under_test.hpp).

#include <gtest/gtest.h>

#include "reduce_cases.hpp"

namespace tetiso {
namespace {

using namespace reduce_cases;

// ---------------------------------------------------------------------------
// Options and bad input.

TEST(Reduce, RejectsPhiOutsideItsRangeAndOtherBadOptions) {
    const Piece sphere = icosphere(1);
    for (const double phi : {0.0, -0.5, 1.01, std::nan("")}) {
        ReduceOptions o;
        o.phi = phi;
        EXPECT_THROW(reduce_under_test(sphere, o), Error) << phi;
    }
    ReduceOptions o;
    o.phi = 1.0;
    EXPECT_NO_THROW(reduce_under_test(sphere, o));
    o.threads = -1;
    EXPECT_THROW(reduce_under_test(sphere, o), Error);
    o = {};
    o.min_angle_degrees = 45;
    EXPECT_THROW(reduce_under_test(sphere, o), Error);
}

std::string error_of(const Piece& p) {
    try {
        reduce_under_test(p);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST(Reduce, NamesTheEdgeOrVertexOfNonManifoldInput) {
    Builder three;
    for (int i = 0; i < 5; ++i) three.add(i, i * i, i % 2);
    three.tri(0, 1, 2);
    three.tri(1, 0, 3);
    three.tri(0, 1, 4);
    const std::string m3 = error_of(three.piece);
    EXPECT_NE(m3.find("edge (key 0, key 1) has 3 triangles"), std::string::npos) << m3;

    Builder same;
    for (int i = 0; i < 4; ++i) same.add(i, i * i, 0);
    same.tri(0, 1, 2);
    same.tri(0, 1, 3);
    const std::string md = error_of(same.piece);
    EXPECT_NE(md.find("edge (key 0, key 1)"), std::string::npos) << md;
    EXPECT_NE(md.find("same direction"), std::string::npos) << md;

    Builder bowtie;
    for (int i = 0; i < 5; ++i) bowtie.add(i, i * i, 0);
    bowtie.tri(0, 1, 2);
    bowtie.tri(0, 3, 4);
    const std::string mb = error_of(bowtie.piece);
    EXPECT_NE(mb.find("vertex (key 0)"), std::string::npos) << mb;

    Builder repeat;
    for (int i = 0; i < 3; ++i) repeat.add(i, 0, 0);
    repeat.tri(0, 1, 1);
    EXPECT_THROW(reduce_under_test(repeat.piece), Error);

    Piece unsorted = icosphere(0);
    std::swap(unsorted.key[0], unsorted.key[1]);
    EXPECT_THROW(reduce_under_test(unsorted), Error);
}

// ---------------------------------------------------------------------------
// Small exact cases.

TEST(Reduce, MinimalComponentsStay) {
    // A tetrahedron, a single triangle: nothing can go.
    Builder tet;
    tet.add(0, 0, 0), tet.add(1, 0, 0), tet.add(0, 1, 0), tet.add(0, 0, 1);
    tet.tri(0, 2, 1), tet.tri(0, 1, 3), tet.tri(0, 3, 2), tet.tri(1, 2, 3);
    Builder one;
    one.add(0, 0, 0), one.add(1, 0, 0), one.add(0, 1, 0);
    one.tri(0, 1, 2);
    ReduceOptions any;
    any.phi = 1e-6;
    any.max_normal_turn_degrees = 89;
    for (const Piece& p : {tet.piece, one.piece}) {
        const Piece out = reduce_under_test(p, any);
        EXPECT_EQ(out.triangle_count(), p.triangle_count());
        expect_valid(p, out, "minimal");
    }
    // An icosahedron reduced as far as the options allow stays a closed
    // genus-0 surface of at least 4 vertices.
    const Piece ico = icosphere(0);
    const Piece out = reduce_under_test(ico, any);
    EXPECT_GE(out.vertex_count(), 4u);
    EXPECT_LT(out.triangle_count(), ico.triangle_count());
    expect_valid(ico, out, "icosahedron");
}

TEST(Reduce, PhiGatesEveryCollapseOutsideTheShortAndValenceThreeBranches) {
    // Φ is computed only when the selection reaches an edge, after the edge
    // was ranked. On an icosahedron the normals of adjacent faces are 41.8°
    // apart, so no leaf is flatter than cos 41.8° = 0.745 < Φ* = 0.9; its
    // edges are equally long (no short edge), its vertices have valence 5
    // and its angles are 60° (no flip gains). The selection reaches edges
    // and must drop them all, leaving the surface as it was.
    const Piece ico = icosphere(0);
    ReduceOptions o;
    o.max_normal_turn_degrees = 89;
    ReduceReport report;
    const Piece out = reduce_under_test(ico, o, &report);
    EXPECT_TRUE(tetiso::test::same_surface(ico, out));
    ASSERT_FALSE(report.rounds.empty());
    EXPECT_EQ(report.rounds[0].candidates, 30u); // every edge could collapse but for Φ
    EXPECT_GT(report.rounds[0].evaluated, 0u);
    EXPECT_EQ(report.rounds[0].collapses, 0u);
    EXPECT_EQ(report.rounds[0].flips, 0u);
}

TEST(Reduce, ReportRoundsAccountForEveryVertexAndTriangle) {
    // Each collapse removes one vertex and the one or two faces of its edge
    // (one on the border); a flip removes nothing. Operations are at least
    // path length 2 apart, so their survivors and flip corners are distinct
    // vertices whose fans change.
    struct Surface {
        const char* name;
        Piece piece;
        bool closed;
    };
    for (const Surface& c : {Surface{"open grid", grid(30), false},
                             Surface{"closed torus", lattice_surface(40, 1, "torus"), true}}) {
        ReduceReport report;
        const Piece out = reduce_under_test(c.piece, {}, &report);
        const auto& rounds = report.rounds;
        ASSERT_GE(rounds.size(), 2u) << c.name;
        EXPECT_EQ(rounds.front().vertices, c.piece.vertex_count()) << c.name;
        EXPECT_EQ(rounds.front().triangles, c.piece.triangle_count()) << c.name;
        std::size_t collapses = 0;
        double round_seconds = 0.0;
        for (std::size_t r = 0; r < rounds.size(); ++r) {
            const ReduceRound& x = rounds[r];
            collapses += x.collapses;
            EXPECT_GE(x.seconds, 0.0) << c.name << " round " << r;
            round_seconds += x.seconds;
            const std::size_t vertices_after = r + 1 < rounds.size() ? rounds[r + 1].vertices : out.vertex_count();
            const std::size_t triangles_after =
                r + 1 < rounds.size() ? rounds[r + 1].triangles : out.triangle_count();
            EXPECT_EQ(vertices_after, x.vertices - x.collapses) << c.name << " round " << r;
            const std::size_t removed = x.triangles - triangles_after;
            if (c.closed) {
                EXPECT_EQ(removed, 2 * x.collapses) << c.name << " round " << r;
            }
            EXPECT_GE(removed, x.collapses) << c.name << " round " << r;
            EXPECT_LE(removed, 2 * x.collapses) << c.name << " round " << r;
            EXPECT_GE(x.changed_vertices, x.collapses + 4 * x.flips) << c.name << " round " << r;
            EXPECT_LE(x.changed_vertices, x.vertices - x.collapses) << c.name << " round " << r;
        }
        EXPECT_GT(collapses, 0u) << c.name;
        // The rounds are parts of the call (which adds the input checks).
        EXPECT_LE(round_seconds, report.seconds) << c.name;
    }
}

TEST(Reduce, FlatDiskCollapsesAndItsBorderStaysOnTheSquareWithItsCorners) {
    const Piece in = grid(40);
    ReduceReport report;
    const Piece out = reduce_under_test(in, {}, &report);
    expect_valid(in, out, "grid");
    EXPECT_EQ(report.triangles_in, in.triangle_count());
    EXPECT_EQ(report.triangles_out, out.triangle_count());
    EXPECT_LT(out.triangle_count() * 20, in.triangle_count());
    EXPECT_NEAR(test::area(out), 1600.0, 1e-2);
    // Border vertices slide along the border only: every vertex on the
    // border of the output lies on the square's boundary, and the corners stay.
    const TopologyReport r = check_topology(out);
    EXPECT_EQ(r.boundary_loops, 1);
    std::set<std::pair<float, float>> corners;
    for (std::size_t v = 0; v < out.vertex_count(); ++v) {
        EXPECT_EQ(out.z[v], 0.0f);
        const bool on_side = out.x[v] == 0.0f || out.x[v] == 40.0f || out.y[v] == 0.0f || out.y[v] == 40.0f;
        if (on_side) corners.insert({out.x[v], out.y[v]});
    }
    for (const auto& c : {std::pair{0.0f, 0.0f}, {40.0f, 0.0f}, {0.0f, 40.0f}, {40.0f, 40.0f}})
        EXPECT_TRUE(corners.count(c)) << c.first << ", " << c.second;
    // Every output border edge lies on a side of the square.
    std::map<std::pair<int, int>, int> edges;
    for (std::size_t t = 0; t < out.triangle_count(); ++t)
        for (int k = 0; k < 3; ++k)
            ++edges[std::minmax(out.triangles[3 * t + static_cast<std::size_t>(k)], out.triangles[3 * t + static_cast<std::size_t>((k + 1) % 3)])];
    for (const auto& [e, n] : edges) {
        if (n != 1) continue;
        const auto a = static_cast<std::size_t>(e.first), b = static_cast<std::size_t>(e.second);
        const bool same_side = (out.x[a] == out.x[b] && (out.x[a] == 0.0f || out.x[a] == 40.0f)) ||
                               (out.y[a] == out.y[b] && (out.y[a] == 0.0f || out.y[a] == 40.0f));
        EXPECT_TRUE(same_side) << out.x[a] << "," << out.y[a] << " - " << out.x[b] << "," << out.y[b];
    }
}

TEST(Reduce, LockedVerticesNeverMoveNorGo) {
    Piece in = grid(30);
    // Lock the border of the left half and a scattered set inside.
    for (std::size_t v = 0; v < in.vertex_count(); ++v) {
        const bool left_border = in.x[v] == 0.0f || ((in.y[v] == 0.0f || in.y[v] == 30.0f) && in.x[v] <= 15.0f);
        if (left_border || v % 37 == 5) in.flags[v] = kLocked;
    }
    // Bend it so collapses move vertices.
    for (std::size_t v = 0; v < in.vertex_count(); ++v) in.z[v] = static_cast<float>(0.02 * in.x[v] * in.x[v]);
    ReduceOptions o;
    o.phi = 0.8;
    const Piece out = reduce_under_test(in, o);
    expect_valid(in, out, "locked grid");
    EXPECT_LT(out.triangle_count() * 3, in.triangle_count());
}

// Edges between two locked vertices, as key pairs.
std::set<std::pair<EdgeKey, EdgeKey>> locked_edges(const Piece& p) {
    std::set<std::pair<EdgeKey, EdgeKey>> out;
    for (std::size_t t = 0; t < p.triangle_count(); ++t)
        for (std::size_t k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(p.triangles[3 * t + k]);
            const auto b = static_cast<std::size_t>(p.triangles[3 * t + (k + 1) % 3]);
            if ((p.flags[a] & kLocked) && (p.flags[b] & kLocked)) out.insert(std::minmax(p.key[a], p.key[b]));
        }
    return out;
}

TEST(Reduce, NoNewEdgeJoinsTwoLockedVertices) {
    // Two pieces that share locked vertices must not both grow the same chord
    // between them: merged by key, it would have four triangles (a crash seen
    // at N = 300, 63 domains). So no reduction may create a locked-locked edge.
    Piece in = grid(12);
    for (std::size_t v = 0; v < in.vertex_count(); ++v) {
        const std::size_t i = v % 13, j = v / 13;
        if (i == 0 || j == 0 || i == 12 || j == 12) in.flags[v] = kLocked;
    }
    const Piece out = reduce_under_test(in);
    expect_valid(in, out, "grid with a locked border");
    EXPECT_LT(out.triangle_count(), in.triangle_count() / 4);
    const auto before = locked_edges(in), after = locked_edges(out);
    for (const auto& e : after) EXPECT_TRUE(before.count(e)) << "new edge " << e.first << "-" << e.second;
}

TEST(Reduce, ZeroLengthEdgesAndNeedlesAreCleanedUp) {
    // A flat grid whose rows come in coincident pairs: every second strip of
    // triangles has zero area, half of its edges zero length. A few vertices
    // are locked so not everything can simply vanish.
    const int n = 20;
    Builder b;
    for (int j = 0; j <= 2 * n + 1; ++j)
        for (int i = 0; i <= n; ++i) b.add(i, j / 2, 0.0);
    auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
    for (int j = 0; j <= 2 * n; ++j)
        for (int i = 0; i < n; ++i) {
            b.tri(id(i, j), id(i + 1, j), id(i + 1, j + 1));
            b.tri(id(i, j), id(i + 1, j + 1), id(i, j + 1));
        }
    // Needles: pull a few vertices almost onto a neighbour.
    for (int k = 0; k < 10; ++k) b.piece.x[static_cast<std::size_t>(id(3 + k, 2 * (k + 3)))] += 0.999f;
    ASSERT_GT(check_topology(b.piece).degenerate_triangles, 0);
    ReduceOptions o;
    o.phi = 1.0; // only the short-edge, valence-3 and flip branches act
    const Piece out = reduce_under_test(b.piece, o);
    expect_valid(b.piece, out, "doubled rows");
    const TopologyReport r = check_topology(out);
    EXPECT_EQ(r.near_degenerate_triangles, 0);
    EXPECT_NEAR(test::area(out), test::area(b.piece), 1e-3);
}

TEST(Reduce, ValenceThreeVerticesAreRemoved) {
    // An icosphere with a vertex added at the centroid of every other
    // triangle (in its plane, so removing it is exact).
    const Piece base = icosphere(3);
    Builder b;
    b.piece = base;
    b.piece.triangles.clear();
    for (std::size_t t = 0; t < base.triangle_count(); ++t) {
        const auto a = base.triangles[3 * t], c = base.triangles[3 * t + 1], d = base.triangles[3 * t + 2];
        if (t % 2) {
            b.tri(a, c, d);
            continue;
        }
        const auto i = static_cast<std::size_t>(a), j = static_cast<std::size_t>(c), k = static_cast<std::size_t>(d);
        const auto m = b.add((base.x[i] + base.x[j] + base.x[k]) / 3.0, (base.y[i] + base.y[j] + base.y[k]) / 3.0,
                             (base.z[i] + base.z[j] + base.z[k]) / 3.0);
        b.tri(a, c, m), b.tri(c, d, m), b.tri(d, a, m);
    }
    ASSERT_GT(interior_valence3(b.piece), 0u);
    ReduceOptions o;
    o.phi = 1.0;
    o.flips = false;
    const Piece out = reduce_under_test(b.piece, o);
    expect_valid(b.piece, out, "split icosphere");
    EXPECT_EQ(interior_valence3(out), 0u);
    EXPECT_EQ(out.triangle_count(), base.triangle_count());
}

TEST(Reduce, NeedlesAroundATinyClusterGoWithIt) {
    // Where the surface passes near a mesh node, marching tetrahedra leave a
    // cluster of vertices far closer to each other than to the rest: here a
    // grid vertex becomes a triangle (u, w, x) of size eps around a vertex d
    // of valence 3, raised by 2 eps (a tent, as such clusters are seldom
    // flat), with a needle on each side of the triangle. No needle's short
    // edge can collapse while d is there (u and w share x through d: the
    // link condition fails), so d must go first. Two things kept it: the
    // normal turn of the face that replaces d's three, a turn that only
    // measures the tent's height, and the quality floor, which the needles
    // beside the survivor (u) failed by rounding when re-judged though they
    // do not move. Each cluster should end as the grid vertex it replaced.
    const int n = 24;
    Builder b;
    auto is_cluster = [](int i, int j) { return i % 3 == 0 && j % 3 == 0 && i > 0 && j > 0 && i < n && j < n; };
    std::vector<std::int32_t> grid_vertex((n + 1) * (n + 1), -1); // -1: the cluster's place
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            if (!is_cluster(i, j)) grid_vertex[static_cast<std::size_t>(j * (n + 1) + i)] = b.add(i, j, 0.0);
    auto id = [&](int i, int j) { return grid_vertex[static_cast<std::size_t>(j * (n + 1) + i)]; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::array<std::array<std::int32_t, 3>, 2> square = {{{id(i, j), id(i + 1, j), id(i + 1, j + 1)},
                                                                        {id(i, j), id(i + 1, j + 1), id(i, j + 1)}}};
            for (const auto& t : square)
                if (t[0] >= 0 && t[1] >= 0 && t[2] >= 0) b.tri(t[0], t[1], t[2]);
        }
    int clusters = 0;
    for (int j = 1; j < n; ++j)
        for (int i = 1; i < n; ++i) {
            if (!is_cluster(i, j)) continue;
            // Neighbours of (i, j) counter-clockwise (the grid's diagonals
            // run from (i, j) to (i + 1, j + 1)); u, w, x sit between them.
            const std::int32_t nb[6] = {id(i + 1, j), id(i + 1, j + 1), id(i, j + 1),
                                        id(i - 1, j), id(i - 1, j - 1), id(i, j - 1)};
            const double eps = 1e-3 * (1.0 + 0.37 * (clusters++ % 7));
            auto at = [&](double degrees) {
                const double a = degrees * std::numbers::pi / 180.0;
                return b.add(i + eps * std::cos(a), j + eps * std::sin(a), 0.0);
            };
            const std::int32_t u = at(22.5), w = at(135.0), x = at(247.5);
            const std::int32_t d = b.add(i, j, 2 * eps);
            b.tri(u, nb[0], nb[1]), b.tri(u, nb[1], w), b.tri(w, nb[1], nb[2]), b.tri(w, nb[2], nb[3]);
            b.tri(w, nb[3], x), b.tri(x, nb[3], nb[4]), b.tri(x, nb[4], nb[5]), b.tri(x, nb[5], u);
            b.tri(u, nb[5], nb[0]);
            b.tri(u, w, d), b.tri(w, x, d), b.tri(x, u, d);
        }
    ASSERT_EQ(check_topology(b.piece).near_degenerate_triangles, 3 * clusters);
    ASSERT_EQ(interior_valence3(b.piece), static_cast<std::size_t>(clusters));
    ReduceOptions o;
    o.phi = 1.0; // only the short-edge, valence-3 and flip branches act
    const Piece out = reduce_under_test(b.piece, o);
    expect_valid(b.piece, out, "clusters");
    EXPECT_EQ(check_topology(out).near_degenerate_triangles, 0);
    EXPECT_EQ(interior_valence3(out), 0u);
    EXPECT_EQ(out.triangle_count(), static_cast<std::size_t>(2 * n * n));
}

TEST(Reduce, FlipsMendTheNarrowTrianglesOfAShearedGrid) {
    // Every square split along its long diagonal: all triangles have a 4.4°
    // angle; flipping to the short diagonal raises a pair's to 8° and more.
    // Rounds without collapses end the reduction after two (paper), so only
    // the flips of two rounds happen here.
    const Piece in = grid(12, 3.0);
    ReduceOptions o;
    o.phi = 1.0;
    o.short_edge_ratio = 0.0;
    ReduceReport report;
    const Piece out = reduce_under_test(in, o, &report);
    expect_valid(in, out, "sheared grid");
    std::size_t flips = 0, collapses = 0;
    for (const auto& r : report.rounds) {
        flips += r.flips;
        collapses += r.collapses;
    }
    EXPECT_EQ(collapses, 0u);
    EXPECT_GE(flips, 20u);
    const AngleStats before = check_topology(in).min_angle, after = check_topology(out).min_angle;
    EXPECT_GE(after.min, before.min - 1e-6);
    EXPECT_GT(after.mean, before.mean + 0.5);
    EXPECT_EQ(after.triangles, before.triangles);
    EXPECT_NEAR(test::area(out), test::area(in), 1e-3);
}

TEST(Reduce, ThinHandleIsNotPinchedOff) {
    // A torus whose tube is a triangle: every ring is a non-separating
    // 3-cycle that one careless collapse would pinch.
    for (const int nv : {3, 4}) {
        const Piece in = torus(200, nv, 1.0, 0.01);
        ReduceOptions o;
        o.phi = 0.5;
        const Piece out = reduce_under_test(in, o);
        expect_valid(in, out, "thin torus " + std::to_string(nv));
        const TopologyReport r = check_topology(out);
        ASSERT_EQ(r.per_component.size(), 1u);
        EXPECT_EQ(r.per_component[0].genus, 1);
        EXPECT_LT(out.triangle_count() * 4, in.triangle_count());
    }
}

} // namespace
} // namespace tetiso
