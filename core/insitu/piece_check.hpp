// Internal: a rank's piece as the solver handed it (InSituPiece), checked
// as the .vtu reader checks a file's arrays, and seen through the functions
// every piece goes through (core/inputs/piece_tables.hpp) without copying
// the solver's arrays.
#pragma once

#include <cstdint>
#include <vector>

#include "piece_tables.hpp"
#include "tetiso/insitu.hpp"

namespace tetiso::insitu {

struct CheckedPiece {
    std::vector<std::int32_t> kept;     // the tetrahedra that are no ghosts, where a mask was given
    std::vector<std::uint64_t> numbers; // their places among all, ghosts too
    detail::PieceMesh mesh;         // views of the solver's arrays (and of `kept`)
};

// Throws tetiso::Error naming the array and element at fault: a type not
// offered, a size that disagrees, a null array, a coordinate or value not
// finite in float range, a node id outside [0, 2^32) or twice in the
// piece, a corner out of range or repeated, no tetrahedra besides ghosts.
// Tetrahedra that overlap (listed twice, inverted) are refused by the scan
// (detail::scan_piece), with the same checks and words as the .pvtu route.
// The result views `piece`'s arrays: they must outlive it.
CheckedPiece check_piece(const InSituPiece& piece);

} // namespace tetiso::insitu
