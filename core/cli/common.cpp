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

// Every integer option, as CLI11 would convert it: "032" as octal, "0x20"
// as hex, "1e3" not at all. Rewritten to plain decimal digits first, so
// that every option reads a number the same way and as a person does.
std::string as_decimal_integer(std::string& text) {
    std::size_t digits = 0;
    const bool negative = !text.empty() && text.front() == '-';
    if (!text.empty() && (text.front() == '-' || text.front() == '+')) digits = 1;
    if (digits == text.size() || text.find_first_not_of("0123456789", digits) != std::string::npos)
        return "'" + text + "' is not a whole number in decimal digits";
    const std::size_t first = std::min(text.find_first_not_of('0', digits), text.size() - 1);
    text = (negative && text.substr(first) != "0" ? "-" : "") + text.substr(first);
    return {};
}

// A file name or array name given empty: CLI11 takes '' as a value.
std::string not_empty(std::string& text) { return text.empty() ? "an empty value names nothing" : std::string{}; }

} // namespace

void require_decimal_integers(CLI::App& app) {
    for (CLI::Option* option : app.get_options()) {
        const std::string type = option->get_type_name();
        if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0)
            option->transform(CLI::Validator(as_decimal_integer, "", "decimal")); // first, before the other checks
    }
    for (CLI::App* command : app.get_subcommands({})) require_decimal_integers(*command);
}

void refuse_meaningless_combinations(CLI::App& app) {
    for (CLI::App* cmd : app.get_subcommands({})) {
        const auto option = [cmd](const char* name) -> CLI::Option* {
            for (CLI::Option* o : cmd->get_options())
                if (o->check_name(name)) return o;
            return nullptr;
        };
        // A field comes from one place: the file's array, a TetGen
        // attribute, or an analytic --field.
        CLI::Option* field = option("--field");
        CLI::Option* array = option("--array");
        CLI::Option* attribute = option("--attribute");
        if (field && array) array->excludes(field);
        if (field && attribute) attribute->excludes(field);
        if (array && attribute) array->excludes(attribute);
        for (const char* name : {"--array", "--node-ids", "--mesh", "--partition", "--split", "--against", "--report",
                                 "-o"})
            if (CLI::Option* o = option(name)) o->check(CLI::Validator(not_empty, "", "not empty"));
        if (CLI::Option* vertices_only = option("--vertices-only"))
            if (CLI::Option* against = option("--against")) vertices_only->needs(against);
    }
}

const CLI::Validator& index_check() {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value || *value != std::floor(*value)) return "'" + text + "' is not a whole number";
            if (*value < 0) return "must be at least 0, not " + text;
            if (*value > std::numeric_limits<int>::max()) return text + " is too large";
            return {};
        },
        "INT >= 0", "index");
    return check;
}

const CLI::Validator& phi_check() {
    static const CLI::Validator check(
        [](std::string& text) -> std::string {
            const std::optional<double> value = number(text);
            if (!value) return "'" + text + "' is not a number";
            if (!(*value > 0 && *value <= 1)) return text + " is outside (0, 1]";
            return {};
        },
        "in (0, 1]", "phi");
    return check;
}

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
    CLI::Option* device = cmd.add_option("--device", choice.device, help)->check(CLI::IsMember(devices))->capture_default_str();
    cmd.add_option("--gpu", choice.gpu, "With --device gpu: which CUDA device (0-based, after CUDA_VISIBLE_DEVICES)")
        ->check(index_check())
        // It picks among GPUs: with the CPU alone it would be ignored.
        ->check(CLI::Validator(
            [device](std::string&) -> std::string {
                const std::string where = device->count() ? device->results().back() : device->get_default_str();
                return where == "cpu" ? "applies with --device gpu; the work runs on the CPU" : std::string{};
            },
            "", "not with cpu"))
        ->capture_default_str();
}

Device open_device(const DeviceChoice& choice) {
    if (!choice.on_gpu()) return Device::host();
    const GpuInfo info = gpu_info(choice.gpu);
    if (!info.available) throw Error("--device gpu: " + info.description);
    return Device::cuda(choice.gpu);
}

nlohmann::json device_json(const Device& device, const StageSeconds& seconds) {
    if (!device.is_gpu()) return {{"kind", "cpu"}};
    return {{"kind", "gpu"},
            {"index", device.gpu()},
            {"name", device.description()},
            {"seconds",
             {{"upload", seconds.upload},
              {"compute", seconds.extract + seconds.reduce},
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
