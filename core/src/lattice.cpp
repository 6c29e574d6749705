// The lattice test problem and its recursive coordinate bisection (paper,
// section "Testing software implementation": a 5x5x5 cube, N^3 nodes,
// split into 250, 125 or 63 domains).
#include "tetiso/lattice.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "lattice_cells.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Splits `box` (holding `count` domains) recursively and appends the leaves
// in depth-first order, so domain ids follow space and do not depend on
// anything but N and D. Returns the index of the tree node made for `box`,
// whose box goes to tree_boxes[node].
int bisect(const CellBox& box, int count, std::vector<CellBox>& leaves, std::vector<DomainTreeNode>& tree,
           std::vector<CellBox>& tree_boxes) {
    const int node = static_cast<int>(tree.size());
    tree.push_back(DomainTreeNode{static_cast<int>(leaves.size()), count, -1, -1});
    tree_boxes.push_back(box);
    if (count == 1) {
        leaves.push_back(box);
        return node;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (box.hi[a] - box.lo[a] > box.hi[axis] - box.lo[axis]) axis = a;
    const std::int64_t length = box.hi[axis] - box.lo[axis];
    const std::int64_t slab = box.cells() / length; // cells in one slice across the axis

    // Halve the domain count, cut the cells in the same proportion, then
    // re-balance the counts to the slices actually cut, keeping at least one
    // cell per domain on both sides (possible because count <= cells).
    const int half = count / 2;
    const std::int64_t left_length =
        std::clamp<std::int64_t>((length * half + count / 2) / count, 1, length - 1);
    const std::int64_t proportional = (static_cast<std::int64_t>(count) * left_length + length / 2) / length;
    const std::int64_t lowest = std::max<std::int64_t>(1, count - (length - left_length) * slab);
    const std::int64_t highest = std::min<std::int64_t>(left_length * slab, count - 1);
    const int left_count = static_cast<int>(std::clamp(proportional, lowest, highest));

    CellBox left = box, right = box;
    left.hi[axis] = box.lo[axis] + left_length;
    right.lo[axis] = left.hi[axis];
    const int left_node = bisect(left, left_count, leaves, tree, tree_boxes);
    const int right_node = bisect(right, count - left_count, leaves, tree, tree_boxes);
    tree[static_cast<std::size_t>(node)].left = left_node;
    tree[static_cast<std::size_t>(node)].right = right_node;
    return node;
}

// Whether two closed boxes (in node coordinates) share a set of dimension >= 1,
// i.e. at least one mesh edge.
bool share_edges(const CellBox& a, const CellBox& b) {
    int positive = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const std::int64_t lo = std::max(a.lo[axis], b.lo[axis]);
        const std::int64_t hi = std::min(a.hi[axis], b.hi[axis]);
        if (lo > hi) return false;
        if (lo < hi) ++positive;
    }
    return positive >= 1;
}

// The field at the box's nodes, node i + px*(j + py*k) (px, py: nodes per
// axis).
std::vector<float> box_field_values(const Lattice& lattice, const CellBox& box, const Field& field) {
    if (box.nodes() > INT32_MAX)
        throw Error("a box of " + std::to_string(box.nodes()) + " lattice nodes is too large for 32-bit local indices");
    std::vector<float> f(static_cast<std::size_t>(box.nodes()));
    const std::int64_t px = box.hi[0] - box.lo[0] + 1, py = box.hi[1] - box.lo[1] + 1, pz = box.hi[2] - box.lo[2] + 1;
    std::vector<double> xs(static_cast<std::size_t>(px)), ys(xs.size()), zs(xs.size());
    for (std::int64_t i = 0; i < px; ++i) xs[static_cast<std::size_t>(i)] = lattice.coordinate(box.lo[0] + i);
    for (std::int64_t k = 0; k < pz; ++k)
        for (std::int64_t j = 0; j < py; ++j) {
            std::fill(ys.begin(), ys.end(), lattice.coordinate(box.lo[1] + j));
            std::fill(zs.begin(), zs.end(), lattice.coordinate(box.lo[2] + k));
            field.evaluate(xs.data(), ys.data(), zs.data(), xs.size(), f.data() + px * (j + py * k));
        }
    return f;
}

} // namespace

Lattice::Lattice(std::int64_t n) : n_(n) {
    if (n < 2) throw Error("lattice size must be at least 2 nodes per axis, got " + std::to_string(n));
    if (n * n * n - 1 > kMaxGlobalId)
        throw Error("lattice size " + std::to_string(n) + " has more nodes than an edge key can address");
}

Decomposition::Decomposition(const Lattice& lattice, int d) : lattice_(lattice) {
    if (d < 1) throw Error("domain count must be at least 1, got " + std::to_string(d));
    if (d > lattice.cell_count())
        throw Error("cannot split " + std::to_string(lattice.cell_count()) + " cells into " +
                    std::to_string(d) + " domains");
    const std::int64_t cells = lattice.n() - 1;
    bisect(CellBox{{0, 0, 0}, {cells, cells, cells}}, d, boxes_, tree_, tree_boxes_);

    neighbours_.resize(boxes_.size());
    for (std::size_t a = 0; a < boxes_.size(); ++a)
        for (std::size_t b = a + 1; b < boxes_.size(); ++b)
            if (share_edges(boxes_[a], boxes_[b])) {
                neighbours_[a].push_back(static_cast<int>(b));
                neighbours_[b].push_back(static_cast<int>(a));
            }
    for (auto& list : neighbours_) std::sort(list.begin(), list.end());
}

