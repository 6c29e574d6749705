// `tetiso reduce`: reduce a surface file with the paper's Φ criterion, keeping
// its topology and its locked vertices.
#include <algorithm>
#include <cstdio>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/error_unit.hpp"
#include "tetiso/io.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::cli {

void add_reduction_options(CLI::App& cmd, ReduceOptions& options) {
    cmd.add_option("--phi", options.phi, "Reduction threshold PHI* in (0, 1]: an edge collapses when its PHI exceeds it")
        ->check(phi_check())
        ->capture_default_str();
    cmd.add_flag("--no-contact-test{false}", options.contact_test,
                 "Skip the test of new faces against nearby faces that share no corner with them: about half the "
                 "reduction's time, but where the surface folds back close to itself the result may cross itself");
}

nlohmann::json reduce_json(const ReduceReport& report) {
    nlohmann::json rounds = nlohmann::json::array();
    for (const ReduceRound& r : report.rounds)
        rounds.push_back({{"round", r.round},
                          {"vertices", r.vertices},
                          {"triangles", r.triangles},
                          {"candidates", r.candidates},
                          {"evaluated", r.evaluated},
                          {"collapses", r.collapses},
                          {"flips", r.flips},
                          {"selection_steps", r.selection_steps},
                          {"selection_passes", r.selection_passes},
                          {"changed_vertices", r.changed_vertices},
                          {"seconds", r.seconds}});
    return {{"triangles_in", report.triangles_in},   {"triangles_out", report.triangles_out},
            {"vertices_in", report.vertices_in},     {"vertices_out", report.vertices_out},
            {"rounds", rounds},                      {"seconds", report.seconds},
            {"stage_seconds",
             {{"fans", report.stages.fans},
              {"edges", report.stages.edges},
              {"geometry", report.stages.geometry},
              {"propose", report.stages.propose},
              {"select", report.stages.select},
              {"apply", report.stages.apply},
              {"contact", report.stages.contact},
              {"compact", report.stages.compact}}}};
}

namespace {

struct ReduceArguments {
    std::filesystem::path input, output, report;
    ReduceOptions options;
    std::optional<double> max_error;
    DeviceChoice device;
};

void run_reduce(const ReduceArguments& args) {
    const double start = now_seconds();
    surface_format(args.output);
    require_writable(args.output);
    if (!args.report.empty()) require_writable(args.report);
    require_distinct_files({{"-o", args.output}, {"--report", args.report}}, {{"input", args.input}});
    const Device device = open_device(args.device);
    const Piece input = read_piece(args.input);
    ReduceOptions options = args.options;
    options.device = device;
    // Without a lattice spacing to relate to, bound the error by a fraction
    // of the input's own edge length (marching-tets edges are about 0.6 h).
    options.max_error = args.max_error.value_or(kAutoErrorPerEdgeLength * mean_edge_length(input));
    // A file written by a reduction carries each triangle's bound on its
    // distance from the raw surface; one already past the bound asked for
    // can only stay as it is, which a user would otherwise not see.
    if (options.max_error > 0) {
        const auto over = std::count_if(input.error.begin(), input.error.end(),
                                        [&](float e) { return e > options.max_error; });
        if (over > 0)
            std::fprintf(stderr, "tetiso: note: %lld triangles of %s already carry an error bound above --max-error %g; "
                                 "they can only stay as they are\n",
                         static_cast<long long>(over), args.input.string().c_str(), options.max_error);
    }
    ReduceReport report;
    StageSeconds seconds;
    const Piece output = reduce(input, options, &report, &seconds);
    OutputFiles files;
    write_piece(output, args.output, files);
    if (!args.report.empty()) {
        nlohmann::json json = reduce_json(report);
        json["command"] = "reduce";
        json["input"] = args.input.string();
        json["output"] = args.output.string();
        json["phi"] = options.phi;
        json["max_error"] = options.max_error;
        json["threads"] = options.threads;
        json["device"] = device_json(device, seconds);
        json["total_seconds"] = now_seconds() - start;
        write_report(json, args.report, files);
    }
    files.commit();
}

} // namespace

void add_reduce_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<ReduceArguments>();
    CLI::App* cmd = app.add_subcommand("reduce", "Reduce a surface: parallel edge collapse and flip, topology kept");
    cmd->add_option("input", args->input, "Surface to reduce, .ply or .vtp (an oriented manifold)")->required();
    cmd->add_option("-o,--output", args->output, "Reduced surface, .ply or .vtp")->required();
    add_reduction_options(*cmd, args->options);
    cmd->add_option_function<double>(
           "--max-error", [args](double e) { args->max_error = e; },
           "Bound on the distance to the input surface, absolute (0: none; default: 0.4 x mean edge length); "
           "for an input that carries tetiso_error_bound (a reduction's output), on the distance to the raw surface it "
           "stands for")
        ->check(error_bound_check());
    add_threads_option(*cmd, args->options.threads, "Threads (0 = all cores); output does not depend on it");
    add_device_options(*cmd, args->device, "the rounds");
    cmd->add_option("--report", args->report, "Write a JSON report here");
    cmd->callback([&run, args] { run = [args] { run_reduce(*args); }; });
}

} // namespace tetiso::cli
