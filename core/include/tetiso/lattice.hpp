// The paper's test problem: an N x N x N lattice of nodes on [0,5]^3, each
// cube cell split into six positively oriented tetrahedra (the Freudenthal /
// Kuhn split along the main diagonal, so faces match between neighbouring
// cells), and its decomposition into D box-shaped domains by recursive
// coordinate bisection. Domains are generated one at a time on demand; the
// whole mesh is never held in memory.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"

namespace tetiso {

inline constexpr double kLatticeExtent = 5.0; // the cube is [0, kLatticeExtent]^3

// The six tetrahedra of a cell, one per ordering of the axes (see
// Decomposition::make_domain); the GPU builds lattice tetrahedra from it too.
inline constexpr int kCellTetOrders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

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

// Recursive coordinate bisection of the lattice's cells into D boxes: each
// split cuts the longest side of a box, dividing the domain count and the
// cells in proportion, so domains differ in size by about one slab of cells.
class Decomposition {
public:
    // Throws tetiso::Error if d < 1 or d exceeds the number of cells. The
    // lattice must outlive the decomposition, which refers to it: a
    // temporary lattice is refused at compile time.
    Decomposition(const Lattice& lattice, int d);
    Decomposition(Lattice&&, int) = delete;

    const Lattice& lattice() const { return lattice_; }
    int domain_count() const { return static_cast<int>(boxes_.size()); }
    const CellBox& box(int domain) const { return boxes_.at(static_cast<std::size_t>(domain)); }

    // Domains that share at least one mesh edge with `domain` (a face or a
    // segment of an edge of its box), sorted.
    const std::vector<int>& neighbours(int domain) const {
        return neighbours_.at(static_cast<std::size_t>(domain));
    }

    // The bisection tree, root first; children come after their parent. Every
    // node covers a box, so the children of a node are adjacent across the
    // cut and their union is convex.
    const std::vector<DomainTreeNode>& tree() const { return tree_; }

    // Domains whose closed box contains the mesh edge between two nodes,
    // sorted. A descent of the bisection tree: O(depth) for an edge inside
    // one domain, so a job's seams ask it of every locked vertex at any
    // domain count.
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const;

    // Builds the nodes, field values and tetrahedra of one domain.
    Domain make_domain(int domain, const Field& field) const;

    // The field values alone, as make_domain gives them (node i + px*(j +
    // py*k) of the box, px and py its nodes per axis): what the GPU needs of
    // a lattice domain whose field it cannot evaluate itself (device.hpp).
    std::vector<float> field_values(int domain, const Field& field) const;

    // Nodes of one domain; throws tetiso::Error when they do not fit int32.
    std::size_t node_count(int domain) const;

    // The faces of a domain's box that are interfaces, not on the cube's
    // surface: bit s for face s (-x, +x, -y, +y, -z, +z).
    std::uint8_t open_faces(int domain) const;

private:
    const Lattice& lattice_;
    std::vector<CellBox> boxes_;
    std::vector<DomainTreeNode> tree_;
    std::vector<CellBox> tree_boxes_; // the box of each tree node
    std::vector<std::vector<int>> neighbours_;
};

// The nodes, field values and tetrahedra of the lattice cells in `box`:
// node i + px*(j + py*k) of the box (px, py its nodes per axis), six
// positively oriented tetrahedra per cell, cells x fastest. A node's
// interface mask has bit s where it lies on face s of the box and bit s of
// open_faces is set (faces -x, +x, -y, +y, -z, +z). Decomposition's
// make_domain is this for a domain's box; any other box gives what a domain
// holds there, bit for bit (tests rebuild one spot of a 10^9-node lattice
// this way). Throws tetiso::Error when the box's nodes do not fit int32.
Domain make_box_domain(const Lattice& lattice, const CellBox& box, const Field& field, std::uint8_t open_faces);

// The lattice test problem as the job's Partition: the lattice, its
// bisection into `domains` boxes and the field, each domain generated on
// demand.
class LatticePartition final : public Partition {
public:
    // Throws tetiso::Error for a lattice or domain count Decomposition refuses.
    LatticePartition(std::int64_t n, int domains, std::unique_ptr<Field> field);
    LatticePartition(const LatticePartition&) = delete; // decomposition_ refers to lattice_
    LatticePartition& operator=(const LatticePartition&) = delete;

    const Lattice& lattice() const { return lattice_; }
    const Decomposition& decomposition() const { return decomposition_; }
    const Field& field() const { return *field_; }

    int domain_count() const override { return decomposition_.domain_count(); }
    const std::vector<int>& neighbours(int domain) const override { return decomposition_.neighbours(domain); }
    const std::vector<DomainTreeNode>& tree() const override { return decomposition_.tree(); }
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override {
        return decomposition_.domains_of_edge(a, b);
    }
    Domain make_domain(int domain) const override { return decomposition_.make_domain(domain, *field_); }
    bool pieces_are_manifold() const override { return true; } // boxes
    double spacing() const override { return lattice_.spacing(); }
    std::int64_t node_count() const override { return lattice_.node_count(); }
    std::int64_t tet_count() const override { return lattice_.tet_count(); }
    std::uint64_t fingerprint() const override;

private:
    Lattice lattice_;
    Decomposition decomposition_;
    std::unique_ptr<Field> field_;
};

} // namespace tetiso
