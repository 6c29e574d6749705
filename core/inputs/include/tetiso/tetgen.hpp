// Unstructured tetrahedral meshes in TetGen's file format (BASE.node and
// BASE.ele, as written by `tetgen`), read as one Domain so that everything
// after it — extraction, reduction, checks — runs as on the lattice.
//
// The whole mesh is one domain: global node ids are the file's node numbers
// minus the first one, no node lies on an interface. The nodal field is
// either an analytic Field evaluated at the nodes, or one of the nodes'
// attributes (TetGen's per-node attribute columns), which is how a solver's
// result comes in. Tetrahedra are reoriented where needed so that all are
// positively oriented, as extraction requires; second-order elements (10
// nodes) are read by their four corners.
#pragma once

#include <filesystem>
#include <optional>

#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

struct TetgenSource {
    // The mesh's base name: reads base + ".node" and base + ".ele".
    std::filesystem::path base;
    // The field: attribute column `attribute` (0-based) of the .node file when
    // set, else `field` evaluated at the node positions.
    std::optional<int> attribute;
    const Field* field = nullptr;
};

// Throws tetiso::Error naming the file and line for anything malformed: a
// missing file or header, counts that disagree with the lines present, node
// numbers that are not consecutive, a tetrahedron that refers to a node that
// does not exist or repeats one, coordinates or values that are not finite,
// more nodes or tetrahedra than one domain's 32-bit indices can hold, or an
// attribute the file lacks.
Domain read_tetgen(const TetgenSource& source);

} // namespace tetiso
