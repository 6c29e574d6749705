// Reduction of whole surfaces: built-in and extracted ones keep their
// topology within the error bound over repeated reductions and seams, keep
// raw samples for later passes, clean up crossings near mesh nodes, and give
// the same bytes for any thread count and for the sweep and the choice by
// reservations. Built a second time as test_reduce_gpu with test_reduce.cpp
// (reduce_under_test.hpp).

#include <gtest/gtest.h>

#include "reduce_cases.hpp"

namespace tetiso {
namespace {

using namespace reduce_cases;

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
            EXPECT_TRUE(identical(swept, detail::reduce_by_reservations(in, o, window, detail::Speculation::kNone)))
                << "window " << window << ", " << threads << " threads";
        }
    // Speculation tests every operation of a round first: the window and the
    // thread count change nothing more. Placing the samples only for the
    // operations the steps decide, and running the steps again where a
    // chosen one fails, must give the same choice too.
    o.threads = 2;
    for (const long window : {5L, 0L, 1L << 30})
        for (const auto speculation : {detail::Speculation::kEveryTest, detail::Speculation::kSamplesWhenDecided})
            EXPECT_TRUE(identical(swept, detail::reduce_by_reservations(in, o, window, speculation)))
                << "window " << window << ", speculating"
                << (speculation == detail::Speculation::kSamplesWhenDecided ? ", samples when decided" : "");
}

INSTANTIATE_TEST_SUITE_P(Surfaces, ChoosingByReservations,
                         ::testing::Values(ReservationCase{"paper", 1}, ReservationCase{"paper", 8},
                                           ReservationCase{"gyroid", 1}, ReservationCase{"gyroid", 8}),
                         [](const ::testing::TestParamInfo<ReservationCase>& info) {
                             return std::string(info.param.field) + "_" + std::to_string(info.param.domains);
                         });

} // namespace
} // namespace tetiso
