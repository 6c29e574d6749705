// Seaming by key on tiny hand-built pieces whose answers are known: shared
// vertices become one, interface locks are released exactly when every domain
// holding the edge has been merged, inconsistent pieces are refused, and the
// reduction after a seam stays near the seam.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/seam.hpp"

namespace tetiso {
namespace {

// A unit square [x0, x0+1] x [y0, y0+1] as two triangles, with given corner
// keys (counter-clockwise from (x0, y0)) and locked corners.
Piece square(float x0, float y0, std::array<EdgeKey, 4> keys, std::array<bool, 4> locked, int domain) {
    const float xs[4] = {x0, x0 + 1, x0 + 1, x0}, ys[4] = {y0, y0, y0 + 1, y0 + 1};
    Piece p;
    std::array<int, 4> order = {0, 1, 2, 3};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return keys[static_cast<std::size_t>(a)] < keys[static_cast<std::size_t>(b)]; });
    std::array<std::int32_t, 4> index{};
    for (int i = 0; i < 4; ++i) {
        const auto c = static_cast<std::size_t>(order[static_cast<std::size_t>(i)]);
        index[c] = i;
        p.x.push_back(xs[c]);
        p.y.push_back(ys[c]);
        p.z.push_back(0);
        p.key.push_back(keys[c]);
        p.flags.push_back(locked[c] ? kLocked : 0);
    }
    p.triangles = {index[0], index[1], index[2], index[0], index[2], index[3]};
    p.domains = {domain};
    return p;
}

// A 2 x 2 grid of squares around the centre vertex (key 100), one square per
// domain; the midpoints of the inner sides are shared by two domains.
//   domain 2 | domain 3
//   ---------+---------
//   domain 0 | domain 1
struct Grid {
    // Keys are built as edge_key(0, n), so that edge_key_low/high decode them.
    static EdgeKey k(int n) { return edge_key(0, n); }
    Piece piece[4];
    std::map<EdgeKey, std::vector<int>> holders{
        {k(100), {0, 1, 2, 3}}, {k(10), {0, 1}}, {k(11), {2, 3}}, {k(12), {0, 2}}, {k(13), {1, 3}}};
    EdgeDomains domains_of_edge() const {
        return [this](GlobalId a, GlobalId b) {
            const auto it = holders.find(edge_key(a, b));
            return it == holders.end() ? std::vector<int>{} : it->second;
        };
    }
    Grid() {
        piece[0] = square(0, 0, {k(1), k(10), k(100), k(12)}, {false, true, true, true}, 0);
        piece[1] = square(1, 0, {k(10), k(2), k(13), k(100)}, {true, false, true, true}, 1);
        piece[2] = square(0, 1, {k(12), k(100), k(11), k(3)}, {true, true, true, false}, 2);
        piece[3] = square(1, 1, {k(100), k(13), k(4), k(11)}, {true, true, false, true}, 3);
    }
};

bool locked(const Piece& p, EdgeKey key) {
    const auto it = std::lower_bound(p.key.begin(), p.key.end(), key);
    return it != p.key.end() && *it == key && (p.flags[static_cast<std::size_t>(it - p.key.begin())] & kLocked);
}