std::vector<int> Decomposition::domains_of_edge(GlobalId a, GlobalId b) const {
    const auto ia = lattice_.node_index(a), ib = lattice_.node_index(b);
    std::array<std::int64_t, 3> lo{}, hi{};
    for (int axis = 0; axis < 3; ++axis) {
        lo[axis] = std::min(ia[axis], ib[axis]);
        hi[axis] = std::max(ia[axis], ib[axis]);
    }
    auto holds = [&](int node) {
        const CellBox& box = tree_boxes_[static_cast<std::size_t>(node)];
        for (int axis = 0; axis < 3; ++axis)
            if (lo[axis] < box.lo[axis] || hi[axis] > box.hi[axis]) return false;
        return true;
    };
    // A box holds the edge only if its parent does, and the children of a
    // node tile it, so the descent reaches every holder and only them; an
    // edge lies in more than one child only on a cut. Left before right
    // gives the leaves, and so the domains, in ascending order.
    // The pending nodes are disjoint subtrees, each with a holder among its
    // leaves, and a lattice edge has at most four holders (the boxes around
    // an axis-parallel segment), so the stack never comes near its size.
    std::vector<int> result;
    if (!holds(0)) return result;
    std::array<int, 64> pending{};
    std::size_t top = 0;
    pending[top++] = 0;
    while (top > 0) {
        const DomainTreeNode& node = tree_[static_cast<std::size_t>(pending[--top])];
        if (node.left < 0) {
            result.push_back(node.first);
            continue;
        }
        if (top + 2 > pending.size()) throw std::logic_error("Decomposition::domains_of_edge: tree descent overflow");
        if (holds(node.right)) pending[top++] = node.right;
        if (holds(node.left)) pending[top++] = node.left;
    }
    return result;
}

std::size_t Decomposition::node_count(int domain) const {
    const std::int64_t nodes = boxes_.at(static_cast<std::size_t>(domain)).nodes();
    if (nodes > INT32_MAX)
        throw Error("domain " + std::to_string(domain) + " has too many nodes for 32-bit local indices");
    return static_cast<std::size_t>(nodes);
}

std::uint8_t Decomposition::open_faces(int domain) const {
    const CellBox& box = boxes_.at(static_cast<std::size_t>(domain));
    const std::int64_t last = lattice_.n() - 1;
    return static_cast<std::uint8_t>((box.lo[0] > 0 ? 1u : 0u) | (box.hi[0] < last ? 2u : 0u) |
                                     (box.lo[1] > 0 ? 4u : 0u) | (box.hi[1] < last ? 8u : 0u) |
                                     (box.lo[2] > 0 ? 16u : 0u) | (box.hi[2] < last ? 32u : 0u));
}

// Both call node_count first: it refuses a domain too large for 32-bit
// indices by its number, where the box's own check could not name it.
std::vector<float> Decomposition::field_values(int domain, const Field& field) const {
    node_count(domain);
    return box_field_values(lattice_, boxes_[static_cast<std::size_t>(domain)], field);
}

Domain Decomposition::make_domain(int domain, const Field& field) const {
    node_count(domain);
    Domain out = make_box_domain(lattice_, boxes_[static_cast<std::size_t>(domain)], field, open_faces(domain));
    out.id = domain;
    return out;
}

Domain make_box_domain(const Lattice& lattice, const CellBox& box, const Field& field, std::uint8_t open_faces) {
    const lattice_cells::Box b = lattice_cells::box_of(lattice, box, open_faces);
    Domain out;
    out.f = box_field_values(lattice, box, field);
    const std::size_t nodes = out.f.size();
    out.x.resize(nodes);
    out.y.resize(nodes);
    out.z.resize(nodes);
    out.gid.resize(nodes);
    out.interface.resize(nodes);
    for (std::size_t v = 0; v < nodes; ++v) {
        const lattice_cells::Node node = lattice_cells::node(b, static_cast<std::int64_t>(v));
        out.x[v] = static_cast<float>(node.x);
        out.y[v] = static_cast<float>(node.y);
        out.z[v] = static_cast<float>(node.z);
        out.gid[v] = node.gid;
        out.interface[v] = node.interface;
    }
    const auto tets = static_cast<std::size_t>(b.nx * b.ny * b.nz) * 6;
    out.tets.resize(4 * tets);
    for (std::size_t t = 0; t < tets; ++t) {
        const lattice_cells::Tet tet = lattice_cells::tet(b, static_cast<std::int64_t>(t));
        for (int c = 0; c < 4; ++c) out.tets[4 * t + static_cast<std::size_t>(c)] = tet.v[c];
    }
    return out;
}

LatticePartition::LatticePartition(std::int64_t n, int domains, std::unique_ptr<Field> field)
    : lattice_(n), decomposition_(lattice_, domains), field_(std::move(field)) {
    if (!field_) throw Error("LatticePartition: no field");
}

std::uint64_t LatticePartition::fingerprint() const {
    return Digest().add(lattice_.n()).add(decomposition_.domain_count()).add(field_->description()).value();
}

} // namespace tetiso
