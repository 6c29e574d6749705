// A Piece on the wire between ranks, on ByteWriter/ByteReader
// (byte_buffer.hpp): each of its arrays in the order of its fields. The job's
// MPI messages and an in-situ call's seam tree carry pieces so.
#pragma once

#include <cstddef>
#include <cstdint>

#include "byte_buffer.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::detail {

// Bytes that put_piece(piece) appends, for a writer to reserve first.
inline std::size_t piece_byte_size(const Piece& piece) {
    const auto array = [](const auto& v) { return sizeof(std::uint64_t) + v.size() * sizeof(v[0]); };
    return array(piece.x) + array(piece.y) + array(piece.z) + array(piece.key) + array(piece.flags) +
           array(piece.triangles) + array(piece.domains) + array(piece.error) + array(piece.sample_xyz) +
           array(piece.sample_triangle) + array(piece.sampled);
}

template <class Bytes>
void put_piece(ByteWriter<Bytes>& out, const Piece& piece) {
    out.put_array(piece.x);
    out.put_array(piece.y);
    out.put_array(piece.z);
    out.put_array(piece.key);
    out.put_array(piece.flags);
    out.put_array(piece.triangles);
    out.put_array(piece.domains);
    out.put_array(piece.error);
    out.put_array(piece.sample_xyz);
    out.put_array(piece.sample_triangle);
    out.put_array(piece.sampled);
}

inline Piece get_piece(ByteReader& in) {
    Piece piece;
    piece.x = in.get_array<float>();
    piece.y = in.get_array<float>();
    piece.z = in.get_array<float>();
    piece.key = in.get_array<EdgeKey>();
    piece.flags = in.get_array<std::uint8_t>();
    piece.triangles = in.get_array<std::int32_t>();
    piece.domains = in.get_array<int>();
    piece.error = in.get_array<float>();
    piece.sample_xyz = in.get_array<float>();
    piece.sample_triangle = in.get_array<std::int32_t>();
    piece.sampled = in.get_array<std::uint8_t>();
    return piece;
}

} // namespace tetiso::detail
