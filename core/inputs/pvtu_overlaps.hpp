// Internal: pieces that overlap (a .pvtu's or the in-situ call's), found
// from what the scan keeps of each (piece_tables.hpp; pvtu.hpp states the
// rules), without any rank holding every piece's cells. `names[p]` names
// piece p in messages.
//
// Pieces that do not overlap meet only on their boundaries. So where a
// tetrahedron on the boundary of piece B also has
//   - a corner inside piece A (on no boundary face of A: A's tetrahedra fill
//     all around it), or
//   - a face inside A (a face of two of A's tetrahedra, one on either side),
// it overlaps A's tetrahedra there; and where it is on A's boundary too, A
// holds it as well. Every tetrahedron two pieces hold is found so, if it
// lies on the boundary of one of them (its corners then all lie on A's
// boundary, or one does not; in the first case its faces are inside A): one
// piece listed twice, under two names, a piece inside another, pieces that
// each hold the whole mesh. Not found: pieces that overlap only where both
// are inside, their shared cells on neither's boundary, which would need
// every piece's cells in one place.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "tetiso/mesh.hpp"

namespace tetiso::detail {

// A tetrahedron by its four global node ids, sorted, and its number in its
// piece (the VTK cell index), for messages.
struct BoundaryTet {
    std::array<GlobalId, 4> ids;
    std::uint64_t cell;
    bool operator<(const BoundaryTet& o) const { return ids < o.ids; }
    bool operator==(const BoundaryTet& o) const { return ids == o.ids; }
};

// A face by its three global node ids, sorted (ids are below 2^32).
using FaceIds = std::array<std::uint32_t, 3>;

// A boundary face by its node ids, sorted, the side its tetrahedron lies
// on (the parity of the permutation from the tetrahedron's corners, oriented
// positively, to the face's sorted corners and the corner it lacks) and that
// tetrahedron's cell. The pieces on either side of a face they share give it
// opposite sides; the same side is a fold between them, where a tangled mesh
// crosses from one piece into another.
struct BoundaryFace {
    FaceIds ids;
    std::uint32_t side;
    std::uint64_t cell;
};

// The boundary face (u, v, w) of the positively oriented tetrahedron
// `corners` (point indices), with its cell number.
BoundaryFace boundary_face(const std::int32_t* corners, const std::array<std::int32_t, 3>& face,
                           const std::vector<GlobalId>& ids, std::uint64_t cell);

// Throws tetiso::Error where two pieces lie on the same side of a face they
// share, or three pieces share a face, naming the face, the pieces and the
// cells. `faces[p]`: piece p's boundary faces.
void refuse_folds_between(const std::vector<std::vector<BoundaryFace>>& faces,
                          const std::vector<std::string>& names);

// What a piece keeps of its inside for the check against the others'
// boundaries: the ids of its nodes on no boundary face, and its faces of
// two tetrahedra whose corners all lie on its boundary (a face with a
// corner inside is found by that corner), both sorted.
struct PieceInside {
    std::vector<GlobalId> nodes;
    std::vector<FaceIds> faces;
};

// The inside of a piece: `tets` over points with global ids `ids`,
// `boundary_faces` its boundary faces (point indices), `used` the points its
// tetrahedra use.
PieceInside piece_inside(const std::vector<std::int32_t>& tets, const std::vector<GlobalId>& ids,
                         const std::vector<std::int32_t>& used, const std::vector<std::array<std::int32_t, 3>>& boundary_faces);

// Throws tetiso::Error naming a tetrahedron on the boundary of two pieces,
// both pieces and its cell in each. `boundary[p]`: piece p's boundary
// tetrahedra, sorted and unique.
void refuse_shared_boundary_tets(const std::vector<std::vector<BoundaryTet>>& boundary,
                                 const std::vector<std::string>& names);

// Where a boundary tetrahedron of any piece reaches inside one of `inside`
// (this rank's pieces, by their index): the first such place in the order
// of (piece, its boundary tetrahedra), as a key to pick the first among
// ranks and the message; an empty message where there is none.
struct InsideOverlap {
    std::int64_t piece = -1;
    std::uint64_t tet = 0;
    std::int64_t other = -1;
    std::string message;
};
InsideOverlap find_inside_overlap(const std::vector<std::pair<int, PieceInside>>& inside,
                                  const std::vector<std::vector<BoundaryTet>>& boundary,
                                  const std::vector<std::string>& names);

} // namespace tetiso::detail
