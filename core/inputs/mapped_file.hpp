// Internal: a regular file's bytes, mapped read-only (no copy, and pages
// the reader never touches are never read), else read whole where mapping
// fails; anything but a regular file is refused (require_regular_file).
// Reading a large piece into a string took as long as all its parsing
// (results/solver-read).
#pragma once

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <string_view>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {

class MappedFile {
public:
    explicit MappedFile(const std::filesystem::path& path) {
        require_regular_file(path);
        // Non-blocking: a pipe put in the file's place since cannot hold the
        // open() up, and is refused below.
        const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
        struct stat info {};
        if (fd >= 0 && ::fstat(fd, &info) == 0 && !S_ISREG(info.st_mode)) {
            ::close(fd);
            throw Error(path.string() + ": not a regular file");
        }
        if (fd >= 0 && info.st_size > 0) {
            void* at = ::mmap(nullptr, static_cast<std::size_t>(info.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
            if (at != MAP_FAILED) {
                map_ = at;
                size_ = static_cast<std::size_t>(info.st_size);
            }
        }
        if (fd >= 0) ::close(fd);
        if (!map_) copy_ = read_whole_file(path); // names the file in its errors
    }
    ~MappedFile() {
        if (map_) ::munmap(map_, size_);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    std::string_view bytes() const {
        return map_ ? std::string_view(static_cast<const char*>(map_), size_) : std::string_view(copy_);
    }

private:
    void* map_ = nullptr;
    std::size_t size_ = 0;
    std::string copy_;
};

} // namespace tetiso::detail
