// VTK XML unstructured grids (.vtu), as VTK, ParaView, meshio and FEniCSx
// write them, read as the volume mesh of one piece.
//
// Every encoding those writers use is read: ascii, inline binary (base64),
// appended raw or base64 data, each optionally zlib-compressed in blocks
// (vtkZLibDataCompressor), with UInt32 or UInt64 block headers, and any of
// VTK's integer and floating-point types in any array (Int32 or Int64
// connectivity, Float32 or Float64 points and fields). The XML is parsed by
// pugixml and the blocks inflated by zlib; only little-endian files are read.
//
// Cells: linear tetrahedra (VTK_TETRA, or VTK_LAGRANGE_TETRAHEDRON with 4
// points, as DOLFINx writes them) are kept; cells of lower dimension
// (vertices, lines, triangles, quads: a solver's boundary markers) are no
// volume and are skipped; any other volume cell is an error naming its type
// and count. Cells marked as ghosts (cell array vtkGhostType, bit
// DUPLICATECELL) belong to another piece and are skipped, so pieces do not
// overlap.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "tetiso/mesh_file.hpp"

namespace tetiso {

// What to read from a piece besides its points and tetrahedra.
struct VtuRequest {
    // The point-data array that is the field; empty: none.
    std::string array;
    // The point-data array of global node ids; empty: the one the file marks
    // as global ids (PointData's GlobalIds attribute), else "GlobalNodeIds",
    // else none.
    std::string node_ids;
    // Whether the ids must be present (a piece of several): without them the
    // error names the integer point arrays the piece has.
    bool require_node_ids = false;
};

// Reads `path`. Throws tetiso::Error naming the file and what is wrong: not
// an unstructured grid, a missing or mistyped array, sizes that disagree
// with the piece's counts or with the data present, a damaged block, an
// index out of range, a coordinate or value that is not finite, a volume
// cell that is not a linear tetrahedron, a node id outside [0, 2^32).
MeshArrays read_vtu(const std::filesystem::path& path, const VtuRequest& request);

// The same from bytes in memory; `name` is used in messages (for tests and
// the fuzzer).
MeshArrays parse_vtu(std::string_view bytes, const std::string& name, const VtuRequest& request);

} // namespace tetiso
