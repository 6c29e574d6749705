// What the fuzz targets share. Every reader takes a path, so each input is
// written to a file in a scratch directory of this process (under /dev/shm
// where there is one: no disk traffic) and read from there. A reader may
// refuse an input only with tetiso::Error; any other exception, a crash, a
// hang or a sanitizer report is a finding.
#pragma once

#include <stdlib.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace tetiso::fuzz {

inline const std::filesystem::path& scratch() {
    static const std::filesystem::path directory = [] {
        std::string pattern = (std::filesystem::is_directory("/dev/shm") ? std::string("/dev/shm") : std::filesystem::temp_directory_path().string()) +
                              "/tetiso_fuzz.XXXXXX";
        if (!::mkdtemp(pattern.data())) ::abort();
        std::atexit([] { std::error_code ignored; std::filesystem::remove_all(scratch(), ignored); });
        return std::filesystem::path(pattern);
    }();
    return directory;
}

inline std::filesystem::path write_file(const std::string& name, std::string_view bytes) {
    const std::filesystem::path path = scratch() / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) ::abort();
    return path;
}

inline std::string_view bytes_of(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

} // namespace tetiso::fuzz
