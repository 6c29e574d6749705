// The paper's test problem: an N x N x N lattice of nodes on [0,5]^3, each
// cube cell split into six positively oriented tetrahedra (the Freudenthal /
// Kuhn split along the main diagonal, so faces match between neighbouring
// cells), and its decomposition into D box-shaped domains by recursive
// coordinate bisection. Domains are generated one at a time on demand; the
// whole mesh is never held in memory.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

inline constexpr double kLatticeExtent = 5.0; // the cube is [0, kLatticeExtent]^3

// A box of lattice cells, [lo, hi) along each axis in cell units.
struct CellBox {
    std::array<std::int64_t, 3> lo{}, hi{};
    std::int64_t cells() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
    std::int64_t nodes() const {
        return (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    }
};

class Lattice {
public:
    // Throws tetiso::Error if n < 2 or the node count does not fit an edge key.
    explicit Lattice(std::int64_t n);

    std::int64_t n() const { return n_; }
    double spacing() const { return kLatticeExtent / static_cast<double>(n_ - 1); }
    std::int64_t node_count() const { return n_ * n_ * n_; }
    std::int64_t cell_count() const { return (n_ - 1) * (n_ - 1) * (n_ - 1); }
    std::int64_t tet_count() const { return 6 * cell_count(); }

    GlobalId node_id(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return i + n_ * (j + n_ * k);
    }
    std::array<std::int64_t, 3> node_index(GlobalId id) const {
        return {id % n_, (id / n_) % n_, id / (n_ * n_)};
    }
    double coordinate(std::int64_t index) const {
        return kLatticeExtent * static_cast<double>(index) / static_cast<double>(n_ - 1);
    }

private:
    std::int64_t n_;
};

// One node of the bisection tree. It covers domains [first, first + count);
// a leaf (count 1) is one domain, an inner node's children are the two boxes
// its cut made. Every node covers a box, so the children of a node are
// adjacent across the cut and their union is convex.
struct BisectionNode {
    int first = 0;
    int count = 1;
    int left = -1;  // index of the child node, -1 for a leaf
    int right = -1;
};

// Recursive coordinate bisection of the lattice's cells into D boxes: each
// split cuts the longest side of a box, dividing the domain count and the
// cells in proportion, so domains differ in size by about one slab of cells.
class Decomposition {
public:
    // Throws tetiso::Error if d < 1 or d exceeds the number of cells.
    Decomposition(const Lattice& lattice, int d);

    const Lattice& lattice() const { return lattice_; }
    int domain_count() const { return static_cast<int>(boxes_.size()); }
    const CellBox& box(int domain) const { return boxes_.at(static_cast<std::size_t>(domain)); }

    // Domains that share at least one mesh edge with `domain` (a face or a
    // segment of an edge of its box), sorted.
    const std::vector<int>& neighbours(int domain) const {
        return neighbours_.at(static_cast<std::size_t>(domain));
    }

    // The bisection tree, root first; children come after their parent.
    const std::vector<BisectionNode>& tree() const { return tree_; }

    // Domains whose closed box contains the mesh edge between two nodes, sorted.
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const;

    // Builds the nodes, field values and tetrahedra of one domain.
    Domain make_domain(int domain, const Field& field) const;

private:
    const Lattice& lattice_;
    std::vector<CellBox> boxes_;
    std::vector<BisectionNode> tree_;
    std::vector<std::vector<int>> neighbours_;
};

} // namespace tetiso
