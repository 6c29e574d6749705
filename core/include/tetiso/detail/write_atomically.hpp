#pragma once

#include <atomic>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "tetiso/error.hpp"

namespace tetiso {

namespace detail {
std::filesystem::path temporary_sibling(const std::filesystem::path& path);
}

template <class WriteFunction>
void write_atomically(const std::filesystem::path& path, WriteFunction&& write) {
    const std::filesystem::path temporary = detail::temporary_sibling(path);
    try {
        write(temporary);
        std::error_code ec;
        std::filesystem::rename(temporary, path, ec);
        if (ec) throw Error(path.string() + ": cannot write: " + ec.message());
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove_all(temporary, ignored); // a file, or a directory `write` filled
        throw;
    }
}

} // namespace tetiso
