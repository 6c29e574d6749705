// Format dispatch, atomic writes, and the checks every reader applies.
#include "tetiso/io.hpp"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

namespace detail {

namespace {

constexpr char kTemporaryInfix[] = ".tmp.";

const char* kind_of(const std::filesystem::file_status& status) {
    switch (status.type()) {
    case std::filesystem::file_type::character: return "a character device";
    case std::filesystem::file_type::block: return "a block device";
    case std::filesystem::file_type::fifo: return "a pipe";
    case std::filesystem::file_type::socket: return "a socket";
    default: return "neither a regular file nor a directory";
    }
}

} // namespace

std::filesystem::path output_target(const std::filesystem::path& path) {
    // The rename that puts an output in place would replace whatever is at
    // its path: a link by a file (leaving what it pointed to stale), and, as
    // root, a device such as /dev/null by a regular file.
    constexpr int kMostLinks = 40; // as the kernel's ELOOP
    std::filesystem::path target = path;
    std::error_code ec;
    for (int links = 0; std::filesystem::is_symlink(std::filesystem::symlink_status(target, ec)); ++links) {
        if (links == kMostLinks) throw Error(path.string() + ": cannot write: too many levels of symbolic links");
        const std::filesystem::path link = std::filesystem::read_symlink(target, ec);
        if (ec) throw Error(path.string() + ": cannot write: cannot read the link (" + ec.message() + ")");
        target = link.is_absolute() ? link : target.parent_path() / link;
    }
    const std::filesystem::file_status status = std::filesystem::status(target, ec);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status) &&
        !std::filesystem::is_directory(status))
        throw Error(path.string() + ": cannot write: it is " + kind_of(status) +
                    ", which an output would replace; give a regular file");
    return target;
}

std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
    // Same directory, so the final rename is atomic; the process id so that
    // a later run can tell a dead writer's leftovers; a random suffix so that
    // concurrent writers of different outputs never collide.
    static thread_local std::mt19937_64 random{std::random_device{}()};
    std::filesystem::path temporary = target;
    temporary += kTemporaryInfix + std::to_string(::getpid()) + "." + std::to_string(random() % 1000000007u);
    return temporary;
}

void remove_stale_temporaries(const std::filesystem::path& target) {
    const std::string prefix = target.filename().string() + kTemporaryInfix;
    std::filesystem::path directory = target.parent_path();
    if (directory.empty()) directory = ".";
    std::error_code ec;
    std::filesystem::directory_iterator entries(directory, ec);
    if (ec) return; // the write itself will say why the directory is unusable
    // Advanced with an error code: a range-for would throw on a directory
    // that changes or turns unreadable while being listed.
    for (; entries != std::filesystem::directory_iterator(); entries.increment(ec)) {
        if (ec) return;
        const std::filesystem::directory_entry& entry = *entries;
        const std::string name = entry.path().filename().string();
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
        // PID.N, both numbers, and no process PID: its writer is gone.
        const std::string rest = name.substr(prefix.size());
        const std::size_t dot = rest.find('.');
        const auto digits = [](const std::string& s) {
            return !s.empty() && s.size() < 12 && s.find_first_not_of("0123456789") == std::string::npos;
        };
        if (dot == std::string::npos || !digits(rest.substr(0, dot)) || !digits(rest.substr(dot + 1))) continue;
        const long pid = std::stol(rest.substr(0, dot));
        if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) continue;
        if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
        std::error_code ignored;
        std::filesystem::remove_all(entry.path(), ignored);
    }
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
    struct stat at {}, bt {};
    if (::stat(a.c_str(), &at) == 0 && ::stat(b.c_str(), &bt) == 0)
        return at.st_dev == bt.st_dev && at.st_ino == bt.st_ino;
    const auto resolved = [](const std::filesystem::path& path) {
        std::error_code ec;
        std::filesystem::path absolute = std::filesystem::absolute(path, ec);
        if (ec) absolute = path;
        std::filesystem::path canonical = std::filesystem::weakly_canonical(absolute, ec);
        return ec ? absolute.lexically_normal() : canonical;
    };
    return resolved(a) == resolved(b);
}

std::string name_output_in(std::string message, const std::filesystem::path& temporary,
                           const std::filesystem::path& path) {
    const std::string from = temporary.string(), to = path.string();
    for (std::size_t at = message.find(from); at != std::string::npos; at = message.find(from, at + to.size()))
        message.replace(at, from.size(), to);
    return message;
}

void require_regular_file(const std::filesystem::path& path) {
    // A device has no end (/dev/zero, a link to it, a .pvtu piece naming
    // it) and a pipe may never deliver one, nor let open() return.
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(path, error); // through links
    if (std::filesystem::is_directory(status)) throw Error(path.string() + ": is a directory, not a file");
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
        throw Error(path.string() + ": not a regular file (it is " + kind_of(status) + ")");
}

std::ifstream open_for_reading(const std::filesystem::path& path) {
    require_regular_file(path);
    std::ifstream file(path, std::ios::binary);
    if (!file) throw Error(path.string() + ": cannot open for reading");
    return file;
}

std::string read_whole_file(const std::filesystem::path& path) {
    std::ifstream file = open_for_reading(path);
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path, error); // never more than this is read
    if (error) throw Error(path.string() + ": cannot read its size (" + error.message() + ")");
    std::string bytes(static_cast<std::size_t>(size), '\0');
    file.read(bytes.data(), static_cast<std::streamsize>(size));
    if (file.gcount() != static_cast<std::streamsize>(size))
        throw Error(path.string() + ": cannot read it whole (it changed while being read?)");
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

void write_piece(const Piece& piece, const std::filesystem::path& path, OutputFiles& output) {
    const SurfaceFormat format = surface_format(path);
    // Both writers lay the bounds out one per triangle.
    if (!piece.error.empty() && piece.error.size() != piece.triangle_count())
        throw Error(path.string() + ": error bounds and triangles differ in number");
    output.add(path, [&](const std::filesystem::path& temporary) {
        if (format == SurfaceFormat::ply)
            detail::write_ply(piece, temporary);
        else
            detail::write_vtp(piece, temporary);
    });
}

void write_piece(const Piece& piece, const std::filesystem::path& path) {
    OutputFiles output;
    write_piece(piece, path, output);
    output.commit();
}

Piece read_piece(const std::filesystem::path& path) {
    Piece piece = surface_format(path) == SurfaceFormat::ply ? detail::read_ply(path) : detail::read_vtp(path);
    detail::validate_and_order(piece, path);
    return piece;
}

} // namespace tetiso
