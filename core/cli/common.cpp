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

void add_device_options(CLI::App& cmd, DeviceChoice& choice, const std::string& what) {
    cmd.add_option("--device", choice.device,
                   "Where " + what + " run: cpu, or gpu (CUDA; the same bytes either way)")
        ->check(CLI::IsMember({"cpu", "gpu"}))
        ->capture_default_str();
    cmd.add_option("--gpu", choice.gpu, "With --device gpu: which CUDA device (0-based, after CUDA_VISIBLE_DEVICES)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
}

std::unique_ptr<Gpu> open_gpu(const DeviceChoice& choice) {
    if (!choice.on_gpu()) return nullptr;
    const GpuInfo info = gpu_info(choice.gpu);
    if (!info.available) throw Error("--device gpu: " + info.description);
    return std::make_unique<Gpu>(choice.gpu);
}

nlohmann::json device_json(const Gpu* gpu, const GpuTimings& seconds) {
    if (!gpu) return {{"kind", "cpu"}};
    return {{"kind", "gpu"},
            {"index", gpu->device()},
            {"name", gpu->description()},
            {"seconds",
             {{"upload", seconds.upload},
              {"compute", seconds.compute},
              {"download", seconds.download},
              {"extract", seconds.extract},
              {"reduce", seconds.reduce}}}};
}

double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

} // namespace tetiso::cli
