// An unstructured mesh stored as one file per domain, so that a job never
// holds more than the domain a task needs.
//
// A solver's large mesh comes split: each of its ~1000 processes writes its
// own part. MeshPartition (mesh_partition.hpp) holds the whole mesh on every
// rank, which bounds a job by one node's memory. `write_mesh_split` turns a
// MeshPartition into a directory that a job reads piecewise instead:
//
//   DIR/index.tetiso     what every rank needs before any task, a few
//                        numbers per domain: counts, spacing, the
//                        fingerprint, the merge tree, the neighbours, each
//                        domain's name and its two files' digests;
//   DIR/domain-K.tetiso  domain K as MeshPartition::make_domain gives it:
//                        nodes, field values, global ids, interface marks,
//                        shared edges and tetrahedra;
//   DIR/edges-K.tetiso   the edges domain K shares, each with the domains
//                        that hold it, which a seam of K's piece needs.
//
// SplitMeshPartition reads the index when built, a domain file when its
// domain is made, and a seam's edge files when the seam asks (edge_domains),
// so no rank holds a table of the whole mesh's interfaces either: a worker's
// memory is the index plus one domain's task. The job over a split is the job
// over the MeshPartition it was written from, bit for bit: the domains, tree,
// spacing, fingerprint and shared edges are the same.
//
// The files are binary, little-endian, each a header (a magic string naming
// the kind of file and a format version), counts, flat arrays, and a 64-bit
// digest of everything before it (split_digest: xxHash's XXH3, chosen over a
// byte-wise FNV-1a because it digests a large file at memory speed). A reader
// checks every count against the file's size before allocating, every index
// against its range, and the digest, and names the file in any error; a
// domain or edge file must also carry the digest the index lists for it, so
// files of two different splits never mix.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "tetiso/mesh.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/partition.hpp"

namespace tetiso {

// Writes `partition` (a MeshPartition, or a PvtuPartition, which reads one
// piece at a time, so that a solver's .pvtu is scanned once for many jobs)
// to the directory `dir`, which must not exist or be
// empty. `default_level` is the isosurface level a job over the split takes
// when none is given: the analytic field's own, 0 for a node attribute (the
// values are stored, the field is not). Everything is written beside `dir`
// first and renamed at the end: on failure (tetiso::Error naming the path)
// nothing is left at `dir`.
void write_mesh_split(const Partition& partition, double default_level, const std::filesystem::path& dir);

// Throws tetiso::Error unless `dir` is absent or an empty directory: what
// write_mesh_split requires, to be asked before the work that precedes it.
void require_new_split_directory(const std::filesystem::path& dir);

class SplitMeshPartition final : public Partition {
public:
    // Reads DIR/index.tetiso; throws tetiso::Error naming the file for
    // anything missing, truncated, damaged or out of range.
    explicit SplitMeshPartition(std::filesystem::path dir);

    int domain_count() const override { return static_cast<int>(names_.size()); }
    const std::vector<int>& neighbours(int domain) const override {
        return neighbours_.at(static_cast<std::size_t>(domain));
    }
    const std::vector<DomainTreeNode>& tree() const override { return tree_; }
    // For an edge that two or more domains share, as MeshPartition answers;
    // for any other, empty: the split keeps no mesh to look it up in, and a
    // job asks only about locked vertices, which lie on shared edges. The
    // first call reads every edge file; a job calls edge_domains instead.
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override;
    // Reads the edge files of domains [first, first + count) (throws
    // tetiso::Error naming one that is missing or damaged).
    EdgeDomains edge_domains(int first, int count) const override;
    // Reads DIR/domain-K.tetiso; throws tetiso::Error naming it.
    Domain make_domain(int domain) const override;
    bool pieces_are_manifold() const override { return false; }
    std::string domain_name(int domain) const override;
    double spacing() const override { return spacing_; }
    std::int64_t node_count() const override { return node_count_; }
    std::int64_t tet_count() const override { return tet_count_; }
    std::uint64_t fingerprint() const override { return fingerprint_; }

    // The level the split was written with (see write_mesh_split).
    double default_level() const { return default_level_; }
    const std::filesystem::path& directory() const { return dir_; }

private:
    std::filesystem::path dir_;
    std::int64_t node_count_ = 0, tet_count_ = 0;
    double spacing_ = 0, default_level_ = 0;
    std::uint64_t fingerprint_ = 0;
    std::vector<DomainTreeNode> tree_;
    std::vector<std::vector<int>> neighbours_;
    std::vector<std::string> names_;
    std::vector<std::uint64_t> domain_digests_, edge_digests_;
    // Every domain's shared edges, for domains_of_edge, read on first use.
    mutable std::once_flag all_edges_once_;
    mutable EdgeDomains all_edges_;
};

// The file of domain `domain` in a split directory.
std::filesystem::path split_domain_file(const std::filesystem::path& dir, int domain);
// The digest a split file ends with, of the bytes before it.
std::uint64_t split_digest(const void* data, std::size_t size);

// The file of domain `domain`'s shared edges in a split directory.
std::filesystem::path split_edges_file(const std::filesystem::path& dir, int domain);
// The index file of a split directory.
std::filesystem::path split_index_file(const std::filesystem::path& dir);

} // namespace tetiso
