// Internal: pieces of a mesh, one per solver rank, made domains seamed by
// global node ids (pvtu.hpp explains the rules), whether the pieces come
// from a .pvtu's files (PvtuPartition) or from a solver's ranks in memory
// (tetiso/insitu.hpp). Both go through these functions, so that the same
// pieces give the same domains, edge keys, merge tree and spacing, and the
// two routes the same surface bytes:
//
//   piece_mesh      a piece's arrays as they lie, its used nodes by id
//   scan_piece      its own tetrahedra checked for overlaps, and what its
//                   boundary contributes to the tables
//   pack / unpack   the scans as bytes for the ranks' all-gather
//   PieceTables     the tables built from every piece's scan
//   make_domain     a piece's domain, shared nodes as the tables say
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "pvtu_overlaps.hpp"
#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/partition.hpp"

namespace tetiso::detail {

// A piece's nodes where they lie, not copied: a reader's separate double
// arrays, or a solver's interleaved float or double coordinates, 32- or
// 64-bit ids, float or double values. Everything is read as float (ids as
// GlobalId), as the .pvtu reader always has.
struct PieceNodes {
    std::size_t count = 0;
    const void* coordinate[3] = {nullptr, nullptr, nullptr}; // x, y, z of node 0
    std::size_t stride = 1;                                  // elements from one node's x to the next's
    bool coordinates_double = true;
    const void* ids = nullptr;
    bool ids_64 = true;
    const void* values = nullptr; // none: the field is evaluated (a reader's) or 0 (the scan's)
    bool values_double = true;

    float coordinate_at(int axis, std::size_t i) const {
        const std::size_t at = i * stride;
        return coordinates_double ? static_cast<float>(static_cast<const double*>(coordinate[axis])[at])
                                  : static_cast<const float*>(coordinate[axis])[at];
    }
    float x(std::size_t i) const { return coordinate_at(0, i); }
    float y(std::size_t i) const { return coordinate_at(1, i); }
    float z(std::size_t i) const { return coordinate_at(2, i); }
    GlobalId id(std::size_t i) const {
        return ids_64 ? static_cast<const std::int64_t*>(ids)[i] : static_cast<GlobalId>(static_cast<const std::int32_t*>(ids)[i]);
    }
    float f(std::size_t i) const {
        if (!values) return 0.0f;
        return values_double ? static_cast<float>(static_cast<const double*>(values)[i]) : static_cast<const float*>(values)[i];
    }
};

// The nodes of a reader's arrays (which must have ids).
PieceNodes nodes_of(const MeshArrays& arrays);

// A piece as a task or the scan sees it: its nodes, its tetrahedra without
// ghost cells, and the nodes those use, sorted by id.
struct PieceMesh {
    PieceNodes nodes;
    const std::int32_t* tets = nullptr; // 4 local node indices each, in [0, nodes.count)
    std::size_t tet_count = 0;
    std::vector<std::int32_t> used;
    // Each tetrahedron's number where it differs from its position (a VTK
    // cell index, an index among ghost cells), for messages; null where not.
    const std::uint64_t* numbers = nullptr;
};

// Finds the used nodes; throws tetiso::Error naming `name` where the piece
// has no tetrahedra or an id is given to two used nodes.
PieceMesh piece_mesh(const PieceNodes& nodes, const std::int32_t* tets, std::size_t tet_count, const std::string& name);

// A node on a piece's boundary, as the scan records it.
struct BoundaryNode {
    GlobalId id;
    int piece;
    float x, y, z, f;
    bool operator<(const BoundaryNode& o) const;
};

// What the scan keeps of one piece: counts, a digest (its file's, or 0),
// its share of the spacing, and its boundary; or why it could not be read.
struct PieceScan {
    std::int64_t tets = 0, used = 0;
    double edge_sum = 0;
    std::uint64_t digest = 0;
    std::vector<BoundaryNode> nodes;
    std::vector<std::pair<EdgeKey, int>> edges;
    // The tetrahedra with a face on the boundary, each as its sorted node
    // ids: two pieces that hold one tetrahedron overlap (pvtu_overlaps.hpp).
    std::vector<BoundaryTet> boundary_tets;
    // Its boundary faces by node ids, each with the side its tetrahedron
    // lies on: two pieces on one side of a face fold over each other.
    std::vector<BoundaryFace> faces;
    // Kept by the rank that scanned it, not sent: what lies inside the piece.
    PieceInside inside;
    std::string error;
};

// Piece p's scan. Throws tetiso::Error naming `name` where the piece's own
// tetrahedra overlap (orient_each, face_pass and refuse_clash, the checks
// check_tetrahedra makes of a whole mesh), oriented over float positions as
// a task orients them, so that such a piece is refused before any task.
// Where there are `several` pieces, keeps its inside for the check between
// pieces.
PieceScan scan_piece(const PieceMesh& piece, int p, const std::string& name, bool several);

// A rank's scans (with the error that kept it from scanning, if any) as
// bytes for RankGroup::all_gather.
std::string pack_scans(const std::string& error, const std::vector<std::pair<int, PieceScan>>& scans);

// Every rank's shares back into `scans` (one per piece, sized already).
// Throws tetiso::Error with the first rank's error, else the first piece's
// (in piece order) that could not be scanned.
void unpack_scans(const std::vector<std::string>& shares, std::vector<PieceScan>& scans);

// The tables every rank builds from every piece's scan: the shared nodes
// and the position and value each takes, the shared edges and their
// domains, the merge tree (domain d is piece source_id[d]), neighbours,
// spacing and counts.
class PieceTables {
public:
    PieceTables() = default;
    // `names[p]` names piece p in messages, `whole` all of them (the
    // .pvtu). Where `values` names the field's values (a field given at the
    // nodes, not evaluated at the positions), shared nodes' values must
    // agree too. `inside` holds this rank's pieces' insides (their scans'),
    // `gather` is the ranks' all-gather (every rank calls it once where
    // there are several pieces, to agree on the first piece that reaches
    // inside another). Throws tetiso::Error, the same on every rank, for
    // pieces that overlap (pvtu_overlaps.hpp) or disagree on a shared node.
    // Empties `scans`.
    using Gather = std::function<std::vector<std::string>(const std::string&)>;
    PieceTables(std::vector<PieceScan>& scans, const std::vector<std::string>& names, const std::string& whole,
                const std::string& values, const std::vector<std::pair<int, PieceInside>>& inside, const Gather& gather);

    int domain_count() const { return static_cast<int>(source_id.size()); }
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const;
    // Piece source_id[domain]'s domain. The field is the nodes' values or,
    // without them, `field` at the positions every piece agrees on.
    Domain make_domain(const PieceMesh& piece, int domain, const Field* field, const std::string& name) const;

    std::vector<int> source_id;
    std::vector<DomainTreeNode> tree;
    std::vector<std::vector<int>> neighbours;
    // Edges held by several pieces, by key, with their domains (sorted).
    std::vector<EdgeKey> shared_keys;
    std::vector<std::int64_t> shared_first;
    std::vector<int> shared_domains;
    // Nodes held by several pieces, by id, with the position and value they take.
    std::vector<GlobalId> shared_nodes;
    std::vector<float> shared_xyz;
    std::vector<float> shared_f;
    std::vector<std::uint64_t> digests; // each piece's scan's
    // What was read but is likely not meant: pieces that fall into groups
    // sharing no node id, whose surfaces are then not joined.
    std::vector<std::string> notes;
    double spacing = 0;
    std::int64_t node_count = 0, tet_count = 0;
};

} // namespace tetiso::detail
