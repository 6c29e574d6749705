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
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "extract_rules.hpp"
#include "reduce/geometry.hpp"
#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
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
