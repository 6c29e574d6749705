// Format dispatch, atomic writes, and the checks every reader applies.
#include "tetiso/io.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

namespace detail {

std::filesystem::path temporary_sibling(const std::filesystem::path& path) {
    // Same directory, so the final rename is atomic; a random suffix so that
    // concurrent writers of different outputs never collide.
    static thread_local std::mt19937_64 random{std::random_device{}()};
    std::filesystem::path temporary = path;
    temporary += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(random() % 1000000007u);
    return temporary;
}

std::ifstream open_for_reading(const std::filesystem::path& path) {
    std::error_code error;
    if (std::filesystem::is_directory(path, error)) throw Error(path.string() + ": is a directory, not a file");
    std::ifstream file(path, std::ios::binary);
    if (!file) throw Error(path.string() + ": cannot open for reading");
    return file;
}

std::string read_whole_file(const std::filesystem::path& path) {
    std::ifstream file = open_for_reading(path);
    std::error_code error;
    std::string bytes;
    if (std::filesystem::is_regular_file(path, error)) {
        const std::uintmax_t size = std::filesystem::file_size(path, error);
        if (error) throw Error(path.string() + ": cannot read its size (" + error.message() + ")");
        bytes.resize(static_cast<std::size_t>(size));
        file.read(bytes.data(), static_cast<std::streamsize>(size));
        if (file.gcount() != static_cast<std::streamsize>(size))
            throw Error(path.string() + ": cannot read it whole (it changed while being read?)");
    } else { // a pipe or a device: no size to ask for
        bytes.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    }
    if (file.bad()) throw Error(path.string() + ": read failed");
    return bytes;
}

void validate_and_order(Piece& piece, const std::filesystem::path& path) {
    const std::size_t n = piece.vertex_count();
    for (std::size_t v = 0; v < n; ++v)
        if (!std::isfinite(piece.x[v]) || !std::isfinite(piece.y[v]) || !std::isfinite(piece.z[v]))
            throw Error(path.string() + ": vertex " + std::to_string(v) + " has a coordinate that is not finite");
    for (std::size_t c = 0; c < piece.triangles.size(); ++c) {
        const std::int32_t v = piece.triangles[c];
        if (v < 0 || static_cast<std::size_t>(v) >= n)
            throw Error(path.string() + ": triangle " + std::to_string(c / 3) + " refers to vertex " +
                        std::to_string(v) + " but there are only " + std::to_string(n) + " vertices");
    }
    if (!order_by_key(piece)) throw Error(path.string() + ": two vertices have the same key");
}

} // namespace detail

SurfaceFormat surface_format(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (extension == ".ply") return SurfaceFormat::ply;
    if (extension == ".vtp") return SurfaceFormat::vtp;
    throw Error(path.string() + ": unknown surface format (use .ply or .vtp)");
}

void write_piece(const Piece& piece, const std::filesystem::path& path) {
    const SurfaceFormat format = surface_format(path);
    // Both writers lay the bounds out one per triangle.
    if (!piece.error.empty() && piece.error.size() != piece.triangle_count())
        throw Error(path.string() + ": error bounds and triangles differ in number");
    write_atomically(path, [&](const std::filesystem::path& temporary) {
        if (format == SurfaceFormat::ply)
            detail::write_ply(piece, temporary);
        else
            detail::write_vtp(piece, temporary);
    });
}

Piece read_piece(const std::filesystem::path& path) {
    Piece piece = surface_format(path) == SurfaceFormat::ply ? detail::read_ply(path) : detail::read_vtp(path);
    detail::validate_and_order(piece, path);
    return piece;
}

} // namespace tetiso
