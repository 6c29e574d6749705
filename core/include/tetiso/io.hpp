// Reading and writing surfaces. Two formats, chosen by file extension:
//  - .ply: binary little-endian PLY; vertex key as two uint32 properties
//    (tetiso_key_hi, tetiso_key_lo) and flags as uchar (tetiso_flags), which
//    PLY readers that do not know them ignore;
//  - .vtp: VTK XML PolyData, raw appended binary, opened by ParaView;
//    tetiso_key (UInt64) and tetiso_flags (UInt8) are point data arrays.
// Readers take only these names as tetiso's data: another tool's "flags" or
// "key" is skipped like any property they do not know.
// Writers never leave a partial file: they write to a temporary name in the
// same directory and rename it at the end (through a symbolic link, to the
// file it names; a device, pipe or socket at the path is refused, never
// replaced). Readers check every count against the file and every index
// against the vertex count.
#pragma once

#include <filesystem>

#include "tetiso/mesh.hpp"

namespace tetiso {

enum class SurfaceFormat { ply, vtp };

// Throws tetiso::Error naming the path if its extension is neither.
SurfaceFormat surface_format(const std::filesystem::path& path);

// Throws tetiso::Error naming the path if it cannot be written; in that case
// nothing is left at `path` (an earlier file there is kept unchanged). Both
// formats hold positions, keys, flags, triangles and, where the piece has
// them, each triangle's error bound (Piece::error: a VTP cell array or a PLY
// face property named "tetiso_error_bound"), which reads back so that a later
// reduction spends only what is left of it.
void write_piece(const Piece& piece, const std::filesystem::path& path);

class OutputFiles;
// The same as one of several outputs that succeed or fail together: the
// file is in place once `output.commit()` returns.
void write_piece(const Piece& piece, const std::filesystem::path& path, OutputFiles& output);

// Reads a surface written by tetiso or, for PLY, by other tools (ascii or
// binary, float or double coordinates, any integer list type for faces;
// polygons are fanned into triangles). Vertices without keys get keys 0..n-1.
// Vertices are reordered by key if needed so that the Piece invariant holds.
// Throws tetiso::Error naming the path and what is wrong.
Piece read_piece(const std::filesystem::path& path);

// Runs `write` with a temporary path beside `path` and renames the result to
// `path` once `write` returns; removes the temporary file if it throws.
template <class WriteFunction>
void write_atomically(const std::filesystem::path& path, WriteFunction&& write);

} // namespace tetiso

#include "tetiso/detail/write_atomically.hpp"
