// The lattice test problem and its decomposition: a conforming, positively
// oriented tetrahedral mesh, split into boxes that tile the cube and agree on
// every shared node.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "tetiso/error.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"

namespace tetiso {
namespace {

double orientation(const Domain& d, std::size_t t) {
    const std::int32_t* v = d.tets.data() + 4 * t;
    auto p = [&](int k, int axis) {
        const auto i = static_cast<std::size_t>(v[k]);
        return static_cast<double>(axis == 0 ? d.x[i] : axis == 1 ? d.y[i] : d.z[i]);
    };
    double a[3], b[3], c[3];
    for (int axis = 0; axis < 3; ++axis) {
        a[axis] = p(1, axis) - p(0, axis);
        b[axis] = p(2, axis) - p(0, axis);
        c[axis] = p(3, axis) - p(0, axis);
    }
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

TEST(Lattice, TetrahedraArePositiveAndFillTheCube) {
    const Lattice lattice(7);
    const Decomposition one(lattice, 1);
    const auto field = make_field("paper");
    const Domain d = one.make_domain(0, *field);
    ASSERT_EQ(d.tet_count(), static_cast<std::size_t>(lattice.tet_count()));
    double volume = 0;
    for (std::size_t t = 0; t < d.tet_count(); ++t) {
        const double det = orientation(d, t);
        ASSERT_GT(det, 0.0) << "tetrahedron " << t;
        volume += det / 6.0;
    }
    EXPECT_NEAR(volume, 125.0, 1e-4);
}

TEST(Lattice, FacesMatchBetweenCells) {
    // A conforming mesh: every triangular face is shared by exactly two
    // tetrahedra, except the faces on the cube's surface.
    const Lattice lattice(6);
    const Decomposition one(lattice, 1);
    const Domain d = one.make_domain(0, *make_field("sphere"));
    std::map<std::array<std::int32_t, 3>, int> faces;
    for (std::size_t t = 0; t < d.tet_count(); ++t)
        for (int skip = 0; skip < 4; ++skip) {
            std::array<std::int32_t, 3> f{};
            int k = 0;
            for (int v = 0; v < 4; ++v)
                if (v != skip) f[static_cast<std::size_t>(k++)] = d.tets[4 * t + static_cast<std::size_t>(v)];
            std::sort(f.begin(), f.end());
            ++faces[f];
        }
    std::int64_t boundary = 0;
    for (const auto& [face, count] : faces) {
        ASSERT_LE(count, 2);
        if (count == 1) ++boundary;
    }
    const std::int64_t cells = lattice.n() - 1;
    EXPECT_EQ(boundary, 6 * 2 * cells * cells);
}

class Decompositions : public ::testing::TestWithParam<int> {};

TEST_P(Decompositions, BoxesTileTheCubeAndNeighboursAreSymmetric) {
    const Lattice lattice(21);
    const Decomposition decomposition(lattice, GetParam());
    ASSERT_EQ(decomposition.domain_count(), GetParam());
    std::int64_t cells = 0, smallest = INT64_MAX, largest = 0;
    for (int a = 0; a < decomposition.domain_count(); ++a) {
        const CellBox& box = decomposition.box(a);
        cells += box.cells();
        smallest = std::min(smallest, box.cells());
        largest = std::max(largest, box.cells());
        for (int b = a + 1; b < decomposition.domain_count(); ++b) {
            const CellBox& other = decomposition.box(b);
            std::int64_t overlap = 1;
            for (int axis = 0; axis < 3; ++axis)
                overlap *= std::max<std::int64_t>(0, std::min(box.hi[axis], other.hi[axis]) -
                                                         std::max(box.lo[axis], other.lo[axis]));
            ASSERT_EQ(overlap, 0) << "domains " << a << " and " << b << " overlap";
        }
        for (const int n : decomposition.neighbours(a)) {
            const auto& back = decomposition.neighbours(n);
            EXPECT_TRUE(std::binary_search(back.begin(), back.end(), a));
        }
    }
    EXPECT_EQ(cells, lattice.cell_count());
    EXPECT_GE(smallest, 1);
}

INSTANTIATE_TEST_SUITE_P(Counts, Decompositions, ::testing::Values(1, 2, 3, 7, 8, 27, 63, 125, 250));

TEST(Decomposition, BalancedAtThePapersSize) {
    // Slabs of whole cells make small lattices uneven; at the paper's 500^3
    // the three series must be within 10% so that load balance is fair.
    const Lattice lattice(500);
    for (const int count : {63, 125, 250}) {
        const Decomposition decomposition(lattice, count);
        std::int64_t smallest = INT64_MAX, largest = 0;
        for (int d = 0; d < count; ++d) {
            smallest = std::min(smallest, decomposition.box(d).cells());
            largest = std::max(largest, decomposition.box(d).cells());
        }
        EXPECT_LE(static_cast<double>(largest), 1.1 * static_cast<double>(smallest)) << count << " domains";
    }
}

TEST(Decomposition, AsManyDomainsAsCells) {
    const Lattice lattice(3); // 8 cells
    const Decomposition decomposition(lattice, 8);
    for (int d = 0; d < 8; ++d) EXPECT_EQ(decomposition.box(d).cells(), 1);
    EXPECT_THROW(Decomposition(lattice, 9), Error);
    EXPECT_THROW(Decomposition(lattice, 0), Error);
    EXPECT_THROW(Lattice(1), Error);
}

TEST(Decomposition, SharedNodesAgreeAndInterfacesAreMarked) {
    const Lattice lattice(12);
    const Decomposition decomposition(lattice, 27);
    const auto field = make_field("x*y - z");
    struct Seen {
        float x, y, z, f;
        int domains;
    };
    std::map<GlobalId, Seen> nodes;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const Domain domain = decomposition.make_domain(d, *field);
        for (std::size_t v = 0; v < domain.node_count(); ++v) {
            const auto [it, fresh] = nodes.try_emplace(domain.gid[v], Seen{domain.x[v], domain.y[v], domain.z[v], domain.f[v], 0});
            ++it->second.domains;
            if (!fresh) {
                ASSERT_EQ(it->second.x, domain.x[v]);
                ASSERT_EQ(it->second.y, domain.y[v]);
                ASSERT_EQ(it->second.z, domain.z[v]);
                ASSERT_EQ(it->second.f, domain.f[v]);
            }
        }
    }
    ASSERT_EQ(static_cast<std::int64_t>(nodes.size()), lattice.node_count());
    // A node is on an interface exactly when it belongs to several domains.
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const Domain domain = decomposition.make_domain(d, *field);
        for (std::size_t v = 0; v < domain.node_count(); ++v)
            ASSERT_EQ(domain.interface[v] != 0, nodes.at(domain.gid[v]).domains > 1) << "node " << domain.gid[v];
    }
}

TEST(Decomposition, DomainsOfEdgeFindEveryHolder) {
    const Lattice lattice(9);
    const Decomposition decomposition(lattice, 8); // 2 x 2 x 2 boxes meeting at the centre node
    const GlobalId centre = lattice.node_id(4, 4, 4);
    EXPECT_EQ(decomposition.domains_of_edge(centre, lattice.node_id(5, 4, 4)).size(), 4u); // on two planes
    EXPECT_EQ(decomposition.domains_of_edge(centre, lattice.node_id(5, 5, 4)).size(), 2u); // in one plane
    EXPECT_EQ(decomposition.domains_of_edge(centre, lattice.node_id(5, 5, 5)).size(), 1u); // inside a box
}

// The tree descent against the definition, box by box, for every edge of
// the Freudenthal split (the axes, the face diagonals and the body
// diagonal, each from its lower node) on uneven bisections, where cuts
// leave T-junctions and boxes of different sizes meet.
TEST(Decomposition, DomainsOfEdgeAgreeWithEveryBox) {
    const Lattice lattice(12);
    const std::int64_t n = lattice.n();
    const std::array<std::int64_t, 3> steps[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0},
                                                 {0, 1, 1}, {1, 0, 1}, {1, 1, 1}};
    for (const int d : {1, 2, 7, 27, 50, 131}) {
        const Decomposition decomposition(lattice, d);
        std::size_t edges = 0, shared = 0;
        for (std::int64_t k = 0; k < n; ++k)
            for (std::int64_t j = 0; j < n; ++j)
                for (std::int64_t i = 0; i < n; ++i)
                    for (const auto& step : steps) {
                        const std::int64_t i2 = i + step[0], j2 = j + step[1], k2 = k + step[2];
                        if (i2 >= n || j2 >= n || k2 >= n) continue;
                        std::vector<int> expected;
                        for (int b = 0; b < d; ++b) {
                            const CellBox& box = decomposition.box(b);
                            if (i >= box.lo[0] && i2 <= box.hi[0] && j >= box.lo[1] && j2 <= box.hi[1] &&
                                k >= box.lo[2] && k2 <= box.hi[2])
                                expected.push_back(b);
                        }
                        ASSERT_FALSE(expected.empty());
                        ASSERT_EQ(decomposition.domains_of_edge(lattice.node_id(i, j, k), lattice.node_id(i2, j2, k2)),
                                  expected)
                            << d << " domains, edge (" << i << "," << j << "," << k << ")-(" << i2 << "," << j2
                            << "," << k2 << ")";
                        ++edges;
                        shared += expected.size() > 1;
                    }
        if (d > 1) {
            EXPECT_GT(shared, 0u) << d << " domains: no edge on an interface was tried";
        }
        EXPECT_GT(edges, 0u);
    }
}

} // namespace
} // namespace tetiso
