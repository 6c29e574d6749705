// One lattice box's nodes and tetrahedra, element by element, for the host
// (make_box_domain) and the device (the GPU builds a lattice domain from its
// box alone): node i + px*(j + py*k) of the box, six positively oriented
// tetrahedra per cell, cells x fastest (lattice.hpp).
#pragma once

#include <cstdint>

#include "hd.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::lattice_cells {

struct Box {
    std::int64_t n;           // lattice nodes per axis
    std::int64_t lo[3];       // the box's first node
    std::int64_t nx, ny, nz;  // cells per axis
    std::int64_t px, py;      // nodes per axis (x, y)
    unsigned open_faces;      // the box's faces that are interfaces (bit s: -x, +x, -y, +y, -z, +z)
};

inline Box box_of(const Lattice& lattice, const CellBox& box, std::uint8_t open_faces) {
    Box b{};
    b.n = lattice.n();
    for (int axis = 0; axis < 3; ++axis) b.lo[axis] = box.lo[static_cast<std::size_t>(axis)];
    b.nx = box.hi[0] - box.lo[0];
    b.ny = box.hi[1] - box.lo[1];
    b.nz = box.hi[2] - box.lo[2];
    b.px = b.nx + 1;
    b.py = b.ny + 1;
    b.open_faces = open_faces;
    return b;
}

// Lattice::coordinate: the same double operations, then one rounding.
TETISO_HD inline double coordinate(const Box& b, std::int64_t index) {
    return kLatticeExtent * static_cast<double>(index) / static_cast<double>(b.n - 1);
}

struct Node {
    double x, y, z; // the coordinates, in double (the field is evaluated there)
    GlobalId gid;
    std::uint8_t interface;
};

TETISO_HD inline Node node(const Box& b, std::int64_t v) {
    const std::int64_t i = v % b.px, j = (v / b.px) % b.py, k = v / (b.px * b.py);
    const std::int64_t gi = b.lo[0] + i, gj = b.lo[1] + j, gk = b.lo[2] + k;
    const unsigned faces = (i == 0 ? 1u : 0u) | (i == b.nx ? 2u : 0u) | (j == 0 ? 4u : 0u) | (j == b.ny ? 8u : 0u) |
                           (k == 0 ? 16u : 0u) | (k == b.nz ? 32u : 0u);
    return {coordinate(b, gi), coordinate(b, gj), coordinate(b, gk), gi + b.n * (gj + b.n * gk),
            static_cast<std::uint8_t>(faces & b.open_faces)};
}

// kCellTetOrders' first two axes of tetrahedron t, two bits each, packed so
// the device reads them without a table.
constexpr unsigned pack_orders() {
    unsigned packed = 0;
    for (unsigned t = 0; t < 6; ++t)
        packed |= (static_cast<unsigned>(kCellTetOrders[t][0]) | static_cast<unsigned>(kCellTetOrders[t][1]) << 2) << (4 * t);
    return packed;
}
constexpr unsigned kPackedOrders = pack_orders();

struct Tet {
    std::int32_t v[4];
};

// Tetrahedron t of the box: one per ordering of the axes, each walking from
// the cell's lowest corner to its highest along one monotone path. The split
// is the same in every cell, so shared faces match. An ordering of odd parity
// gives a negatively oriented walk; swapping its middle two vertices makes it
// positive.
TETISO_HD inline Tet tet(const Box& b, std::int64_t t) {
    const std::int64_t cell = t / 6;
    const int which = static_cast<int>(t % 6);
    const std::int64_t i = cell % b.nx, j = (cell / b.nx) % b.ny, k = cell / (b.nx * b.ny);
    const std::int64_t stride[3] = {1, b.px, b.px * b.py};
    const std::int64_t origin = i + b.px * (j + b.py * k);
    const std::int64_t v1 = origin + stride[(kPackedOrders >> (4 * which)) & 3u];
    const std::int64_t v2 = v1 + stride[(kPackedOrders >> (4 * which + 2)) & 3u];
    const bool odd = which >= 3;
    return {{static_cast<std::int32_t>(origin), static_cast<std::int32_t>(odd ? v2 : v1),
             static_cast<std::int32_t>(odd ? v1 : v2), static_cast<std::int32_t>(origin + stride[0] + stride[1] + stride[2])}};
}

} // namespace tetiso::lattice_cells
