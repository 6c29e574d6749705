// `tetiso check`: is this surface sound? Topology, quality and, against a
// reference, distance and per-component signatures, printed as JSON; with
// --strict, a gate for CI scripts: one line on stderr per clause of the
// surface contract that the surface violates, and exit status 1.
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "tetiso/check_report.hpp"
#include "tetiso/io.hpp"

namespace tetiso::cli {
namespace {

// The exit status of a surface that violates the contract: 2 stays what it
// is for every command, bad input.
constexpr int kViolated = 1;

struct CheckArguments {
    std::filesystem::path input;
    std::filesystem::path against;
    bool self_intersections = true;
    bool vertices_only = false;
    bool strict = false;
};

void run_check(const CheckArguments& args) {
    const Piece surface = read_piece(args.input);
    std::optional<Piece> reference;
    if (!args.against.empty()) reference = read_piece(args.against);
    nlohmann::json out = check_report(surface, reference ? &*reference : nullptr,
                                      CheckReportOptions{.self_intersections = args.self_intersections,
                                                         .vertices_only = args.vertices_only,
                                                         .strict = args.strict});
    out["file"] = args.input.string();
    if (reference) out["against"]["file"] = args.against.string();
    std::cout << out.dump(2) << '\n';
    if (!args.strict) return;
    const auto violations = out["violations"].get<std::vector<std::string>>();
    if (violations.empty()) return;
    for (const std::string& line : violations) std::cerr << "tetiso check: " << args.input.string() << ": " << line << '\n';
    std::cout.flush();
    std::exit(kViolated);
}

} // namespace

void add_check_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<CheckArguments>();
    CLI::App* cmd = app.add_subcommand("check", "Report the topology and quality of a surface as JSON");
    cmd->add_option("input", args->input, "Surface to check, .ply or .vtp")->required();
    cmd->add_option("--against", args->against,
                    "Reference surface: adds the symmetric Hausdorff distance and whether the per-component "
                    "(genus, boundary loops) signatures match");
    cmd->add_flag("--vertices-only", args->vertices_only,
                  "With --against: measure at the vertices only (forward is then the largest distance of IN's "
                  "vertices to REF, what reduce's --max-error bounds when IN is the input and REF the result)");
    cmd->add_flag("!--no-self-intersections", args->self_intersections,
                  "Skip the self-intersection count (CGAL builds only; slow on large surfaces)");
    cmd->add_flag("--strict", args->strict,
                  "A gate: exit 1, with one line on stderr per violated clause, unless the surface is clean "
                  "(no degenerate triangle, duplicate position, self-intersection or duplicate triangle; "
                  "manifold, consistently oriented; with --against, the reference's component signatures)");
    cmd->callback([&run, args] { run = [args] { run_check(*args); }; });
}

} // namespace tetiso::cli
