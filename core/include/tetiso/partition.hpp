// A tetrahedral mesh split into domains, as the job sees it, whatever made the
// split: the lattice's recursive bisection into boxes (lattice.hpp), or a
// domain id per tetrahedron of an unstructured mesh, from a solver's
// partition file or METIS (mesh_partition.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tetiso/mesh.hpp"

namespace tetiso {

// The domains of the whole mesh that contain the mesh edge between two nodes
// (global ids), sorted.
using EdgeDomains = std::function<std::vector<int>(GlobalId, GlobalId)>;

// One node of a partition's merge tree. It covers domains [first, first +
// count); a leaf (count 1) is one domain, an inner node joins its two
// children, which share at least one mesh edge wherever the mesh allows (two
// parts of a mesh with several components may share none).
struct DomainTreeNode {
    int first = 0;
    int count = 1;
    int left = -1;  // index of the child node, -1 for a leaf
    int right = -1;
};

// 64-bit FNV-1a over what is added, for Partition::fingerprint: a digest to
// tell two ranks' partitions apart, not a defence against anyone.
class Digest {
public:
    template <class T>
    Digest& add(const T* data, std::size_t count) {
        const auto* bytes = reinterpret_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < count * sizeof(T); ++i) value_ = (value_ ^ bytes[i]) * 0x100000001b3ull;
        return *this;
    }
    template <class T>
    Digest& add(const T& value) { return add(&value, 1); }
    Digest& add(const std::string& text) { return add(text.data(), text.size()); }
    std::uint64_t value() const { return value_; }

private:
    std::uint64_t value_ = 0xcbf29ce484222325ull;
};

// The processes that build one partition together, each its share of the
// work, and how they pool what they found: all_gather takes this rank's
// bytes and returns every rank's, in rank order, on every rank (a
// collective call: every rank makes it once). The default is one process.
struct RankGroup {
    int rank = 0;
    int size = 1;
    std::function<std::vector<std::string>(const std::string&)> all_gather;
};

class Partition {
public:
    virtual ~Partition() = default;

    virtual int domain_count() const = 0;
    // Domains that share at least one mesh edge with `domain`, sorted.
    virtual const std::vector<int>& neighbours(int domain) const = 0;
    // The merge tree, root first; children come after their parent, and
    // domain ids are numbered so that every node covers a range of them.
    virtual const std::vector<DomainTreeNode>& tree() const = 0;
    // Domains that hold the mesh edge between two nodes (global ids), sorted.
    virtual std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const = 0;
    // domains_of_edge for every edge that a domain in [first, first + count)
    // holds: all that a seam of those domains asks about (it asks for its
    // locked vertices, whose edges its domains share with others). A
    // partition that keeps no table of the whole mesh's shared edges (a
    // split mesh) loads only that range's; the answer may keep data alive.
    virtual EdgeDomains edge_domains(int first, int count) const {
        (void)first;
        (void)count;
        return [this](GlobalId a, GlobalId b) { return domains_of_edge(a, b); };
    }
    // Builds the nodes, field values, interfaces and tetrahedra of one domain.
    // Several threads may call it at once (run_domain_tasks' lanes do).
    virtual Domain make_domain(int domain) const = 0;
    // Whether every domain's isosurface piece is a 2-manifold (with border),
    // as a convex domain's always is; if not, a domain's reduction must
    // first find where its piece is pinched (reduce_piece).
    virtual bool pieces_are_manifold() const = 0;
    // How `domain` is called in messages and reports.
    virtual std::string domain_name(int domain) const { return "domain " + std::to_string(domain); }

    // The whole mesh's spacing h, the unit of the job's error bound: one
    // value for the whole mesh, so that the bound never depends on the split.
    virtual double spacing() const = 0;
    virtual std::int64_t node_count() const = 0;
    virtual std::int64_t tet_count() const = 0;
    // A digest of everything above that the output depends on, compared
    // between the ranks of a job before it starts.
    virtual std::uint64_t fingerprint() const = 0;
};

} // namespace tetiso
