// `tetiso extract`: the lattice test problem, domain by domain, extracted and
// combined by key into one surface (reduction arrives with `--reduce`).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include "commands.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/io.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/seam.hpp"

namespace tetiso::cli {
namespace {

struct ExtractArguments {
    std::int64_t lattice = 0;
    int domains = 1;
    std::string field = "paper";
    std::optional<double> level;
    int threads = 1;
    bool reduce = false;
    ReduceOptions reduce_options;
    double max_error_spacings = 0.25;
    std::filesystem::path output;
    std::filesystem::path report;
};

void run_extract(const ExtractArguments& args) {
    const double start = now_seconds();
    surface_format(args.output);
    require_writable(args.output);
    if (!args.report.empty()) require_writable(args.report);

    const Lattice lattice(args.lattice);
    const Decomposition decomposition(lattice, args.domains);
    const std::unique_ptr<Field> field = make_field(args.field);
    const double level = args.level.value_or(field->default_level());

    double generate_seconds = 0, extract_seconds = 0;
    float lowest = std::numeric_limits<float>::infinity(), highest = -lowest;
    std::vector<Piece> pieces;
    pieces.reserve(static_cast<std::size_t>(args.domains));
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const double t0 = now_seconds();
        const Domain domain = decomposition.make_domain(d, *field);
        const double t1 = now_seconds();
        pieces.push_back(extract(domain, static_cast<float>(level), ExtractOptions{args.threads}));
        extract_seconds += now_seconds() - t1;
        generate_seconds += t1 - t0;
        const auto [lo, hi] = std::minmax_element(domain.f.begin(), domain.f.end());
        lowest = std::min(lowest, *lo);
        highest = std::max(highest, *hi);
    }
    const double t_combine = now_seconds();
    Piece surface = merge_all(std::move(pieces));
    unlock_settled(surface, [&](GlobalId a, GlobalId b) { return decomposition.domains_of_edge(a, b); });
    const double combine_seconds = now_seconds() - t_combine;

    if (surface.triangle_count() == 0)
        std::cerr << "tetiso: the surface is empty: level " << level
                  << (level < lowest || level > highest ? " is outside" : " is within")
                  << " the field's range [" << lowest << ", " << highest << "]\n";
    ReduceReport reduce_report;
    if (args.reduce) {
        ReduceOptions options = args.reduce_options;
        options.threads = args.threads;
        options.max_error = args.max_error_spacings * lattice.spacing();
        surface = tetiso::reduce(surface, options, &reduce_report);
    }
    const double t_write = now_seconds();
    write_piece(surface, args.output);
    const double write_seconds = now_seconds() - t_write;

    if (!args.report.empty()) {
        nlohmann::json report = {
            {"command", "extract"},
            {"lattice", args.lattice},
            {"field", field->description()},
            {"level", level},
            {"field_range", {lowest, highest}},
            {"domains", decomposition.domain_count()},
            {"nodes", lattice.node_count()},
            {"tets", lattice.tet_count()},
            {"threads", args.threads},
            {"vertices", surface.vertex_count()},
            {"triangles", surface.triangle_count()},
            {"output", args.output.string()},
            {"seconds",
             {{"generate", generate_seconds},
              {"extract", extract_seconds},
              {"combine", combine_seconds},
              {"reduce", reduce_report.seconds},
              {"write", write_seconds},
              {"total", now_seconds() - start}}},
        };
        if (args.reduce) {
            report["reduction"] = reduce_json(reduce_report);
            report["phi"] = args.reduce_options.phi;
            report["max_error"] = args.max_error_spacings * lattice.spacing();
        }
        write_report(report, args.report);
    }
}

} // namespace

void add_extract_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<ExtractArguments>();
    CLI::App* cmd = app.add_subcommand("extract", "Extract the isosurface of the lattice test problem");
    cmd->add_option("--lattice", args->lattice, "Nodes per axis of the N x N x N lattice on [0,5]^3")
        ->required()
        ->check(CLI::Range(std::int64_t{2}, std::int64_t{1625}));
    cmd->add_option("--domains", args->domains, "Number of domains (recursive coordinate bisection)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--field", args->field,
                    std::string("Built-in field (") + builtin_field_names() + ") or an expression in x, y, z")
        ->capture_default_str();
    cmd->add_option_function<double>(
        "--level", [args](double level) { args->level = level; },
        "Isosurface level (default: the field's own, 0.5 for paper)");
    cmd->add_option("--threads", args->threads, "Threads inside a domain (0 = all cores); output does not depend on it")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_flag("--reduce", args->reduce, "Reduce the combined surface (parallel edge collapse and flip)");
    add_phi_option(*cmd, args->reduce_options.phi);
    cmd->add_option("--max-error", args->max_error_spacings,
                    "With --reduce: bound on the distance to the raw surface, in lattice spacings (0: none)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd->add_option("-o,--output", args->output, "Output surface, .ply or .vtp")->required();
    cmd->add_option("--report", args->report, "Write a JSON report here");
    cmd->callback([&run, args] { run = [args] { run_extract(*args); }; });
}

} // namespace tetiso::cli
