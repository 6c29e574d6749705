// Gmsh meshes (.msh), formats 4.1 (ascii and binary) and 2.2 (ascii and
// binary), read as the volume mesh of one domain.
//
// Sections read: $MeshFormat, $Nodes, $Elements and $NodeData (the field:
// the view whose first string tag is the requested name; the last one of
// that name when a file holds several time steps). Every other section is
// skipped to its $End line. Node tags may be sparse: nodes are numbered in
// the order of their tags. Elements of dimension 0 to 2 (points, lines,
// boundary triangles and quads) are no volume and are skipped; linear
// tetrahedra are kept; any other volume element is an error naming its
// type and count. Counts are checked against the bytes left before
// anything is allocated, tags against the nodes present, values for NaN and
// infinity.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "tetiso/mesh_file.hpp"

namespace tetiso {

// Reads `path`; `view` names the $NodeData field, empty for none. Throws
// tetiso::Error naming the file and what is wrong.
MeshArrays read_msh(const std::filesystem::path& path, const std::string& view);

// The same from bytes in memory; `name` is used in messages.
MeshArrays parse_msh(std::string_view bytes, const std::string& name, const std::string& view);

} // namespace tetiso
