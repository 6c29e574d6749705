// Internal: the format-specific readers and writers behind io.hpp.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "tetiso/mesh.hpp"

namespace tetiso::detail {

void write_ply(const Piece& piece, const std::filesystem::path& path);
Piece read_ply(const std::filesystem::path& path);
void write_vtp(const Piece& piece, const std::filesystem::path& path);
Piece read_vtp(const std::filesystem::path& path);

// Whether a value read as a double is a whole number in [0, limit): the
// readers hold every number as a double, and converting one that is not
// (a fraction, a NaN, something out of range) to an integer type would be
// undefined rather than an error.
inline bool whole_below(double value, double limit) {
    return value >= 0 && value < limit && value == std::floor(value);
}

// The names of tetiso's own data in both formats. They carry the project's
// prefix because plain names are taken: MeshLab writes a PLY vertex "flags"
// (VCG's selection and deletion bits), which read as tetiso's lock bits
// would pin arbitrary vertices, or fail as "not a byte".
// A vertex's global edge key: one UInt64 VTP point array; two uint32 PLY
// vertex properties, high and low word (PLY has no 64-bit integer type).
inline constexpr char kKeyName[] = "tetiso_key";
inline constexpr char kKeyHighName[] = "tetiso_key_hi";
inline constexpr char kKeyLowName[] = "tetiso_key_lo";
// VertexFlag bits: a VTP point array, a PLY vertex property.
inline constexpr char kFlagsName[] = "tetiso_flags";
// Each triangle's bound on the distance from the raw vertices it stands for
// (Piece::error; a VTP cell array, a PLY face property): ParaView colours a
// surface by it, and reading it back lets a later reduction spend only what
// is left of the bound.
inline constexpr char kErrorBoundName[] = "tetiso_error_bound";

// Throws tetiso::Error naming `path` when it is there but is not a regular
// file, through any links: a directory (which opens on Linux and then fails,
// or reads as empty, only when read), a device such as /dev/zero (no end),
// a pipe (an open() that may never return) or a socket.
void require_regular_file(const std::filesystem::path& path);

// `path` opened for reading in binary mode. Throws tetiso::Error naming it
// when it cannot be opened or is not a regular file (require_regular_file).
std::ifstream open_for_reading(const std::filesystem::path& path);

// The whole file, read in one call: through istreambuf_iterator, byte by
// byte, reading took about twice as long.
// Throws tetiso::Error naming the file when it cannot be opened or read
// (not a regular file, a file that shrinks while read); never reads more
// than the size the file had when opened.
std::string read_whole_file(const std::filesystem::path& path);

// Where an ASCII number starting at `at` begins for std::from_chars: past a
// leading '+' followed by a digit or a point, which C's strtod and scanf
// take (and so VTK, Gmsh and TetGen) and from_chars does not; "+-1" and a
// '+' alone stay refused.
inline const char* past_plus(const char* at, const char* end) {
    return end - at > 1 && *at == '+' && ((at[1] >= '0' && at[1] <= '9') || at[1] == '.') ? at + 1 : at;
}

// Checks indices and coordinates and restores the key order; shared by readers.
void validate_and_order(Piece& piece, const std::filesystem::path& path);

} // namespace tetiso::detail
