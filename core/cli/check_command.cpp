// `tetiso check`: is this surface sound? Topology, quality and, against a
// reference, distance and per-component signatures, printed as JSON.
#include <iostream>

#include "commands.hpp"
#include "tetiso/check.hpp"
#include "tetiso/io.hpp"

namespace tetiso::cli {
namespace {

struct CheckArguments {
    std::filesystem::path input;
    std::filesystem::path against;
    bool self_intersections = true;
    bool vertices_only = false;
};

void run_check(const CheckArguments& args) {
    const Piece surface = read_piece(args.input);
    const TopologyReport topology = check_topology(surface);
    nlohmann::json out = {{"file", args.input.string()}, {"topology", to_json(topology)}};
    if (args.self_intersections && have_self_intersections()) {
        const std::optional<std::size_t> crossings = count_self_intersections(surface);
        out["self_intersections"] = crossings ? nlohmann::json(*crossings) : nlohmann::json(nullptr);
    }
    if (!args.against.empty()) {
        const Piece reference = read_piece(args.against);
        const TopologyReport reference_topology = check_topology(reference);
        out["against"] = {
            {"file", args.against.string()},
            {"same_signatures", same_signatures(topology, reference_topology)},
            {"reference_topology", to_json(reference_topology)},
            {"hausdorff", to_json(hausdorff(surface, reference, HausdorffOptions{.vertices_only = args.vertices_only}))},
        };
    }
    std::cout << out.dump(2) << '\n';
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
    cmd->callback([&run, args] { run = [args] { run_check(*args); }; });
}

} // namespace tetiso::cli
