// The subcommands of the `tetiso` program. Each registers its options on the
// CLI11 app and returns the function that runs it once parsing succeeded.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

namespace tetiso::cli {

using Command = std::function<void()>;

void add_extract_command(CLI::App& app, Command& run);
void add_check_command(CLI::App& app, Command& run);
void add_run_command(CLI::App& app, Command& run);

// Fails early, before any work, if `path` cannot be created: its directory
// must exist and be writable, and its extension known to `kind`.
void require_writable(const std::filesystem::path& path);

// Writes a JSON report atomically (never a half-written file).
void write_report(const nlohmann::json& report, const std::filesystem::path& path);

// Seconds since an arbitrary start, for stage timings.
double now_seconds();

} // namespace tetiso::cli
