// Internal: the format-specific readers and writers behind io.hpp.
#pragma once

#include <filesystem>

#include "tetiso/mesh.hpp"

namespace tetiso::detail {

void write_ply(const Piece& piece, const std::filesystem::path& path);
Piece read_ply(const std::filesystem::path& path);
void write_vtp(const Piece& piece, const std::filesystem::path& path);
Piece read_vtp(const std::filesystem::path& path);

// Checks indices and coordinates and restores the key order; shared by readers.
void validate_and_order(Piece& piece, const std::filesystem::path& path);

} // namespace tetiso::detail
