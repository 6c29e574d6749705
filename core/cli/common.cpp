// Helpers shared by the subcommands: output checks and reports.
#include <cerrno>
#include <charconv>
#include <cstring>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <vector>

#include <unistd.h>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/pvtu.hpp"

namespace tetiso::cli {

namespace {

// The value as a double, or nullopt when it is not a number at all.
std::optional<double> number(const std::string& text) {
    double value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec == std::errc::result_out_of_range) return text.front() == '-' ? -HUGE_VAL : HUGE_VAL;
    if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
    return value;
}

} // namespace

const CLI::Validator& domain_count_check() {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value || *value != std::floor(*value)) return "'" + text + "' is not a whole number";
            if (*value < 1) return "must be at least 1, not " + text;
            if (*value > std::numeric_limits<int>::max()) return text + " is too many";
            return {};
        },
        "INT >= 1", "domain count");
    return check;
}

const CLI::Validator& error_bound_check() {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value) return "'" + text + "' is not a number";
            if (!std::isfinite(*value)) return text + " is not a finite bound (0 means none)";
            if (*value < 0) return "must be at least 0, not " + text;
            return {};
        },
        "FLOAT >= 0", "error bound");
    return check;
}

void add_threads_option(CLI::App& cmd, int& threads, const std::string& description) {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value || *value != std::floor(*value)) return "'" + text + "' is not a whole number";
            if (*value < 0 || *value > kMaxThreads)
                return text + " is outside 0 (all cores) to " + std::to_string(kMaxThreads);
            return {};
        },
        "0.." + std::to_string(kMaxThreads), "thread count");
    cmd.add_option("--threads", threads, description)->check(check)->capture_default_str();
}

void add_level_option(CLI::App& cmd, std::optional<double>& level, const std::string& description) {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value) return "'" + text + "' is not a number";
            if (std::isnan(*value)) return "a level must be a number, not " + text;
            if (std::abs(*value) > std::numeric_limits<float>::max())
                return text + " does not fit a float (the field's values are floats, of magnitude at most 3.4e38)";
            return {};
        },
        "FLOAT", "level");
    cmd.add_option_function<double>(
           "--level", [&level](double value) { level = value; }, description)
        ->check(check);
}

void require_writable(const std::filesystem::path& path) {
    std::filesystem::path directory = detail::output_target(path).parent_path();
    if (directory.empty()) directory = ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(directory, ec))
        throw Error(path.string() + ": cannot write: directory " + directory.string() + " does not exist");
    if (::access(directory.c_str(), W_OK) != 0)
        throw Error(path.string() + ": cannot write: directory " + directory.string() + " is not writable");
    if (std::filesystem::is_directory(path, ec)) throw Error(path.string() + ": cannot write: it is a directory");
}

void require_distinct_files(const std::vector<NamedFile>& outputs, const std::vector<NamedFile>& inputs) {
    const auto describe = [](const NamedFile& file) { return file.path.string() + " (" + file.option + ")"; };
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        if (outputs[i].path.empty()) continue; // an output not asked for
        const std::filesystem::path target = detail::output_target(outputs[i].path);
        for (std::size_t j = 0; j < i; ++j)
            if (!outputs[j].path.empty() && detail::same_file(detail::output_target(outputs[j].path), target))
                throw Error(describe(outputs[i]) + ": cannot write: it is the same file as the output " +
                            describe(outputs[j]) + "; give each output a path of its own");
        for (const NamedFile& input : inputs)
            if (detail::same_file(input.path, target))
                throw Error(describe(outputs[i]) + ": cannot write: it is the same file as the input " +
                            describe(input) + ", which it would replace");
    }
}

std::vector<NamedFile> mesh_files(const std::filesystem::path& mesh) {
    std::vector<NamedFile> files;
    switch (mesh_format(mesh)) {
    case MeshFormat::tetgen: {
        const std::string extension = mesh.extension().string();
        const std::filesystem::path base =
            extension == ".node" || extension == ".ele" ? mesh.parent_path() / mesh.stem() : mesh;
        files.push_back({"--mesh", base.string() + ".node"});
        files.push_back({"--mesh", base.string() + ".ele"});
        break;
    }
    case MeshFormat::pvtu:
        files.push_back({"--mesh", mesh});
        for (const std::filesystem::path& piece : read_pvtu_index(mesh).pieces)
            files.push_back({"a piece of --mesh", piece});
        break;
    default: files.push_back({"--mesh", mesh});
    }
    return files;
}

std::vector<NamedFile> split_files(const std::filesystem::path& dir) {
    std::vector<NamedFile> files;
    std::error_code ec;
    std::filesystem::directory_iterator entries(dir, ec);
    if (ec) return files; // the split's reader says what is wrong with it
    for (; entries != std::filesystem::directory_iterator(); entries.increment(ec)) {
        if (ec) break;
        files.push_back({"a file of --split", entries->path()});
    }
    return files;
}

void write_report(const nlohmann::json& report, const std::filesystem::path& path, OutputFiles& output) {
    output.add(path, [&](const std::filesystem::path& temporary) {
        std::ofstream file(temporary, std::ios::trunc);
        if (!file) throw Error(path.string() + ": cannot open for writing: " + std::strerror(errno));
        file << report.dump(2) << '\n';
        file.close();
        if (!file) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
    });
}

void add_device_options(CLI::App& cmd, DeviceChoice& choice, const std::string& what, bool automatic) {
    std::vector<std::string> devices{"cpu", "gpu"};
    std::string help = "Where " + what + " run: cpu, or gpu (CUDA; the same bytes either way)";
    if (automatic) {
        choice.device = "auto";
        devices.push_back("auto");
        help = "Where " + what + " run: cpu, gpu (CUDA), or auto (each task where its node's resource manager "
               "predicts it ends first: the CPU or any of the node's GPUs; the CPU alone where there is no GPU); "
               "the same bytes every way";
    }
    cmd.add_option("--device", choice.device, help)->check(CLI::IsMember(devices))->capture_default_str();
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

void note_empty_surface(double level, float lowest, float highest) {
    std::cerr << "tetiso: the surface is empty: level " << level;
    if (lowest <= highest)
        std::cerr << (level < lowest || level > highest ? " is outside" : " is within") << " the field's range ["
                  << lowest << ", " << highest << "]";
    std::cerr << '\n';
}

double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

} // namespace tetiso::cli
