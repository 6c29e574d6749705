// What every simplification baseline's adapter does to a Piece on the way in
// and out: check its arrays, and compact the surviving vertices back into a
// Piece in input order, which keeps their keys sorted and unique.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::reference {

// Throws tetiso::Error, naming `who`, when the piece's arrays disagree in
// length or a triangle refers to a vertex that does not exist.
inline void check_piece_arrays(const char* who, const Piece& piece) {
    const std::size_t n = piece.vertex_count();
    if (piece.x.size() != n || piece.y.size() != n || piece.z.size() != n || piece.flags.size() != n)
        throw Error(std::string(who) + ": vertex arrays of the piece differ in length");
    if (piece.triangles.size() % 3 != 0) throw Error(std::string(who) + ": triangle array is not a multiple of 3");
    for (std::size_t i = 0; i < piece.triangles.size(); ++i) {
        const std::int32_t corner = piece.triangles[i];
        if (corner < 0 || static_cast<std::size_t>(corner) >= n)
            throw Error(std::string(who) + ": triangle " + std::to_string(i / 3) + " refers to vertex " +
                        std::to_string(corner) + ", the piece has " + std::to_string(n));
    }
}

// The vertices v of `piece` with renumber[v] >= 0, in input order, with their
// keys and flags; renumber[v] becomes each one's index in the result.
// position(v, x, y, z) sets where a survivor now lies (a baseline may have
// moved it). Triangles are left to the caller; domains are copied.
template <class Position>
Piece survivors(const Piece& piece, std::vector<std::int32_t>& renumber, const Position& position) {
    Piece out;
    out.domains = piece.domains;
    for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
        if (renumber[v] < 0) continue;
        renumber[v] = static_cast<std::int32_t>(out.key.size());
        float x = 0, y = 0, z = 0;
        position(v, x, y, z);
        out.x.push_back(x);
        out.y.push_back(y);
        out.z.push_back(z);
        out.key.push_back(piece.key[v]);
        out.flags.push_back(piece.flags[v]);
    }
    return out;
}

} // namespace tetiso::reference
