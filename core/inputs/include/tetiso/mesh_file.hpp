// A solver's mesh file, whatever its format, read as one Domain: the entry
// point of `--mesh PATH` in extract, run and split, which picks the reader by
// the path's extension.
//
//   .vtu          a VTK XML unstructured grid (io_vtu.hpp);
//   .pvtu         ParaView's partitioned grid: its pieces, matched by global
//                 node ids, joined into one mesh here; `run` instead keeps
//                 each piece a domain (pvtu.hpp);
//   .msh          a Gmsh mesh, format 4.1 (ascii or binary) or 2.2 (io_msh.hpp);
//   anything else TetGen: BASE, BASE.node or BASE.ele (tetgen.hpp).
//
// The field is a named point array (--array NAME: a VTK point-data array, a
// Gmsh $NodeData view), a TetGen node attribute, or an analytic Field
// evaluated at the nodes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

enum class MeshFormat { tetgen, vtu, pvtu, msh };

// By extension: .vtu, .pvtu, .msh, else TetGen.
MeshFormat mesh_format(const std::filesystem::path& path);

struct MeshSource {
    std::filesystem::path path;
    std::optional<int> attribute; // TetGen only: node attribute column K
    std::string array;            // .vtu, .pvtu, .msh: the named point array / $NodeData view
    std::string node_ids;         // .vtu, .pvtu: the point array of global node ids (default: the marked one)
    const Field* field = nullptr; // otherwise: evaluated at the nodes
    // Whether the field comes from the file (then its level is 0 by default).
    bool field_from_file() const { return attribute.has_value() || !array.empty(); }
    // For reports: "attribute K", "array NAME" or the field's description.
    std::string field_description() const;
};

// A volume mesh as a reader found it, before it becomes a Domain: positions
// and values as read (double), tetrahedra as point indices in the file's
// corner order; lower-dimensional and ghost cells already left out.
struct MeshArrays {
    std::vector<double> x, y, z;
    std::vector<double> f;          // the requested array, one value per point; empty if none asked
    std::vector<GlobalId> ids;      // global node ids, one per point; empty if none found
    std::vector<std::int32_t> tets; // 4 point indices each
    std::size_t ghost_cells = 0;    // cells skipped as ghosts
    // Each tetrahedron's number in the file, for messages, where that is not
    // its position among the tetrahedra: the VTK cell index (other cells
    // before it), the Gmsh element tag. Empty where every number is the position.
    std::vector<std::uint64_t> tet_numbers;
    const char* number_word = "cell";
};

// The whole mesh of `source` as one domain: node i has global id i, no node
// lies on an interface, every tetrahedron is positively oriented. Throws
// tetiso::Error naming the file and what is wrong, including options that
// do not apply to the format (an attribute of a VTK file, an array of a
// TetGen one), a field that is neither, and tetrahedra that overlap
// (check_tetrahedra; for a .pvtu, pvtu.hpp). For a .pvtu, `piece_of_tet`
// (where given) receives each tetrahedron's piece, in the file's order.
Domain read_mesh(const MeshSource& source, std::vector<std::int32_t>* piece_of_tet = nullptr);

// A Domain from arrays a reader produced: coordinates stored as float, the
// field taken from `arrays.f` or evaluated by `field` at the coordinates as
// read, tetrahedra reoriented where negative. Node i gets global id i.
// Throws tetiso::Error (naming `name`, the file) for a tetrahedron of zero
// volume or tetrahedra that overlap (check_tetrahedra).
Domain domain_from_arrays(MeshArrays arrays, const Field* field, const std::string& name = "the mesh");

// Whether tetrahedron (a, b, c, d) of `domain` is negatively oriented, in
// double precision over its stored (float) coordinates.
bool negatively_oriented(const Domain& domain, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d);
// Six times the signed volume of tetrahedron (a, b, c, d) of `domain`, in
// double precision over its stored (float) coordinates.
double signed_volume6(const Domain& domain, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d);
// Orients every tetrahedron positively, each by its own corners (two swapped
// where its volume is negative): a mesh listing its tetrahedra in mixed
// corner orders reads right. Throws tetiso::Error naming `name` and the
// tetrahedron (counting tetrahedra only, in the file's order) for one of zero
// volume, which has no orientation. Overlaps are check_tetrahedra's.
void orient_tetrahedra(Domain& domain, const std::string& name);

// orient_tetrahedra, then the check that no two tetrahedra overlap across a
// face, which is what extraction needs for a consistently oriented surface
// (each triangle is wound by its own tetrahedron): two tetrahedra on one
// face must lie on opposite sides of it, and no face may have three. Throws
// tetiso::Error naming `name` and the first tetrahedron in the file's order
// that clashes, by its position and its number in the file (`numbers`,
// MeshArrays::tet_numbers, called `number_word`), and how many faces clash:
// a tetrahedron listed twice; one inverted (its corners listed against the
// orientation most of the mesh's are listed in, and on the same side of a
// face as its neighbour); two that overlap so otherwise; several on one
// face. A mesh listed all in negative order is read (each is oriented by its
// own corners), as is one that mixes orders without folding. Not detected:
// an overlap without such a face, as where the mesh's boundary passes
// through itself (a search in space would be needed). Costs a sort of the
// faces, bucketed by their smallest corner.
void check_tetrahedra(Domain& domain, const std::string& name, const std::vector<std::uint64_t>& numbers = {},
                      const char* number_word = "cell");

} // namespace tetiso
