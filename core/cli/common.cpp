// Helpers shared by the subcommands: output checks and reports.
#include <chrono>
#include <fstream>

#include <unistd.h>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

namespace tetiso::cli {

void require_writable(const std::filesystem::path& path) {
    std::filesystem::path directory = path.parent_path();
    if (directory.empty()) directory = ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(directory, ec))
        throw Error(path.string() + ": cannot write: directory " + directory.string() + " does not exist");
    if (::access(directory.c_str(), W_OK) != 0)
        throw Error(path.string() + ": cannot write: directory " + directory.string() + " is not writable");
    if (std::filesystem::is_directory(path, ec)) throw Error(path.string() + ": cannot write: it is a directory");
}

void write_report(const nlohmann::json& report, const std::filesystem::path& path) {
    write_atomically(path, [&](const std::filesystem::path& temporary) {
        std::ofstream file(temporary, std::ios::trunc);
        if (!file) throw Error(path.string() + ": cannot open for writing");
        file << report.dump(2) << '\n';
        file.close();
        if (!file) throw Error(path.string() + ": write failed");
    });
}

double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

} // namespace tetiso::cli
