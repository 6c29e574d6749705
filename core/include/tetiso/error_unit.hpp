// The unit of a reduction's error bound on a surface that comes without a
// lattice spacing (`tetiso reduce`, tetiso.reduce): its mean edge length, so
// that both measure it the same way and give the same bytes.
#pragma once

#include "tetiso/mesh.hpp"

namespace tetiso {

// Mean length of a surface's triangle edges, each edge counted once per
// triangle. 0 for a piece without triangles.
double mean_edge_length(const Piece& piece);

// The default error bound of a reduction that knows no lattice spacing, as a
// fraction of the input's mean edge length.
inline constexpr double kAutoErrorPerEdgeLength = 0.4;

} // namespace tetiso
