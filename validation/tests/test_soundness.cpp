// Every surface clean as written, in the float32 it is stored in: no
// zero-area triangle, no two vertices at one position, no self-intersection
// (docs/ARCHITECTURE.md, "Contracts"). Where the isosurface passes within
// float resolution of a mesh node, the crossings of the node's edges used to
// land on the node's own position, or a few ulps off it, whatever the
// decomposition; on an interface, locked, they reached the output unreduced.
// These cases put the level exactly at a node's value and an ulp either side,
// on nodes of interfaces, and check the raw surface, every domain's piece and
// the job's result with the contract's gate (contract_violations); and that
// the clusters of crossings the clearance leaves around such a node do not
// stay in a reduced surface as needles.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "extract_rules.hpp"
#include "reduce/contact.hpp"
#include "reduce/geometry.hpp"
#include "reduce_cases.hpp"
#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"

namespace tetiso {
namespace {

// The contract's gate, self-intersections included where CGAL is built in;
// the violations, one per line, or nothing.
std::string violations(const Piece& surface) {
    const std::optional<std::vector<TrianglePair>> crossings =
        have_self_intersections() ? find_self_intersections(surface) : std::nullopt;
    std::string out;
    for (const std::string& line : contract_violations(surface, check_topology(surface), crossings))
        out += line + "\n";
    return out;
}

// The field's float value at lattice node (i, j, k), as extraction sees it.
float node_value(const Field& field, const Lattice& lattice, std::int64_t i, std::int64_t j, std::int64_t k) {
    const double x = lattice.coordinate(i), y = lattice.coordinate(j), z = lattice.coordinate(k);
    float value = 0.0f;
    field.evaluate(&x, &y, &z, 1, &value);
    return value;
}

// ------------------------------------------------------------ the rule alone

// A node at x ≈ 4.9 and its 26 lattice neighbours at spacing 5 / 499, where
// an ulp is a twentieth of a millionth of an edge: the paper's N = 500
// lattice. The level is the node's value, or 2.7e-6 below it (the node of
// the paper's 250-domain surface whose crossings met).
TEST(CrossingPlacement, EveryEdgeThroughANodeAtTheLevelGetsItsOwnPosition) {
    const float h = 5.0f / 499.0f;
    const std::array<float, 3> node = {4.9098196f, 4.3286572f, 2.5050101f};
    for (const float offset : {0.0f, 2.7e-6f}) {
        for (const bool node_first : {true, false}) {
            std::vector<float> x = {node[0]}, y = {node[1]}, z = {node[2]}, f = {0.5f + offset};
            std::vector<GlobalId> gid = {node_first ? 0 : 100};
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        if (dx == 0 && dy == 0 && dz == 0) continue;
                        x.push_back(node[0] + static_cast<float>(dx) * h);
                        y.push_back(node[1] + static_cast<float>(dy) * h);
                        z.push_back(node[2] + static_cast<float>(dz) * h);
                        f.push_back(0.2f);
                        gid.push_back(static_cast<GlobalId>(node_first ? x.size() : x.size() - 1));
                    }
            const std::vector<std::uint8_t> interface(x.size(), 0);
            const extract_rules::NodeView view{x.data(), y.data(), z.data(), f.data(),
                                               gid.data(), interface.data(), nullptr, 0};
            std::set<std::array<float, 3>> positions = {node};
            for (std::size_t other = 1; other < x.size(); ++other) {
                const extract_rules::CrossingVertex v = extract_rules::place_crossing(view, 0, other, 0.5f);
                EXPECT_TRUE(positions.insert({v.x, v.y, v.z}).second)
                    << "the crossing towards neighbour " << other << " (offset " << offset << ", node first "
                    << node_first << ") is at the node or at another crossing";
            }
        }
    }
}

TEST(CrossingPlacement, StaysOnItsEdgeAndMovesWithTheLevel) {
    // The parameter never leaves [clearance, 1 - clearance] and never
    // decreases as the level moves from fa towards fb.
    const float clearance = extract_rules::node_clearance(4.9f, 1.0f, 0.0f, 4.91f, 1.0f, 0.0f);
    EXPECT_GT(clearance, 0.0f);
    EXPECT_LT(clearance, 0.01f);
    float previous = 0.0f;
    for (int step = 0; step <= 1000; ++step) {
        const float level = 1.0f - 0.001f * static_cast<float>(step); // from fa = 1 to fb = 0
        const float t = extract_rules::crossing_parameter(1.0f, 0.0f, level, clearance);
        EXPECT_GE(t, clearance);
        EXPECT_LE(t, 1.0f - clearance);
        EXPECT_GE(t, previous);
        previous = t;
    }
    // An edge shorter than the clearance asks keeps its crossing in its middle half.
    EXPECT_EQ(extract_rules::node_clearance(4.9f, 0, 0, std::nextafter(4.9f, 5.0f), 0, 0), 0.25f);
    EXPECT_EQ(extract_rules::node_clearance(1, 1, 1, 1, 1, 1), 0.25f);
}

// ------------------------------------------------------------- whole surfaces

// The plane x = 2.5 through a whole layer of nodes of the N = 5 lattice: every
// crossing of an edge from that layer is at its node. Before the clearance
// the raw surface had 96 zero-area triangles, 56 repeated positions and 117
// crossing pairs.
TEST(SurfacesAreClean, APlaneThroughALayerOfNodes) {
    for (const int domains : {1, 2, 8}) {
        SCOPED_TRACE("domains " + std::to_string(domains));
        const Piece raw = test::lattice_surface(5, domains, "x", 2.5);
        ASSERT_GT(raw.triangle_count(), 0u);
        EXPECT_EQ(violations(raw), "");
        JobConfig config;
        config.lattice = 5;
        config.domains = domains;
        config.field = "x";
        config.level = 2.5;
        config.seam_rings = 0;
        EXPECT_EQ(violations(run_local(Job(config), {}).surface), "");
    }
}

// A sphere whose level is one ulp above the value of node (3, 5, 4) of the
// N = 11 lattice, on the interface of its 4-domain split: its crossings lay
// one to three ulps from it, and the job without seam reduction (the
// interface's triangles as the domains left them) had 3 crossing pairs there.
TEST(SurfacesAreClean, ALevelAnUlpFromANodeOnAnInterface) {
    const std::string sphere = "sqrt((x-3.352)^2+(y-1.69)^2+(z-1.784)^2)";
    const Lattice lattice(11);
    const float at_node = node_value(*make_field(sphere), lattice, 3, 5, 4);
    for (const float level : {std::nextafter(at_node, 0.0f), at_node, std::nextafter(at_node, 10.0f)})
        for (const int rings : {0, 1}) {
            SCOPED_TRACE("level " + std::to_string(level) + ", seam rings " + std::to_string(rings));
            JobConfig config;
            config.lattice = 11;
            config.domains = 4;
            config.field = sphere;
            config.level = level;
            config.seam_rings = rings;
            EXPECT_EQ(violations(run_local(Job(config), {}).surface), "");
            EXPECT_EQ(violations(test::lattice_surface(11, 4, sphere, level)), "");
        }
}

// The paper's own case: node (490, 432, 250) of the N = 500 lattice, where
// the paper field is 2.7e-6 above the level 0.5. It lies inside domain 230 of
// the 250-domain split, on no interface: its crossings, free, met at one
// float position, and the domain's reduction left that cluster in the
// paper's surface as a repeated position, two zero-area triangles and 12
// crossing pairs. The domain's task, extracted and reduced as the job does.
TEST(SurfacesAreClean, ThePapersNodeOfTheN500Lattice) {
    JobConfig config;
    config.lattice = 500;
    config.domains = 250;
    const Job job(config);
    const GlobalId node = 490 + 500 * (432 + 500 * 250);
    const std::vector<int> holders = job.partition().domains_of_edge(node, node + 1);
    ASSERT_EQ(holders, std::vector<int>{230}) << "one domain holds the node";
    int task = 0;
    while (!(job.kind(task) == TaskKind::domain && job.node(task).first == 230)) ++task;
    TaskRecord record;
    const Piece piece = job.execute(task, nullptr, nullptr, record, TaskThreads{});
    EXPECT_EQ(violations(piece), "");
}

// ------------------------------------------- reductions that crossed themselves

// The legality tests judged contact only between faces that share a corner;
// the soak's reduced surfaces that crossed themselves (results/soundness)
// were each a new face carried through a face it shares nothing with. The
// smallest job of each kind, as the soak drew it (seed: job).

// A job's result, checked; skipped where self-intersections cannot be
// measured (tetiso built without CGAL).
#define EXPECT_CLEAN_JOB(config)                                                   \
    do {                                                                           \
        if (!have_self_intersections()) GTEST_SKIP() << "built without CGAL";     \
        EXPECT_EQ(violations(run_local(Job(config), {}).surface), "");             \
    } while (0)

// Seed 43, job 521: a collapse at the lattice's border whose new fan passes
// through four faces of a sheet that folds back past it, none of which
// shares a corner with the fan (round 6; 4 crossing pairs).
TEST(ReducedSurfacesAreClean, AFanThroughFacesItSharesNoCornerWith) {
    if (!have_self_intersections()) GTEST_SKIP() << "built without CGAL";
    const std::string field =
        "(0.921*cos(1.706*x+2.866*y+-2.436*z+1.675))*(min(sqrt((sqrt((x-2.993)^2+(y-2.048)^2)-0.944)^2+(z-2.09)^2),"
        "0.972*x+0.268*y+-0.822*z))";
    const Piece raw = test::lattice_surface(7, 1, field, -0.06763477623462677);
    ASSERT_EQ(violations(raw), "");
    ReduceOptions options;
    options.phi = 0.9;
    options.max_error = 0.25;
    for (const int threads : {1, 2}) {
        options.threads = threads;
        EXPECT_EQ(violations(reduce(raw, options)), "") << threads << " threads";
    }
}

// Seed 42, job 2688: the same inside one of two domains (4 crossing pairs).
TEST(ReducedSurfacesAreClean, AFanThroughFacesItSharesNoCornerWithInADomain) {
    JobConfig config;
    config.lattice = 9;
    config.domains = 2;
    config.field = "0.569*cos(0.378*x+-1.519*y+1.937*z+0.517)";
    config.level = 0.46064603328704834;
    config.seam_rings = 0;
    config.sample_rings = 1;
    config.max_error_spacings = 0;
    config.reduce_options.phi = 0.7;
    EXPECT_CLEAN_JOB(config);
}

// Seed 42, job 745: the same on a Gmsh mesh (6 crossing pairs).
TEST(ReducedSurfacesAreClean, AFanThroughFacesItSharesNoCornerWithOnAMesh) {
    JobConfig config;
    config.mesh = std::string(TETISO_MESHES_DIR) + "/solver/cube-4.1.msh";
    config.domains = 1;
    config.field = "0.811*cos(2.885*x+-0.002*y+2.441*z+0.505)";
    config.level = 0.5462812185287476;
    config.seam_rings = 1;
    config.sample_rings = 0;
    config.max_error_spacings = 0.5;
    config.reduce_options.phi = 0.7;
    EXPECT_CLEAN_JOB(config);
}

// Seed 43, job 919: a seam reduces a region around the interface as a piece
// of its own, and pushed it through the rest of the surface, which its
// tests could not see (8 crossing pairs with one seam ring, none with 0).
TEST(ReducedSurfacesAreClean, ASeamRegionPushedThroughTheRestOfThePiece) {
    JobConfig config;
    config.lattice = 16;
    config.domains = 8;
    config.field = "paper";
    config.level = -1.8116562366485596;
    config.seam_rings = 1;
    config.sample_rings = 1;
    config.max_error_spacings = 0.5;
    config.reduce_options.phi = 0.7;
    EXPECT_CLEAN_JOB(config);
}

// The pieces of a batch are separate surfaces, however near in space: a unit
// sphere and one just inside it, batched, each come out as reduced alone.
// Reduced as one piece, the outer sphere's collapses that would cut through
// the inner one are refused, so the contact test does see the other sphere
// where it may.
TEST(ContactTest, PiecesOfABatchAreNotJudgedAgainstEachOther) {
    const Piece outer = reduce_cases::icosphere(3);
    Piece inner = outer, both = outer;
    const auto shift = static_cast<std::int32_t>(outer.vertex_count());
    for (std::size_t v = 0; v < inner.vertex_count(); ++v) {
        for (std::vector<float>* c : {&inner.x, &inner.y, &inner.z}) (*c)[v] *= 0.98f;
        inner.key[v] += outer.key.size();
        both.x.push_back(inner.x[v]);
        both.y.push_back(inner.y[v]);
        both.z.push_back(inner.z[v]);
        both.key.push_back(inner.key[v]);
        both.flags.push_back(inner.flags[v]);
    }
    for (const std::int32_t v : outer.triangles) both.triangles.push_back(v + shift);
    for (const int threads : {1, 2}) {
        ReduceOptions options;
        options.threads = threads;
        const Piece outer_alone = reduce(outer, options), inner_alone = reduce(inner, options);
        const std::vector<Piece> batched = reduce_batch({outer, inner}, options);
        ASSERT_EQ(batched.size(), 2u);
        EXPECT_TRUE(test::same_piece(outer_alone, batched[0])) << threads << " threads";
        EXPECT_TRUE(test::same_piece(inner_alone, batched[1])) << threads << " threads";
        const Piece together = reduce(both, options);
        EXPECT_GT(together.triangle_count(), outer_alone.triangle_count() + inner_alone.triangle_count());
        if (have_self_intersections()) {
            EXPECT_EQ(violations(together), "");
        }
    }
}

// The contact test itself: triangles that cross, that touch within rounding,
// that lie side by side in one plane, and that are apart.
TEST(ContactTest, TrianglesThatShareNoCorner) {
    using reduction::Vec;
    using reduction::triangles_meet;
    const Vec a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    // A triangle piercing (a, b, c) through its interior.
    EXPECT_TRUE(triangles_meet(a, b, c, {0.2, 0.2, -1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
    // One whose corner lies on (a, b, c), and one an ulp above it.
    EXPECT_TRUE(triangles_meet(a, b, c, {0.25, 0.25, 0}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
    EXPECT_TRUE(triangles_meet(a, b, c, {0.25, 0.25, 1e-7}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
    // In the plane: overlapping, then beside it.
    EXPECT_TRUE(triangles_meet(a, b, c, {0.5, -0.5, 0}, {0.5, 2, 0}, {-1, 0.5, 0}));
    EXPECT_FALSE(triangles_meet(a, b, c, {1, 1, 0}, {2, 1, 0}, {1, 2, 0}));
    // Above it, and crossing its plane beside it.
    EXPECT_FALSE(triangles_meet(a, b, c, {0.2, 0.2, 0.1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
    EXPECT_FALSE(triangles_meet(a, b, c, {2, 2, -1}, {3, 2, 1}, {2, 3, 1}));
}

// Two operations of one round, apart in the surface but close in space, each
// see the round's start only: a sphere and a slightly turned copy just
// inside it, reduced as one piece with a loose error bound, so that both
// sheets collapse side by side in the same rounds, a few hundredths of an
// edge apart. Their new faces are set against each other's.
TEST(ContactTest, OperationsOfOneRoundAreJudgedAgainstEachOther) {
    if (!have_self_intersections()) GTEST_SKIP() << "built without CGAL";
    const Piece outer = reduce_cases::icosphere(4);
    Piece both = outer;
    const auto shift = static_cast<std::int32_t>(outer.vertex_count());
    const double turn = 0.01, c = std::cos(turn), s = std::sin(turn);
    for (std::size_t v = 0; v < outer.vertex_count(); ++v) {
        const double x = outer.x[v], y = outer.y[v], z = outer.z[v];
        both.x.push_back(static_cast<float>(0.995 * (c * x - s * y)));
        both.y.push_back(static_cast<float>(0.995 * (s * x + c * y)));
        both.z.push_back(static_cast<float>(0.995 * z));
        both.key.push_back(outer.key[v] + outer.key.size());
        both.flags.push_back(outer.flags[v]);
    }
    for (const std::int32_t v : outer.triangles) both.triangles.push_back(v + shift);
    ASSERT_EQ(violations(both), "");
    for (const int threads : {1, 2}) {
        ReduceOptions options;
        options.threads = threads;
        options.phi = 0.5;
        options.max_error = 0.2;
        EXPECT_EQ(violations(reduce(both, options)), "") << threads << " threads";
    }
}

// ------------------------------------------------- seams: the region's rim

// Soak job 46:514: the seam of domains 0 and 1 of the N = 17 lattice's
// 5-domain split, reduced without rings (the umbrellas of the unlocked
// vertices alone). A collapse there moved a vertex of the interface y = 2.5
// onto another, laying two faces in the plane x = 0.625, and one of their
// edges over the fold of two faces of domain 0 that lay beyond the region's
// rim (their common edge in that plane): 8 pairs of triangles crossed.
JobConfig job_46_514() {
    JobConfig config;
    config.lattice = 17;
    config.domains = 5;
    config.level = 2.5152339935302734;
    config.seam_rings = 0;
    config.sample_rings = 1;
    config.max_error_spacings = 0;
    return config;
}

TEST(SurfacesAreClean, ASeamWhoseRegionEndsBesideAFold) {
    EXPECT_EQ(violations(run_local(Job(job_46_514()), {}).surface), "");
}

// Triangles around each vertex key, counted.
std::map<EdgeKey, int> fan_sizes(const Piece& piece) {
    std::map<EdgeKey, int> out;
    for (const std::int32_t v : piece.triangles) ++out[piece.key[static_cast<std::size_t>(v)]];
    return out;
}

// The legality tests of a collapse or flip read the whole fan of every
// corner of the faces it makes, which are the vertices it moves or removes
// and their neighbours: in a seam's reduction, each free vertex and each of
// its neighbours has every triangle of its fan in the region handed to the
// reduction; the triangles it holds beyond (those whose corners are all
// locked) come back unchanged.
TEST(SeamRegion, EveryFanAFreeVertexTouchesIsWholeAndTheFacesBeyondStay) {
    const Job job(job_46_514());
    std::vector<Piece> domain(2);
    for (int task = 0; task < job.task_count(); ++task)
        if (job.kind(task) == TaskKind::domain && job.node(task).first < 2) {
            TaskRecord record;
            domain[static_cast<std::size_t>(job.node(task).first)] =
                job.execute(task, nullptr, nullptr, record, TaskThreads{});
        }
    const EdgeDomains holders = [&](GlobalId a, GlobalId b) { return job.partition().domains_of_edge(a, b); };
    Piece merged = merge_by_key(domain[0], domain[1]);
    ASSERT_GT(unlock_settled(merged, holders), 0u);
    const std::map<EdgeKey, int> whole = fan_sizes(merged);
    for (const int rings : {0, 1}) {
        SCOPED_TRACE("seam rings " + std::to_string(rings));
        SeamOptions options;
        options.reduce_options = job.config().reduce_options; // max_error_spacings 0: as given
        options.rings = rings;
        std::size_t free_vertices = 0, beyond = 0;
        options.reducer = [&](const Piece& region, const ReduceOptions& o, ReduceReport* report) {
            const std::map<EdgeKey, int> held = fan_sizes(region);
            for (std::size_t t = 0; t < region.triangle_count(); ++t) {
                bool any_free = false;
                for (std::size_t c = 0; c < 3; ++c)
                    any_free = any_free || !(region.flags[static_cast<std::size_t>(region.triangles[3 * t + c])] & kLocked);
                if (!any_free) continue;
                for (std::size_t c = 0; c < 3; ++c) {
                    const EdgeKey key = region.key[static_cast<std::size_t>(region.triangles[3 * t + c])];
                    EXPECT_EQ(held.at(key), whole.at(key)) << "the fan of vertex " << key << " is cut";
                }
            }
            for (const std::uint8_t f : region.flags) free_vertices += (f & kLocked) ? 0 : 1;
            const Piece reduced = reduce(region, o, report);
            const auto after = test::canonical_triangles(reduced);
            for (const auto& t : test::canonical_triangles(region)) {
                const auto is_locked = [&](EdgeKey key) {
                    const auto at = std::lower_bound(region.key.begin(), region.key.end(), key);
                    return (region.flags[static_cast<std::size_t>(at - region.key.begin())] & kLocked) != 0;
                };
                if (!is_locked(t[0]) || !is_locked(t[1]) || !is_locked(t[2])) continue;
                ++beyond;
                EXPECT_TRUE(std::binary_search(after.begin(), after.end(), t))
                    << "a triangle of locked vertices " << t[0] << " " << t[1] << " " << t[2] << " changed";
            }
            return reduced;
        };
        const Piece joined = seam(domain[0], domain[1], holders, options);
        EXPECT_GT(free_vertices, 0u);
        EXPECT_GT(beyond, 0u);
        EXPECT_EQ(violations(joined), "");
    }
}

// A flip changes only faces with a free corner, as a collapse does: two thin
// triangles in a plane, (u, w, c) and (w, u, d), the flip of (u, w) doubling
// their smallest angle. With u, w and d locked, (w, u, d) may be a face a
// seam's reduction holds beyond its region, and stays; with d free, it flips.
TEST(SeamRegion, AFlipLeavesAFaceOfLockedVerticesAsItIs) {
    for (const bool d_locked : {true, false}) {
        SCOPED_TRACE(d_locked ? "d locked" : "d free");
        Piece in;
        in.x = {-1.0f, 1.0f, 0.0f, 0.0f}; // u, w, c, d
        in.y = {0.0f, 0.0f, 0.2f, -0.2f};
        in.z = {0.0f, 0.0f, 0.0f, 0.0f};
        in.key = {1, 2, 3, 4};
        in.flags = {kLocked, kLocked, 0, static_cast<std::uint8_t>(d_locked ? kLocked : 0)};
        in.triangles = {0, 1, 2, 1, 0, 3};
        ReduceOptions options;
        options.phi = 1.0; // no collapse but the short-edge branch's
        options.short_edge_ratio = 0.0;
        ReduceReport report;
        const Piece out = reduce(in, options, &report);
        std::size_t flips = 0;
        for (const auto& round : report.rounds) flips += round.flips;
        EXPECT_EQ(flips, d_locked ? 0u : 1u);
        EXPECT_EQ(test::canonical_triangles(out) == test::canonical_triangles(in), d_locked);
    }
}

// ------------------------------------------------------- near-degenerate triangles

// The reduction judges faces thinner than kArtefactUlps as artefacts of
// where their corners were put (geometry.hpp, resolved): that must cover the
// clusters the node clearance makes, two crossings up to 2√3 clearances
// apart (extract_rules.hpp).
static_assert(reduction::kArtefactUlps >= 4.0 * extract_rules::kNodeClearanceUlps,
              "a node's cluster of crossings is wider than the reduction's artefact scale");

// Whether edge (a, b) of a surface is as short as the node clearance makes
// them: under kArtefactUlps units in the last place of its largest coordinate.
bool at_clearance_scale(const Piece& s, std::int32_t a, std::int32_t b) {
    const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
    const double dx = s.x[ia] - s.x[ib], dy = s.y[ia] - s.y[ib], dz = s.z[ia] - s.z[ib];
    const double largest = std::max({std::fabs(s.x[ia]), std::fabs(s.y[ia]), std::fabs(s.z[ia]), std::fabs(s.x[ib]),
                                     std::fabs(s.y[ib]), std::fabs(s.z[ib])});
    return std::sqrt(dx * dx + dy * dy + dz * dz) < reduction::kArtefactUlps * 0x1p-23 * largest;
}

double smallest_angle_degrees(const Piece& s, std::size_t t) {
    std::array<std::array<double, 3>, 3> p{};
    for (std::size_t c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(s.triangles[3 * t + c]);
        p[c] = {s.x[v], s.y[v], s.z[v]};
    }
    double smallest = 180.0;
    for (std::size_t c = 0; c < 3; ++c) {
        const auto& o = p[c];
        const auto& q = p[(c + 1) % 3];
        const auto& r = p[(c + 2) % 3];
        double dot = 0, lq = 0, lr = 0;
        for (std::size_t k = 0; k < 3; ++k) {
            dot += (q[k] - o[k]) * (r[k] - o[k]);
            lq += (q[k] - o[k]) * (q[k] - o[k]);
            lr += (r[k] - o[k]) * (r[k] - o[k]);
        }
        if (lq == 0 || lr == 0) return 0.0;
        smallest = std::min(smallest, std::acos(std::clamp(dot / std::sqrt(lq * lr), -1.0, 1.0)) * 180.0 / std::numbers::pi);
    }
    return smallest;
}

// Spheres of radius² = m h² on the N = 41 lattice (h = 1/8: coordinates,
// field and level exact in float), centred on a node or 4 h below the cube's
// face z = 0, so that every node (i, j, k) with (i-20)² + (j-20)² + (k-k0)²
// = m lies on the level and the crossings of its edges sit at the node
// clearance: a cluster a few dozen ulps across around each, with needles
// from it to the rest of the surface; the second sphere's clusters lie on
// the surface's border, where the nodes on the face meet the level. Every
// raw triangle under 1° touches such a cluster. A move within a cluster is
// far inside the error bound, and the angle floor lets no operation make a
// new triangle under 1° out of good ones, so a reduction that may merge the
// clusters leaves no edge at the clearance's scale and no triangle under 1°.
TEST(NearDegenerateTriangles, ClustersOfNodesOnTheLevelAreMergedWhole) {
    struct Case {
        std::string field;
        int k0, m;
    };
    const std::vector<Case> cases = {{"(x-2.5)^2+(y-2.5)^2+(z-2.5)^2", 20, 81},
                                     {"(x-2.5)^2+(y-2.5)^2+(z-2.5)^2", 20, 300},
                                     {"(x-2.5)^2+(y-2.5)^2+(z+0.5)^2", -4, 125}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.field + " at " + std::to_string(c.m) + " h^2");
        int on_level = 0, on_face = 0;
        for (int i = 0; i <= 40; ++i)
            for (int j = 0; j <= 40; ++j)
                for (int k = 0; k <= 40; ++k)
                    if ((i - 20) * (i - 20) + (j - 20) * (j - 20) + (k - c.k0) * (k - c.k0) == c.m) {
                        ++on_level;
                        on_face += k == 0;
                    }
        ASSERT_GT(on_level, 0);
        if (c.k0 < 0) {
            ASSERT_GT(on_face, 0) << "no node on the cube's face lies on the level";
        }
        const double level = c.m / 64.0;
        const Piece raw = test::lattice_surface(41, 1, c.field, level);
        std::size_t raw_slivers = 0;
        for (std::size_t t = 0; t < raw.triangle_count(); ++t) {
            if (!(smallest_angle_degrees(raw, t) < 1.0)) continue;
            ++raw_slivers;
            const std::int32_t* v = &raw.triangles[3 * t];
            EXPECT_TRUE(at_clearance_scale(raw, v[0], v[1]) || at_clearance_scale(raw, v[1], v[2]) ||
                        at_clearance_scale(raw, v[2], v[0]))
                << "raw triangle " << t << " is under 1 degree away from any node on the level";
        }
        ASSERT_GT(raw_slivers, 0u) << "the case has no cluster to merge";
        for (const int domains : {1, 6}) {
            SCOPED_TRACE("domains " + std::to_string(domains));
            JobConfig config;
            config.lattice = 41;
            config.domains = domains;
            config.field = c.field;
            config.level = level;
            const Piece out = run_local(Job(config), {}).surface;
            EXPECT_EQ(violations(out), "");
            std::size_t short_edges = 0, slivers = 0;
            for (std::size_t t = 0; t < out.triangle_count(); ++t) {
                const std::int32_t* v = &out.triangles[3 * t];
                short_edges += at_clearance_scale(out, v[0], v[1]) + at_clearance_scale(out, v[1], v[2]) +
                               at_clearance_scale(out, v[2], v[0]);
                slivers += smallest_angle_degrees(out, t) < 1.0;
            }
            EXPECT_EQ(short_edges, 0u);
            EXPECT_EQ(slivers, 0u);
        }
    }
}

} // namespace
} // namespace tetiso