TEST(Seam, VertexSharedByFourDomainsStaysLockedUntilAllAreMerged) {
    const Grid grid;
    SeamOptions no_reduce;
    no_reduce.reduce = false;
    SeamReport report;
    const Piece bottom = seam(grid.piece[0], grid.piece[1], grid.domains_of_edge(), no_reduce, &report);
    EXPECT_EQ(bottom.vertex_count(), 6u); // 4 + 4 - 2 shared
    EXPECT_EQ(bottom.triangle_count(), 4u);
    EXPECT_EQ(report.vertices_unlocked, 1u); // the midpoint between 0 and 1
    EXPECT_FALSE(locked(bottom, Grid::k(10)));
    EXPECT_TRUE(locked(bottom, Grid::k(100))) << "domains 2 and 3 still hold the centre";
    EXPECT_TRUE(locked(bottom, Grid::k(12)));
    EXPECT_EQ(bottom.domains, (std::vector<int>{0, 1}));

    const Piece top = seam(grid.piece[2], grid.piece[3], grid.domains_of_edge(), no_reduce);
    const Piece all = seam(bottom, top, grid.domains_of_edge(), no_reduce, &report);
    EXPECT_EQ(all.vertex_count(), 9u);
    EXPECT_EQ(all.triangle_count(), 8u);
    EXPECT_EQ(report.vertices_unlocked, 3u); // centre and the two vertical midpoints
    for (std::size_t v = 0; v < all.vertex_count(); ++v) EXPECT_FALSE(all.flags[v] & kLocked);
    const TopologyReport topology = check_topology(all);
    EXPECT_TRUE(topology.manifold);
    EXPECT_TRUE(topology.oriented);
    EXPECT_EQ(topology.euler, 1);
    EXPECT_TRUE(std::is_sorted(all.key.begin(), all.key.end()));
}

TEST(Seam, PieceThatTouchesNoOtherIsUnchanged) {
    const Grid grid;
    Piece far = square(5, 5, {Grid::k(50), Grid::k(51), Grid::k(52), Grid::k(53)}, {false, false, false, false}, 7);
    SeamReport report;
    const Piece both = seam(grid.piece[0], far, grid.domains_of_edge(), SeamOptions{}, &report);
    EXPECT_EQ(report.vertices_unlocked, 0u);
    EXPECT_EQ(both.vertex_count(), 8u);
    EXPECT_EQ(both.triangle_count(), 4u);
    EXPECT_TRUE(locked(both, Grid::k(100)));
    EXPECT_EQ(both.domains, (std::vector<int>{0, 7}));
}

TEST(Seam, InconsistentPiecesAreRefused) {
    const Grid grid;
    Piece moved = grid.piece[1];
    const auto shared = static_cast<std::size_t>(
        std::lower_bound(moved.key.begin(), moved.key.end(), Grid::k(10)) - moved.key.begin());
    moved.x[shared] += 1e-6f; // the vertex both pieces share, now off by a hair
    EXPECT_THROW(merge_by_key(grid.piece[0], moved), Error);
    EXPECT_THROW(merge_by_key(grid.piece[0], grid.piece[0]), Error) << "the same domain twice";
}

TEST(Seam, MergeOrderDoesNotMatter) {
    const Grid grid;
    std::vector<Piece> forward(grid.piece, grid.piece + 4), backward(forward.rbegin(), forward.rend());
    const Piece a = merge_all(forward), b = merge_all(backward);
    EXPECT_TRUE(test::same_surface(a, b));
    EXPECT_EQ(a.triangles, b.triangles);
}

// Triangles in canonical order: rotated to their smallest corner, sorted,
// their bounds and samples carried along; the order they came in is gone.
TEST(Seam, TrianglesInCanonicalOrderCarryTheirData) {
    Piece piece;
    piece.x = piece.y = piece.z = std::vector<float>(5, 0.0f);
    piece.key = {1, 2, 3, 4, 5};
    piece.flags = std::vector<std::uint8_t>(5, 0);
    piece.triangles = {3, 4, 1, 0, 1, 2, 2, 0, 3};
    piece.error = {0.3f, 0.1f, 0.2f};
    piece.sampled = {1, 0, 1};
    piece.sample_xyz = {0, 0, 0, 1, 1, 1};
    piece.sample_triangle = {0, 2};
    Piece shuffled = piece;
    shuffled.triangles = {0, 3, 2, 1, 3, 4, 1, 2, 0};
    shuffled.error = {0.2f, 0.3f, 0.1f};
    shuffled.sampled = {1, 1, 0};
    shuffled.sample_triangle = {1, 0};
    order_triangles(piece);
    order_triangles(shuffled);
    EXPECT_EQ(piece.triangles, (std::vector<std::int32_t>{0, 1, 2, 0, 3, 2, 1, 3, 4}));
    EXPECT_EQ(piece.error, (std::vector<float>{0.1f, 0.2f, 0.3f}));
    EXPECT_EQ(piece.sampled, (std::vector<std::uint8_t>{0, 1, 1}));
    EXPECT_EQ(piece.sample_triangle, (std::vector<std::int32_t>{2, 1}));
    EXPECT_EQ(shuffled.triangles, piece.triangles);
    EXPECT_EQ(shuffled.error, piece.error);
    EXPECT_EQ(shuffled.sampled, piece.sampled);
}

