// Internal: the merge tree over a mesh's domains by heavy-edge matching,
// and the shared-edge tables it is built from, shared by MeshPartition and
// PvtuPartition (mesh_partition.hpp explains the construction).
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

// From `holders`, every (edge, part) pair sorted and without repeats: the
// edges that several parts hold, appended to `keys`; each one's parts
// (ascending) appended to `parts`, edge e's from first[e] to first[e + 1]
// (`first` gets its leading 0 here); and each pair of parts' shared-edge
// count added to `weights`.
void group_shared_edges(const std::vector<std::pair<EdgeKey, int>>& holders, std::vector<EdgeKey>& keys,
                        std::vector<std::int64_t>& first, std::vector<int>& parts, PairWeights& weights);

// Each domain's neighbours, sorted: the pairs of `weights` (parts by source
// id) renumbered by `domain_of_source`.
std::vector<std::vector<int>> neighbour_lists(const PairWeights& weights, const std::vector<int>& domain_of_source);

} // namespace tetiso::detail
