// Seaming pieces by their vertex keys (paper, section "Isosurface reduction
// and seaming"): two pieces get one numbering by merging their key-sorted
// vertex lists; no coordinates are compared. A vertex keyed by the same edge
// in both pieces becomes one vertex.
#pragma once

#include <functional>
#include <vector>

#include "tetiso/mesh.hpp"

namespace tetiso {

// Merges two pieces covering disjoint sets of domains. Throws tetiso::Error if
// they share a domain, or if a key appears in both with different positions
// (the pieces were not extracted consistently).
Piece merge_by_key(const Piece& a, const Piece& b);

// Merges any number of pieces, pairwise in a balanced tree; the result does
// not depend on the order of `pieces`.
Piece merge_all(std::vector<Piece> pieces);

// The domains of the whole mesh that contain the mesh edge between two nodes.
using EdgeDomains = std::function<std::vector<int>(GlobalId, GlobalId)>;

// Clears kLocked on every vertex whose edge lies in no domain outside
// `piece.domains`: its neighbourhood is complete, so reduction may touch it.
// Returns the number of vertices unlocked.
std::size_t unlock_settled(Piece& piece, const EdgeDomains& domains_of_edge);

} // namespace tetiso
