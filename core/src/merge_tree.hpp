// Internal: the merge tree over a mesh's domains by heavy-edge matching,
// shared by MeshPartition and PvtuPartition (mesh_partition.hpp explains
// the construction).
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "tetiso/partition.hpp"

namespace tetiso::detail {

// Weight of the domain pair (p, q), p < q: the edges they share.
using PairWeights = std::map<std::pair<int, int>, std::int64_t>;

// The tree over parts 0 .. part_tets.size() - 1 (each with its tetrahedron
// count), root first; appends each leaf's part to `source_id` in leaf order,
// which is the domains' numbering.
void build_merge_tree(const std::vector<std::int64_t>& part_tets, const PairWeights& weights,
                      std::vector<DomainTreeNode>& tree, std::vector<int>& source_id);

} // namespace tetiso::detail
