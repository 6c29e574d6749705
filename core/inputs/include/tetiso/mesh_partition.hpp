// An unstructured tetrahedral mesh split into domains by a domain id per
// tetrahedron, which is how a solver's decomposition comes: read from a
// partition file, or computed here by METIS.
//
// The job needs three things a box decomposition gets from geometry and an
// unstructured one must get from the mesh:
//
//   - which edges lie on an interface, exactly: an edge is shared when the
//     tetrahedra around it belong to more than one domain. A node mask cannot
//     say it (a chord between two interface nodes may run through one
//     domain's inside), so each domain carries the sorted keys of its shared
//     edges (Domain::shared_edges);
//   - which domains hold an edge, to free a vertex once all of them are
//     seamed (domains_of_edge);
//   - a merge tree whose inner nodes join adjacent domain sets. It is built
//     bottom up by heavy-edge matching: at each level every set is paired,
//     smallest first, with the unpaired neighbour it shares the most edges
//     with, so seams are short and the tree is about log2(D) deep.
//
// Domains are renumbered in the order of the tree's leaves, so that every
// tree node covers a range of ids, as the job's task tree requires;
// source_id() gives the partition's own id of each.
//
// The whole mesh is held (each rank of a job that runs over it reads it):
// this suits meshes that fit one node's memory. Beyond that, a partition is
// written once as one file per domain (mesh_split.hpp), and a job's ranks
// read only the domains they work on.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"
#include "tetiso/mesh_file.hpp"

namespace tetiso {

// A partition file: one domain id per tetrahedron, in the order of the mesh's
// .ele file, one per line ('#' starts a comment), ids from 0; METIS's mpmetis
// writes such files (BASE.epart.D). Throws tetiso::Error naming the file and
// line for a line that is not one whole number in [0, 2^31), or a count that
// differs from `tet_count`.
std::vector<std::int32_t> read_partition(const std::filesystem::path& file, std::size_t tet_count);

// Whether this tetiso was built with METIS.
bool have_metis();

// Splits `mesh`'s tetrahedra into `domains` parts with METIS (the dual graph
// of face-sharing tetrahedra, k-way, a fixed seed: the same parts for the
// same mesh, run after run). Throws tetiso::Error if built without METIS, if
// METIS fails, or if it leaves a part empty (more parts than the mesh can
// give).
std::vector<std::int32_t> partition_with_metis(const Domain& mesh, int domains);

class MeshPartition;

// The mesh of `source` (any format read_mesh reads) split by the partition
// file `partition_file` (its domain count must be `domains` unless that is
// 0), or, without one, into `domains` parts by METIS, or, for a .pvtu with
// neither, into its pieces. Throws tetiso::Error for a mesh or partition
// that cannot be read or used, naming the file.
std::unique_ptr<MeshPartition> partition_mesh(const MeshSource& source, const std::filesystem::path& partition_file,
                                              int domains);

class MeshPartition final : public Partition {
public:
    // `mesh` is the whole mesh as one domain (read_mesh); `part` gives each
    // of its tetrahedra a domain id in [0, D), every id used; `source` names
    // where the ids came from, for messages. Throws tetiso::Error if `part`
    // does not fit the mesh.
    MeshPartition(Domain mesh, const std::vector<std::int32_t>& part, std::string source);

    int domain_count() const override { return static_cast<int>(source_id_.size()); }
    const std::vector<int>& neighbours(int domain) const override {
        return neighbours_.at(static_cast<std::size_t>(domain));
    }
    const std::vector<DomainTreeNode>& tree() const override { return tree_; }
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override;
    Domain make_domain(int domain) const override;
    // A domain may touch itself along an edge (METIS's parts need not even
    // be connected).
    bool pieces_are_manifold() const override { return false; }
    std::string domain_name(int domain) const override;
    double spacing() const override { return spacing_; }
    std::int64_t node_count() const override { return static_cast<std::int64_t>(mesh_.node_count()); }
    std::int64_t tet_count() const override { return static_cast<std::int64_t>(mesh_.tet_count()); }
    std::uint64_t fingerprint() const override { return fingerprint_; }

    // The partition's own id of `domain`.
    int source_id(int domain) const { return source_id_.at(static_cast<std::size_t>(domain)); }
    // Tetrahedra in `domain`.
    std::int64_t domain_tet_count(int domain) const;

private:
    Domain mesh_;                          // tetrahedra grouped by domain, in file order within one
    std::vector<std::int64_t> tets_first_; // domain d's tetrahedra: [tets_first_[d], tets_first_[d + 1])
    std::vector<int> source_id_;
    std::vector<DomainTreeNode> tree_;
    std::vector<std::vector<int>> neighbours_;
    // Edges held by more than one domain, by key, with their domains.
    std::vector<EdgeKey> shared_keys_;
    std::vector<std::int64_t> shared_first_;
    std::vector<int> shared_domains_;
    // Each domain's shared edges, sorted by key.
    std::vector<std::int64_t> domain_shared_first_;
    std::vector<EdgeKey> domain_shared_;
    // The tetrahedra around each node, for edges held by one domain.
    std::vector<std::int64_t> node_tets_first_;
    std::vector<std::int32_t> node_tets_;
    double spacing_ = 0;
    std::uint64_t fingerprint_ = 0;
    std::string source_;
};

} // namespace tetiso