TEST(Seam, ReductionAfterASeamStaysNearTheSeam) {
    // Two halves of a reduced gyroid: far from the cut the result keeps the
    // halves' triangles exactly; near it the reduction runs. The region grows
    // with the cut's length and the halves with their area: at N = 60 the
    // region is well under half of them (at N = 40 the halves, reduced to
    // some 2,700 triangles each, are hardly wider than the region's rings).
    const Lattice lattice(60);
    const Decomposition two(lattice, 2);
    const auto field = make_field("gyroid");
    ReduceOptions options;
    options.max_error = 0.25 * lattice.spacing();
    const Piece left = reduce(extract(two.make_domain(0, *field), 0.0f), options);
    const Piece right = reduce(extract(two.make_domain(1, *field), 0.0f), options);
    SeamOptions seam_options;
    seam_options.reduce_options = options;
    SeamReport report;
    const Piece joined =
        seam(left, right, [&](GlobalId a, GlobalId b) { return two.domains_of_edge(a, b); }, seam_options, &report);
    EXPECT_GT(report.vertices_unlocked, 0u);
    EXPECT_LT(report.region_triangles, (left.triangle_count() + right.triangle_count()) / 2);
    EXPECT_LT(joined.triangle_count(), left.triangle_count() + right.triangle_count());
    // The halves' error bounds travel through the seam: the reduction near it
    // spends only what the halves left, so the whole stays within one bound.
    ASSERT_EQ(joined.error.size(), joined.triangle_count());
    EXPECT_LE(*std::max_element(joined.error.begin(), joined.error.end()), options.max_error);
    EXPECT_GT(*std::max_element(joined.error.begin(), joined.error.end()), 0.0f);

    // Triangles of the inputs whose vertices are all far from the cut plane
    // (more than the region's reach) appear unchanged, by key.
    const double cut = lattice.coordinate(two.box(0).hi[0]);
    const auto result = test::canonical_triangles(joined);
    for (const Piece* half : {&left, &right}) {
        std::size_t far = 0, kept = 0;
        for (std::size_t t = 0; t < half->triangle_count(); ++t) {
            bool is_far = true;
            for (int k = 0; k < 3; ++k)
                is_far = is_far && std::abs(half->x[static_cast<std::size_t>(half->triangles[3 * t + static_cast<std::size_t>(k)])] - cut) > 1.0;
            if (!is_far) continue;
            ++far;
            std::array<EdgeKey, 3> key{half->key[static_cast<std::size_t>(half->triangles[3 * t])],
                                       half->key[static_cast<std::size_t>(half->triangles[3 * t + 1])],
                                       half->key[static_cast<std::size_t>(half->triangles[3 * t + 2])]};
            std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
            kept += std::binary_search(result.begin(), result.end(), key) ? 1 : 0;
        }
        EXPECT_GT(far, 0u);
        EXPECT_EQ(kept, far);
    }
    const TopologyReport topology = check_topology(joined);
    EXPECT_TRUE(topology.manifold);
    EXPECT_TRUE(topology.oriented);
    // The reference is the same field's unreduced surface on the same lattice.
    EXPECT_TRUE(same_signatures(topology, check_topology(test::lattice_surface(60, 1, "gyroid"))));
}

