// The subcommands of the `tetiso` program. Each registers its options on the
// CLI11 app and returns the function that runs it once parsing succeeded.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tetiso/device.hpp"
#include "tetiso/io.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::cli {

using Command = std::function<void()>;

void add_extract_command(CLI::App& app, Command& run);
void add_check_command(CLI::App& app, Command& run);
void add_run_command(CLI::App& app, Command& run);
void add_reduce_command(CLI::App& app, Command& run);
void add_split_command(CLI::App& app, Command& run);

// --phi and --no-contact-test, shared by every command that reduces.
void add_reduction_options(CLI::App& cmd, ReduceOptions& options);

// The checks every command applies to the options of the same kind, so that
// one value is refused, or taken, the same way by each (a NaN passes a
// "non-negative" test, and CLI11's own messages print ranges of 300 digits).
// A count of domains: a whole number, at least 1.
const CLI::Validator& domain_count_check();
// An index (--gpu, --attribute): a whole number, at least 0.
const CLI::Validator& index_check();
// --phi: a number in (0, 1] (0 and NaN are not).
const CLI::Validator& phi_check();
// Makes every integer option of `app` and its subcommands read decimal
// digits only (an optional sign, leading zeros ignored: "032" is 32, "0x20"
// is refused), before any other check of the option. For main(), once every
// option is added.
void require_decimal_integers(CLI::App& app);
// Refuses, in every subcommand of `app`, options that mean nothing together
// or given empty: --array with --field or --attribute, --attribute with
// --field, --vertices-only without --against, '' as a file or array name.
// For main(), once every option is added.
void refuse_meaningless_combinations(CLI::App& app);
// A distance bound: a finite number, at least 0.
const CLI::Validator& error_bound_check();
// --threads: 0 (all cores) to kMaxThreads.
void add_threads_option(CLI::App& cmd, int& threads, const std::string& description);
// --level: a finite number that fits a float, the type of field values.
void add_level_option(CLI::App& cmd, std::optional<double>& level, const std::string& description);

// --device cpu|gpu and --gpu N, shared by the commands that can run on a GPU.
struct DeviceChoice {
    std::string device = "cpu";
    int gpu = 0;
    bool on_gpu() const { return device == "gpu"; }
    bool automatic() const { return device == "auto"; }
};
// what: the work that runs there, for the help text. With `automatic`,
// --device also takes auto (tetiso run: a resource manager per node places
// each task), which is then the default.
void add_device_options(CLI::App& cmd, DeviceChoice& choice, const std::string& what, bool automatic = false);

// The device asked for; throws tetiso::Error ("--device gpu: why not")
// when there is no such GPU.
Device open_device(const DeviceChoice& choice);

// The report's "device": the CPU, or the GPU's name and its seconds by stage.
nlohmann::json device_json(const Device& device, const StageSeconds& seconds);

nlohmann::json reduce_json(const ReduceReport& report);

// Fails early, before any work, if `path` cannot be created: its directory
// (that of the file a link there names) must exist and be writable, and it
// must not be a directory, a device, a pipe or a socket.
void require_writable(const std::filesystem::path& path);

// A file named on the command line, by the option that names it ("-o",
// "--report", "--mesh", "input"), for require_distinct_files.
struct NamedFile {
    std::string option;
    std::filesystem::path path;
};
// Fails early, before any work, when two of a command's outputs are one file
// or an output is one of its inputs, which the output would replace: the
// same device and inode, or the same path once resolved (detail::same_file),
// so "./x", links and hard links count. An output that is a link stands for
// the file it names (the one written).
void require_distinct_files(const std::vector<NamedFile>& outputs, const std::vector<NamedFile>& inputs);
// The files `--mesh PATH` reads: PATH; a .pvtu's pieces too; TetGen's
// BASE.node and BASE.ele.
std::vector<NamedFile> mesh_files(const std::filesystem::path& mesh);
// The files of a split directory (`run --split DIR`).
std::vector<NamedFile> split_files(const std::filesystem::path& dir);

// Writes a JSON report as one of the command's outputs, which are renamed
// into place together by output.commit() (never a half-written file, nor a
// surface without the report asked for).
void write_report(const nlohmann::json& report, const std::filesystem::path& path, OutputFiles& output);

// The note on stderr that the surface is empty, the same from every command:
// whether the level lies outside the field's range [lowest, highest] (left
// out where lowest > highest, a range not known).
void note_empty_surface(double level, float lowest, float highest);

// Seconds since an arbitrary start, for stage timings.
double now_seconds();

} // namespace tetiso::cli
