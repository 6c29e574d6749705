// The simplification baselines' adapters (reference/): what bench_reduce
// compares tetiso with must be a faithful copy of each library's result. A
// wrong renumbering, a lost orientation or a vertex read from the wrong index
// would show as a broken Piece invariant, misoriented edges, another
// topology or a surface far from the input; each careful baseline also
// promises to keep topology (its link-condition test), which these check.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"
#include "test_support.hpp"

namespace tetiso {
namespace {

struct Baseline {
    std::string name;
    std::function<Piece(const Piece&, std::size_t)> simplify;
    bool keeps_topology; // meshoptimizer does not promise it
    bool moves_vertices; // CGAL places survivors at the quadric's optimum
};

std::vector<Baseline> baselines() {
    std::vector<Baseline> all;
#ifdef TETISO_HAVE_MESHOPTIMIZER
    all.push_back({"meshopt", [](const Piece& p, std::size_t t) { return reference::meshopt_simplify(p, t); }, false, false});
#endif
#ifdef TETISO_HAVE_CGAL_SIMPLIFY
    all.push_back({"cgal", [](const Piece& p, std::size_t t) { return reference::cgal_simplify(p, t); }, true, true});
#endif
#ifdef TETISO_HAVE_OPENMESH
    all.push_back({"openmesh", [](const Piece& p, std::size_t t) { return reference::openmesh_decimate(p, t); }, true, false});
#endif
    return all;
}

TEST(ReferenceBaselines, HasFunctionsMatchTheBuild) {
#ifdef TETISO_HAVE_CGAL_SIMPLIFY
    EXPECT_TRUE(reference::has_cgal_simplify());
#else
    EXPECT_FALSE(reference::has_cgal_simplify());
#endif
#ifdef TETISO_HAVE_OPENMESH
    EXPECT_TRUE(reference::has_openmesh());
#else
    EXPECT_FALSE(reference::has_openmesh());
#endif
}

// Closed (sphere, torus) and open (gyroid: borders on the cube's faces)
// surfaces, each simplified tenfold.
TEST(ReferenceBaselines, SimplifyToTheTargetAndKeepThePieceSound) {
    const auto all = baselines();
    if (all.empty()) GTEST_SKIP() << "this build has no simplification baseline";
    for (const std::string field : {"sphere", "torus", "gyroid"}) {
        const Piece raw = test::lattice_surface(40, 1, field);
        const TopologyReport raw_topology = check_topology(raw);
        ASSERT_TRUE(raw_topology.manifold) << field;
        const std::size_t target = raw.triangle_count() / 10;
        const double extent = 5.0;
        for (const Baseline& b : all) {
            SCOPED_TRACE(b.name + " on " + field);
            const Piece out = b.simplify(raw, target);
            EXPECT_LE(out.triangle_count(), target);
            EXPECT_GT(out.triangle_count(), target / 2);
            // The Piece invariant, and every survivor is an input vertex.
            EXPECT_TRUE(std::is_sorted(out.key.begin(), out.key.end()));
            EXPECT_EQ(std::adjacent_find(out.key.begin(), out.key.end()), out.key.end());
            ASSERT_EQ(out.x.size(), out.key.size());
            for (std::size_t v = 0; v < out.key.size(); ++v) {
                const auto at = std::lower_bound(raw.key.begin(), raw.key.end(), out.key[v]);
                ASSERT_TRUE(at != raw.key.end() && *at == out.key[v]);
                if (b.moves_vertices) continue;
                const auto i = static_cast<std::size_t>(at - raw.key.begin());
                ASSERT_TRUE(out.x[v] == raw.x[i] && out.y[v] == raw.y[i] && out.z[v] == raw.z[i]) << "vertex " << v;
            }
            ASSERT_EQ(out.flags.size(), out.key.size());
            const TopologyReport topology = check_topology(out);
            EXPECT_EQ(topology.misoriented_edges, 0);
            EXPECT_EQ(topology.referenced_vertices, topology.vertices); // no vertex left unused
            if (b.keeps_topology) {
                EXPECT_TRUE(topology.manifold);
                EXPECT_TRUE(same_signatures(raw_topology, topology));
            }
            // Near the input: a tenfold reduction of these smooth surfaces
            // departs from them by a few lattice spacings (h = 5 / 39; the
            // open gyroid's borders erode most, 2.3 h with OpenMesh), while a
            // survivor given the wrong position lands anywhere in the cube.
            EXPECT_LT(hausdorff(raw, out).symmetric, 0.1 * extent);
        }
    }
}

// An edge of three triangles has no halfedge form: the careful baselines
// refuse the piece with an error, not a crash or a silently different input.
TEST(ReferenceBaselines, CarefulBaselinesRefuseANonManifoldEdge) {
    Piece fin;
    fin.x = {0, 1, 0, 0, 0};
    fin.y = {0, 0, 1, 0, -1};
    fin.z = {0, 0, 0, 1, 0};
    fin.key = {1, 2, 3, 4, 5};
    fin.flags.assign(5, 0);
    fin.triangles = {0, 1, 2, 1, 0, 3, 0, 1, 4}; // edge (0, 1) in three triangles
    bool any = false;
    for (const Baseline& b : baselines()) {
        if (!b.keeps_topology) continue;
        any = true;
        SCOPED_TRACE(b.name);
        EXPECT_THROW(b.simplify(fin, 1), Error);
    }
    if (!any) GTEST_SKIP() << "this build has no careful baseline";
}

TEST(ReferenceBaselines, ATriangleOutsideTheVerticesIsAnError) {
    Piece bad;
    bad.x = bad.y = bad.z = {0, 1, 0};
    bad.key = {1, 2, 3};
    bad.flags.assign(3, 0);
    bad.triangles = {0, 1, 3};
    const auto all = baselines();
    if (all.empty()) GTEST_SKIP() << "this build has no simplification baseline";
    for (const Baseline& b : all) {
        SCOPED_TRACE(b.name);
        EXPECT_THROW(b.simplify(bad, 1), Error);
    }
}

} // namespace
} // namespace tetiso
