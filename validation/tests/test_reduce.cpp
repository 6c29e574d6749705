// Reduction (core/src/reduce/): the reduced surface keeps the topology of
// every component, stays a consistently oriented manifold without degenerate
// triangles, keeps locked vertices bit for bit and border vertices on the
// border, stays within half a lattice spacing of the input, and does not
// depend on the thread count. Tiny exact meshes built here probe the branches
// (needles, zero-length edges, valence-3 vertices, flips, thin handles,
// minimal components); extracted lattice surfaces probe the whole. Built a
// second time as test_reduce_gpu, where every reduction also runs on the GPU
// and must give the same bytes (reduce_under_test.hpp).
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

namespace tetiso {
namespace {

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
Piece icosphere(int levels) {
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
Piece torus(int nu, int nv, double ring, double tube) {
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
Piece grid(int n, double shear = 0.0, double scale = 1.0) {
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

void expect_valid(const Piece& in, const Piece& out, const std::string& what) {
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
bool identical(const Piece& a, const Piece& b) {
    return a.key == b.key && a.flags == b.flags && a.triangles == b.triangles && test::same_bits(a.x, b.x) &&
           test::same_bits(a.y, b.y) && test::same_bits(a.z, b.z) && test::same_bits(a.error, b.error) &&
           a.sampled == b.sampled && a.sample_triangle == b.sample_triangle &&
           test::same_bits(a.sample_xyz, b.sample_xyz);
}

std::size_t interior_valence3(const Piece& p) {
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

// The largest distance of the input's vertices to the reduced surface: what
// ReduceOptions::max_error bounds.
double vertex_distance(const Piece& in, const Piece& out) {
    HausdorffOptions o;
    o.vertices_only = true;
    return hausdorff(in, out, o).forward;
}

TEST(Reduce, SphereAndTorusBuiltInCode) {
    // max_error holds at the input's vertices, exactly. Between them the
    // input's triangles and the reduced faces part further only by how much
    // the surface bends within one reduced face, which the bound limits too:
    // twice the bound is a loose envelope for the sampled distance.
    const double bound = 0.01;
    const Piece sphere = icosphere(5);
    ReduceOptions o;
    o.max_error = bound;
    const Piece s = reduce_under_test(sphere, o);
    expect_valid(sphere, s, "icosphere");
    EXPECT_LE(vertex_distance(sphere, s), bound * (1 + 1e-5));
    EXPECT_LE(hausdorff(sphere, s).symmetric, 2 * bound);
    EXPECT_GT(test::signed_volume(s) * test::signed_volume(sphere), 0) << "orientation kept";
    const Piece ring = torus(240, 60, 1.0, 0.3);
    const Piece t = reduce_under_test(ring, o);
    expect_valid(ring, t, "torus");
    EXPECT_LE(vertex_distance(ring, t), bound * (1 + 1e-5));
    EXPECT_LE(hausdorff(ring, t).symmetric, 2 * bound);
    EXPECT_LT(t.triangle_count() * 5, ring.triangle_count());
}

// ---------------------------------------------------------------------------
// Extracted surfaces.

struct Case {
    const char* field;
    std::int64_t n;
    double min_ratio; // required triangles_in / triangles_out
};

TEST(Reduce, ExtractedSurfacesKeepTopologyAndStayWithinHalfASpacing) {
    // At the bound `tetiso extract --reduce` and `tetiso run` use by default
    // (0.25 h): the ratio of 10 for sphere and torus, and for the
    // paper's surface at N = 100, its benchmark size.
    for (const Case c : {Case{"sphere", 80, 10.0}, Case{"torus", 80, 10.0}, Case{"gyroid", 60, 2.0},
                         Case{"paper", 100, 10.0}}) {
        const Piece in = lattice_surface(c.n, 1, c.field);
        const double h = Lattice(c.n).spacing();
        ReduceOptions o;
        o.max_error = 0.25 * h;
        ReduceReport report;
        const Piece out = reduce_under_test(in, o, &report);
        expect_valid(in, out, c.field);
        EXPECT_LE(vertex_distance(in, out), o.max_error * (1 + 1e-5)) << c.field;
        const HausdorffReport d = hausdorff(in, out);
        EXPECT_LE(d.symmetric, 0.5 * h) << c.field;
        EXPECT_GE(static_cast<double>(in.triangle_count()), c.min_ratio * static_cast<double>(out.triangle_count()))
            << c.field << ": " << in.triangle_count() << " -> " << out.triangle_count();
        EXPECT_FALSE(report.rounds.empty());
    }
}

TEST(Reduce, ErrorBoundHoldsOverRepeatedReductions) {
    // A job reduces a region again after every seam. Each triangle carries its
    // bound on the distance to the raw surface, so the second pass may only
    // spend what the first left: the bound holds for the result as a whole,
    // not per pass (reset, two passes could drift up to twice as far).
    const std::int64_t n = 60;
    const double h = Lattice(n).spacing();
    const Piece in = lattice_surface(n, 1, "paper");
    ReduceOptions o;
    o.max_error = 0.25 * h;
    const Piece once = reduce_under_test(in, o);
    ASSERT_EQ(once.error.size(), once.triangle_count());
    for (const float e : once.error) ASSERT_LE(e, o.max_error);
    o.phi = 0.8; // a laxer criterion offers the second pass new collapses
    const Piece twice = reduce_under_test(once, o);
    expect_valid(in, twice, "reduced twice");
    ASSERT_EQ(twice.error.size(), twice.triangle_count());
    for (const float e : twice.error) ASSERT_LE(e, o.max_error);
    // Each pass holds the bound at its own input's vertices, and the second,
    // which measures whole triangles of the first's output against their
    // bounds, holds it at the raw vertices too: one budget, not two.
    EXPECT_LE(vertex_distance(in, once), o.max_error * (1 + 1e-5));
    EXPECT_LE(vertex_distance(once, twice), o.max_error * (1 + 1e-5));
    EXPECT_LE(vertex_distance(in, twice), o.max_error * (1 + 1e-5));
    EXPECT_LE(hausdorff(in, twice).symmetric, 0.5 * h);
}

TEST(Reduce, KeptSamplesAreTheRawVerticesAndLetALaterPassSpendTheBudgetAgain) {
    // A reduction that hands on its samples (keep_samples) hands on every
    // raw vertex once, each held by a triangle whose error bounds it. A
    // second pass over that output measures the raw vertices themselves, so
    // it may bring the surface anywhere within the bound of them: it reduces
    // further than a pass that knows only the triangles' errors, and the
    // bound still holds at every raw vertex.
    const std::int64_t n = 60;
    const double h = Lattice(n).spacing();
    const Piece in = lattice_surface(n, 1, "paper");
    const auto raw = test::referenced_positions(in);
    ReduceOptions o;
    o.max_error = 0.25 * h;
    o.keep_samples = true;
    const Piece once = reduce_under_test(in, o);
    ASSERT_EQ(once.sampled.size(), once.triangle_count());
    EXPECT_TRUE(std::all_of(once.sampled.begin(), once.sampled.end(), [](auto s) { return s == 1; }));
    EXPECT_EQ(test::sample_positions(once), raw);
    test::expect_samples_sound(once, raw, "once");

    o.phi = 0.8; // a laxer criterion offers the second pass new collapses
    const Piece twice = reduce_under_test(once, o);
    Piece blind = once;
    blind.sample_xyz.clear();
    blind.sample_triangle.clear();
    blind.sampled.clear();
    const Piece twice_blind = reduce_under_test(blind, o);
    expect_valid(in, twice, "reduced twice, with the raw vertices");
    expect_valid(in, twice_blind, "reduced twice, with the errors only");
    EXPECT_LE(vertex_distance(in, twice), o.max_error * (1 + 1e-5));
    EXPECT_LE(vertex_distance(in, twice_blind), o.max_error * (1 + 1e-5));
    EXPECT_LT(twice.triangle_count(), twice_blind.triangle_count());
    EXPECT_EQ(test::sample_positions(twice), raw);
    test::expect_samples_sound(twice, raw, "twice");
    // Without samples in, every triangle holds a triangle of the input as
    // its sample: none can be handed on as raw vertices.
    EXPECT_EQ(twice_blind.sample_count(), 0u);

    // Samples that do not fit the piece are refused, not used.
    Piece bad = once;
    bad.sample_triangle.front() = static_cast<std::int32_t>(bad.triangle_count());
    EXPECT_THROW(reduce_under_test(bad, o), Error);
    bad = once;
    bad.sampled.assign(bad.triangle_count(), 0);
    EXPECT_THROW(reduce_under_test(bad, o), Error);
    bad = once;
    bad.sample_xyz.pop_back();
    EXPECT_THROW(reduce_under_test(bad, o), Error);
}

// The piece with the positions extraction gave before crossings kept clear
// of their nodes (extract_rules.hpp, node_clearance): t = (level - fa) /
// (fb - fa) from the smaller-id end, the node itself within 2^-24 of it. Such
// a surface (a user's for `tetiso reduce`, another extractor's) has clusters
// of vertices at a node or within ulps of it, which reduction must clean up.
Piece with_unclear_crossings(Piece piece, const Domain& domain, float level) {
    std::map<GlobalId, std::size_t> local;
    for (std::size_t v = 0; v < domain.node_count(); ++v) local[domain.gid[v]] = v;
    for (std::size_t i = 0; i < piece.vertex_count(); ++i) {
        const std::size_t a = local.at(edge_key_low(piece.key[i])), b = local.at(edge_key_high(piece.key[i]));
        float t = (level - domain.f[a]) / (domain.f[b] - domain.f[a]);
        t = t < 0x1p-24f ? 0.0f : (t > 1.0f - 0x1p-24f ? 1.0f : t);
        piece.x[i] = domain.x[a] + t * (domain.x[b] - domain.x[a]);
        piece.y[i] = domain.y[a] + t * (domain.y[b] - domain.y[a]);
        piece.z[i] = domain.z[a] + t * (domain.z[b] - domain.z[a]);
    }
    return piece;
}

TEST(Reduce, SurfaceThroughMeshNodesIsCleanedUp) {
    // x = 2.5 is a plane of lattice nodes for odd N: crossings placed at the
    // nodes give zero-length edges and zero-area triangles.
    const std::int64_t n = 41;
    const Lattice lattice(n);
    const Decomposition whole(lattice, 1);
    const Piece in = with_unclear_crossings(lattice_surface(n, 1, "x - 2.5", 0.0),
                                            whole.make_domain(0, *make_field("x - 2.5")), 0.0f);
    ASSERT_GT(check_topology(in).degenerate_triangles, 0);
    const Piece out = reduce_under_test(in);
    expect_valid(in, out, "plane through nodes");
    EXPECT_EQ(check_topology(out).near_degenerate_triangles, 0);
    EXPECT_LT(out.triangle_count() * 50, in.triangle_count());
    EXPECT_LE(hausdorff(in, out).symmetric, 0.5 * Lattice(n).spacing());
}

std::int64_t zero_area_triangles(const Piece& p) { return check_topology(p).zero_area_triangles; }

TEST(Reduce, ClustersWithinFloatResolutionOfAMeshNodeAreCleanedUp) {
    // Where the paper surface at N = 1000 passes within float resolution of
    // a node, the vertices on the node's edges placed without clearance
    // (with_unclear_crossings) round to points that differ
    // in one coordinate by a few ulps: they lie on a line, the faces among
    // them have zero area and the needles from them to the rest have
    // normals that rounding chose. The 1000-domain job once kept six such
    // triangles (around these nodes); any way out of the cluster was
    // refused by the needles' normals.
    const Lattice lattice(1000);
    const auto field = make_field("paper");
    ReduceOptions o;
    o.max_error = 0.25 * lattice.spacing(); // as the job sets it
    for (const auto& node : {std::array<std::int64_t, 3>{457, 159, 843}, std::array<std::int64_t, 3>{774, 309, 186}}) {
        const std::int64_t half = 6;
        // What a 1000-domain job's domain holds around the node, without
        // interfaces: 12^3 cells rather than 10^6.
        const CellBox box{{node[0] - half, node[1] - half, node[2] - half}, {node[0] + half, node[1] + half, node[2] + half}};
        const Domain domain = make_box_domain(lattice, box, *field, 0);
        const auto level = static_cast<float>(field->default_level());
        const Piece in = with_unclear_crossings(extract(domain, level), domain, level);
        SCOPED_TRACE("around node " + std::to_string(node[0]) + "," + std::to_string(node[1]) + "," + std::to_string(node[2]));
        ASSERT_GT(zero_area_triangles(in), 0) << "the surface no longer passes that close to the node";
        const Piece out = reduce_under_test(in, o);
        expect_valid(in, out, "cluster");
        EXPECT_LT(out.triangle_count() * 4, in.triangle_count());
    }
}

TEST(Reduce, InterfaceVerticesOfADomainStayLocked) {
    const Lattice lattice(40);
    const Decomposition decomposition(lattice, 4);
    const auto field = make_field("paper");
    const Piece in = extract(decomposition.make_domain(1, *field), 0.5f);
    const auto locked = std::count_if(in.flags.begin(), in.flags.end(), [](auto f) { return (f & kLocked) != 0; });
    ASSERT_GT(locked, 0);
    ReduceOptions o;
    o.max_error = 0.4 * lattice.spacing();
    const Piece out = reduce_under_test(in, o);
    expect_valid(in, out, "domain piece");
    EXPECT_LT(out.triangle_count() * 2, in.triangle_count());
}

// Large enough (84 K triangles, 43 K vertices and samples) that every step
// of a round runs on the threads, the counting sorts by atomic counters
// included; the kept samples show their order.
TEST(Reduce, OutputDoesNotDependOnThreadsOrRuns) {
    const Piece in = lattice_surface(40, 1, "gyroid");
    ReduceOptions o;
    o.max_error = 0.4 * Lattice(40).spacing();
    o.keep_samples = true;
    o.threads = 1;
    const Piece a = reduce_under_test(in, o);
    const Piece b = reduce_under_test(in, o);
    o.threads = 2;
    const Piece c = reduce_under_test(in, o);
    // Another count: the reservations' steps decide other operations
    // together, never others in the end.
    o.threads = 3;
    const Piece d = reduce_under_test(in, o);
    EXPECT_TRUE(identical(a, b));
    EXPECT_TRUE(identical(a, c));
    EXPECT_TRUE(identical(a, d));
    EXPECT_LT(a.triangle_count(), in.triangle_count());
    EXPECT_GT(a.sample_count(), 0u);
}

// A fault of tetiso's own (a surface the operations broke) is not the
// input's: callers that report bad input must not catch it as such, and the
// command line gives it its own exit status.
TEST(Reduce, InternalFaultsAreNotInputErrors) {
    bool taken_for_input = false, reported = false;
    try {
        throw InternalError("tetiso::reduce: vertex (key 1) became non-manifold");
    } catch (const Error&) {
        taken_for_input = true;
    } catch (const std::exception& e) {
        reported = std::string(e.what()).find("non-manifold") != std::string::npos;
    }
    EXPECT_FALSE(taken_for_input);
    EXPECT_TRUE(reported);
}

// The job lends a running reduction more cores between rounds
// (ReduceOptions::more_threads): the count changing mid-call must not
// change the result either.
TEST(Reduce, ThreadsOfferedBetweenRoundsChangeNothing) {
    const Piece in = lattice_surface(40, 1, "gyroid");
    ReduceOptions o;
    o.max_error = 0.4 * Lattice(40).spacing();
    ReduceReport single_report;
    const Piece single = reduce_under_test(in, o, &single_report);
    int asked = 0;
    o.more_threads = [&asked] {
        ++asked;
        return asked % 3 == 0 ? 3 : asked % 3 == 1 ? 0 : 2; // keep, 2, 3, keep, ...
    };
    ReduceReport report;
    const Piece varied = reduce_under_test(in, o, &report);
    EXPECT_TRUE(identical(single, varied));
    // Asked before every round, the last one (which finds nothing) included.
    EXPECT_GE(asked, static_cast<int>(report.rounds.size()));
    EXPECT_EQ(report.rounds.size(), single_report.rounds.size());
}

// The GPU chooses each round's independent set by deterministic
// reservations with a window of the whole round, in every round and for the
// flips too, testing every collapse before the steps (speculation), where
// the host sweeps in order on one thread and takes windows of a
// thirty-second on several. The choice, and so the surface, must not
// depend on how it is made: here on the host, where CI runs it, with windows
// of one operation up to all of them. One case per surface (the whole one,
// or one domain's piece with its interface locked), each its own test.
struct ReservationCase {
    const char* field;
    int domains;
};

class ChoosingByReservations : public ::testing::TestWithParam<ReservationCase> {};

TEST_P(ChoosingByReservations, GivesTheSweepsBytes) {
    const ReservationCase c = GetParam();
    const Lattice lattice(40);
    const Decomposition decomposition(lattice, c.domains);
    const auto f = make_field(c.field);
    const Piece in = extract(decomposition.make_domain(c.domains - 1, *f), static_cast<float>(f->default_level()));
    ReduceOptions o;
    o.max_error = 0.25 * lattice.spacing();
    o.keep_samples = true;
    const Piece swept = reduce(in, o);
    EXPECT_EQ(c.domains > 1, std::count(in.flags.begin(), in.flags.end(), kLocked) > 0);
    EXPECT_LT(swept.triangle_count(), in.triangle_count());
    for (const long window : {1L, 5L, 1000L, 0L, 1L << 30})
        for (const int threads : {1, 2}) {
            o.threads = threads;
            EXPECT_TRUE(identical(swept, detail::reduce_by_reservations(in, o, window, false)))
                << "window " << window << ", " << threads << " threads";
        }
    // Speculation tests every operation of a round first: the window and the
    // thread count change nothing more.
    o.threads = 2;
    for (const long window : {5L, 0L, 1L << 30})
        EXPECT_TRUE(identical(swept, detail::reduce_by_reservations(in, o, window, true)))
            << "window " << window << ", speculating";
}

INSTANTIATE_TEST_SUITE_P(Surfaces, ChoosingByReservations,
                         ::testing::Values(ReservationCase{"paper", 1}, ReservationCase{"paper", 8},
                                           ReservationCase{"gyroid", 1}, ReservationCase{"gyroid", 8}),
                         [](const ::testing::TestParamInfo<ReservationCase>& info) {
                             return std::string(info.param.field) + "_" + std::to_string(info.param.domains);
                         });

} // namespace
} // namespace tetiso