TEST(Seam, RawSamplesTravelThroughTheSeamAndStayNearOpenInterfaces) {
    // Four domains of the paper surface, reduced keeping their raw vertices
    // near their interfaces. Seaming two of them re-measures those raw
    // vertices near the seam: the result holds the bound at every raw vertex
    // of both, reduces further than a seam that knows only the triangles'
    // errors, and keeps samples only near the interfaces to the other two.
    const Lattice lattice(48);
    const Decomposition four(lattice, 4);
    const auto field = make_field("paper");
    ReduceOptions options;
    options.max_error = 0.25 * lattice.spacing();
    options.keep_samples = true;
    SeamOptions seam_options;
    seam_options.reduce_options = options;
    const int first = 0, second = four.neighbours(0).front();
    std::vector<Piece> raw(2), reduced(2);
    for (int k = 0; k < 2; ++k) {
        raw[k] = extract(four.make_domain(k == 0 ? first : second, *field), 0.5f);
        reduced[k] = reduce(raw[k], options);
        EXPECT_EQ(reduced[k].sample_count(), test::referenced_positions(raw[k]).size());
        keep_samples_near_locked(reduced[k], seam_options.sample_rings);
        test::expect_samples_sound(reduced[k], test::referenced_positions(raw[k]), "domain");
        // Every triangle at an interface keeps its raw vertices; some far
        // from all of them do not.
        std::size_t at_interface = 0, unsampled = 0;
        for (std::size_t t = 0; t < reduced[k].triangle_count(); ++t) {
            bool locked = false;
            for (int c = 0; c < 3; ++c)
                locked = locked || (reduced[k].flags[static_cast<std::size_t>(reduced[k].triangles[3 * t + static_cast<std::size_t>(c)])] & kLocked);
            if (locked) {
                ++at_interface;
                EXPECT_TRUE(reduced[k].triangle_sampled(t)) << "triangle " << t;
            }
            unsampled += reduced[k].triangle_sampled(t) ? 0 : 1;
        }
        EXPECT_GT(at_interface, 0u);
        EXPECT_GT(unsampled, 0u);
    }
    const EdgeDomains domains_of_edge = [&](GlobalId a, GlobalId b) { return four.domains_of_edge(a, b); };
    const Piece joined = seam(reduced[0], reduced[1], domains_of_edge, seam_options);
    std::vector<Piece> blind = reduced;
    for (Piece& p : blind) {
        p.sample_xyz.clear();
        p.sample_triangle.clear();
        p.sampled.clear();
    }
    const Piece joined_blind = seam(blind[0], blind[1], domains_of_edge, seam_options);

    const Piece both_raw = merge_by_key(raw[0], raw[1]);
    HausdorffOptions vertices;
    vertices.vertices_only = true;
    EXPECT_LE(hausdorff(both_raw, joined, vertices).forward, options.max_error * (1 + 1e-5));
    EXPECT_LE(hausdorff(both_raw, joined_blind, vertices).forward, options.max_error * (1 + 1e-5));
    EXPECT_LT(joined.triangle_count(), joined_blind.triangle_count());
    test::expect_samples_sound(joined, test::referenced_positions(both_raw), "seam");
    EXPECT_GT(joined.sample_count(), 0u); // the interfaces to the other two domains are still open
    const TopologyReport topology = check_topology(joined);
    EXPECT_TRUE(topology.manifold);
    EXPECT_TRUE(topology.oriented);
    EXPECT_TRUE(same_signatures(topology, check_topology(both_raw)));

    // Once no interface is open no later seam can use them: all are dropped.
    Piece closed = joined;
    for (std::uint8_t& f : closed.flags) f = static_cast<std::uint8_t>(f & ~kLocked);
    keep_samples_near_locked(closed, seam_options.sample_rings);
    EXPECT_EQ(closed.sample_count(), 0u);
    EXPECT_TRUE(closed.sampled.empty());
}

} // namespace
} // namespace tetiso
