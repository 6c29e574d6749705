// ParaView's partitioned unstructured grid (.pvtu) as a decomposition: each
// piece (one .vtu per solver rank) is a domain, and pieces are seamed as
// lattice boxes are, by global node ids, never by coordinates.
//
// Before any task, the partition scans every piece once, one at a time (the
// ranks of a job share the pieces out and pool what they found), and
// keeps only what lies on its boundary (faces of one of its tetrahedra
// only): the ids, positions and values of its boundary nodes and the ids of
// its boundary edges. A node or edge that two pieces share lies on both
// boundaries, so these tables give the shared edges, the pieces' adjacency,
// the merge tree (heavy-edge matching, as MeshPartition builds it) and the
// checks between pieces, in memory of the order of the pieces' surfaces. A
// task then reads its piece again, alone. Ghost cells (vtkGhostType) are
// skipped, so pieces do not overlap. The scan refuses a piece whose own
// tetrahedra overlap (check_tetrahedra in mesh_file.hpp: one listed twice,
// an inverted one), tetrahedra of two pieces that lie on one side of the
// face they share (a tangle across pieces), and pieces that overlap each
// other (one listed twice or under two names, one inside another, each
// holding the whole mesh, cells shared but not marked as ghosts) wherever a
// tetrahedron on the boundary of one also lies on the other's boundary or
// reaches inside it (pvtu_overlaps.hpp), naming it, its cell and both
// pieces; pieces that overlap only where both are inside are not found.
// Pieces that share no node id with the rest are read, with a note
// (notes()). The in-situ call (tetiso/insitu.hpp) goes through the same
// scan and checks (core/inputs/piece_tables.hpp), so it refuses the same pieces.
//
// Solvers write a shared node from every rank that holds it, and its
// coordinates and values need not carry the same bits in each: a shared node
// takes the smallest position and value its pieces give (whatever the
// pieces' order), so that every piece places the isosurface vertices on a
// shared edge identically. The copies must agree within a tolerance, the
// same rule for coordinates and values: 1e-4 of the mesh's mean edge length
// for a position, and in any case 4 units of float rounding of the larger
// magnitude; otherwise the pieces are refused, naming the node, both pieces
// and both values to full precision.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/partition.hpp"

namespace tetiso {

namespace detail {
class PieceTables;
}

// The pieces a .pvtu lists (paths resolved against its directory) and the
// name of the array its PPointData marks as global ids (empty if none).
struct PvtuIndex {
    std::vector<std::filesystem::path> pieces;
    std::string global_ids;
};

// Throws tetiso::Error naming the file if it is not a PUnstructuredGrid with
// at least one piece. A collection (a time series, as DOLFINx writes
// NAME.pvtu beside NAME000000.pvtu, ...) stands for its last data set;
// `depth` counts such steps, of which one is followed.
PvtuIndex read_pvtu_index(const std::filesystem::path& path, int depth = 0);

class PvtuPartition final : public Partition {
public:
    // `source.path` is the .pvtu; the field is `source.array` or, without
    // one, `source.field` at the nodes. Throws tetiso::Error naming the
    // file or piece for anything unreadable or inconsistent: a piece
    // missing or without tetrahedra, several pieces without node ids, a
    // node id twice in one piece, a shared node with different values.
    // `field`, where given, is kept and used in place of source.field. The
    // ranks of `group` (an MPI job's) scan every size-th piece each and pool
    // their boundaries, so that every piece is read once in all; the
    // partition is the same for any group.
    explicit PvtuPartition(const MeshSource& source, std::unique_ptr<Field> field = nullptr,
                           const RankGroup& group = {});
    ~PvtuPartition() override;

    int domain_count() const override;
    const std::vector<int>& neighbours(int domain) const override;
    const std::vector<DomainTreeNode>& tree() const override;
    // For an edge two or more pieces share; empty for any other (a job asks
    // only about locked vertices, which lie on shared edges).
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override;
    // Reads the piece's file again; throws tetiso::Error if it changed since.
    Domain make_domain(int domain) const override;
    bool pieces_are_manifold() const override { return false; }
    std::string domain_name(int domain) const override;
    double spacing() const override;
    std::int64_t node_count() const override;
    std::int64_t tet_count() const override;
    std::uint64_t fingerprint() const override { return fingerprint_; }

    // What was read but is likely not meant, each also printed on stderr as
    // "tetiso: note: TEXT" by rank 0 of the group: pieces that fall into
    // groups sharing no node id (a mesh of several bodies, or ids that are
    // not global), whose surfaces are then not joined.
    const std::vector<std::string>& notes() const;

    // The .pvtu's own index of `domain`'s piece.
    int source_id(int domain) const;
    const std::filesystem::path& piece_path(int domain) const;

private:
    std::unique_ptr<Field> field_;
    MeshSource source_;
    std::string ids_name_;
    std::vector<std::filesystem::path> pieces_;
    // The domains, shared nodes and edges, tree and spacing the pieces'
    // scans gave (core/inputs/piece_tables.hpp, shared with the in-situ route).
    std::unique_ptr<detail::PieceTables> tables_;
    std::uint64_t fingerprint_ = 0;
};

} // namespace tetiso
