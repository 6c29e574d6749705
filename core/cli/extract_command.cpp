// `tetiso extract`: the lattice test problem, domain by domain, extracted and
// combined by key into one surface, or an unstructured mesh (TetGen, .vtu,
// .pvtu, .msh) as one domain; `--reduce` reduces the result.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/io.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/seam.hpp"
#include "tetiso/mesh_file.hpp"

namespace tetiso::cli {
namespace {

struct ExtractArguments {
    std::int64_t lattice = 0;
    std::filesystem::path mesh;        // a mesh file (mesh_file.hpp), instead of --lattice
    std::optional<int> attribute;      // with --mesh: the field is this node attribute
    std::string array, node_ids;       // with --mesh: the field's point array; a .pvtu's node ids
    int domains = 1;
    std::string field = "paper";
    std::optional<double> level;
    int threads = 1;
    DeviceChoice device; // where the marching tetrahedra and the reduction run
    bool reduce = false;
    ReduceOptions reduce_options;
    double max_error_spacings = 0.25;
    std::filesystem::path output;
    std::filesystem::path report;
};

void run_extract_mesh(const ExtractArguments& args, const Field& field, double start) {
    const Device device = open_device(args.device);
    StageSeconds stage_seconds;
    const double t0 = now_seconds();
    const MeshSource source{args.mesh, args.attribute, args.array, args.node_ids, &field};
    const Domain domain = read_mesh(source);
    const double t1 = now_seconds();
    // An attribute has no level of its own; an analytic field does.
    const double level = args.level.value_or(source.field_from_file() ? 0.0 : field.default_level());
    Piece surface = extract(domain, static_cast<float>(level), ExtractOptions{args.threads, device}, &stage_seconds);
    const double t2 = now_seconds();
    const auto [lo, hi] = std::minmax_element(domain.f.begin(), domain.f.end());
    if (surface.triangle_count() == 0 && lo != domain.f.end()) note_empty_surface(level, *lo, *hi);
    ReduceReport reduce_report;
    const double spacing = mean_edge_length(domain);
    if (args.reduce) {
        ReduceOptions options = args.reduce_options;
        options.threads = args.threads;
        options.max_error = args.max_error_spacings * spacing;
        options.device = device;
        surface = reduce(surface, options, &reduce_report, &stage_seconds);
    }
    const double t3 = now_seconds();
    OutputFiles output;
    write_piece(surface, args.output, output);
    if (args.report.empty()) return output.commit();
    nlohmann::json report = {
        {"command", "extract"},
        {"mesh", args.mesh.string()},
        {"field", source.field_description()},
        {"level", level},
        {"domains", 1},
        {"nodes", domain.node_count()},
        {"tets", domain.tet_count()},
        {"mean_edge_length", spacing},
        {"threads", args.threads},
        {"device", device_json(device, stage_seconds)},
        {"vertices", surface.vertex_count()},
        {"triangles", surface.triangle_count()},
        {"output", args.output.string()},
        {"seconds",
         {{"read", t1 - t0},
          {"extract", t2 - t1},
          {"reduce", reduce_report.seconds},
          {"write", now_seconds() - t3},
          {"total", now_seconds() - start}}},
    };
    if (lo != domain.f.end()) report["field_range"] = {*lo, *hi};
    if (args.reduce) {
        report["reduction"] = reduce_json(reduce_report);
        report["phi"] = args.reduce_options.phi;
        report["max_error"] = args.max_error_spacings * spacing;
    }
    write_report(report, args.report, output);
    output.commit();
}

void run_extract(const ExtractArguments& args) {
    const double start = now_seconds();
    surface_format(args.output);
    require_writable(args.output);
    if (!args.report.empty()) require_writable(args.report);

    if (args.mesh.empty() == (args.lattice == 0)) throw Error("give either --lattice or --mesh");
    if (!args.mesh.empty() && args.domains != 1)
        throw Error("--mesh reads one domain; --domains applies to the lattice only");
    if ((args.attribute || !args.array.empty() || !args.node_ids.empty()) && args.mesh.empty())
        throw Error("--attribute, --array and --node-ids need --mesh");
    require_distinct_files({{"-o", args.output}, {"--report", args.report}},
                           args.mesh.empty() ? std::vector<NamedFile>{} : mesh_files(args.mesh));
    std::unique_ptr<Field> made_field = make_field(args.field);
    if (!args.mesh.empty()) return run_extract_mesh(args, *made_field, start);
    const LatticePartition partition(args.lattice, args.domains, std::move(made_field));
    const Lattice& lattice = partition.lattice();
    const Decomposition& decomposition = partition.decomposition();
    const Field* field = &partition.field();
    const double level = args.level.value_or(field->default_level());
    DomainTaskOptions task;
    task.level = static_cast<float>(level);
    task.device = open_device(args.device);
    task.threads = args.threads;
    StageSeconds stage_seconds;

    double generate_seconds = 0, extract_seconds = 0;
    float lowest = std::numeric_limits<float>::infinity(), highest = -lowest;
    std::vector<Piece> pieces;
    pieces.reserve(static_cast<std::size_t>(args.domains));
    bool range_known = true;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const double t0 = now_seconds();
        DomainTaskResult done = run_domain_task(partition, d, task);
        generate_seconds += done.seconds.generate;
        extract_seconds += now_seconds() - t0 - done.seconds.generate;
        stage_seconds += done.seconds;
        pieces.push_back(std::move(done.piece));
        // A GPU builds a lattice domain itself: its values stay there.
        range_known = range_known && done.field_low <= done.field_high;
        lowest = std::min(lowest, done.field_low);
        highest = std::max(highest, done.field_high);
    }
    const double t_combine = now_seconds();
    Piece surface = merge_all(std::move(pieces));
    unlock_settled(surface, [&](GlobalId a, GlobalId b) { return decomposition.domains_of_edge(a, b); });
    const double combine_seconds = now_seconds() - t_combine;

    // The field's range: for the message on an empty surface, and in the
    // report (the GPU's domains have it on the host only when asked).
    if (!range_known && (surface.triangle_count() == 0 || !args.report.empty()))
        for (int d = 0; d < decomposition.domain_count(); ++d) {
            const std::vector<float> values = decomposition.field_values(d, *field);
            const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
            lowest = std::min(lowest, *lo);
            highest = std::max(highest, *hi);
        }
    if (surface.triangle_count() == 0) note_empty_surface(level, lowest, highest);
    ReduceReport reduce_report;
    if (args.reduce) {
        ReduceOptions options = args.reduce_options;
        options.threads = args.threads;
        options.max_error = args.max_error_spacings * lattice.spacing();
        options.device = task.device;
        surface = reduce(surface, options, &reduce_report, &stage_seconds);
    }
    const double t_write = now_seconds();
    OutputFiles output;
    write_piece(surface, args.output, output);
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
            {"device", device_json(task.device, stage_seconds)},
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
        write_report(report, args.report, output);
    }
    output.commit();
}

} // namespace

void add_extract_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<ExtractArguments>();
    CLI::App* cmd = app.add_subcommand("extract", "Extract the isosurface of the lattice test problem or of a mesh");
    auto* lattice = cmd->add_option("--lattice", args->lattice, "Nodes per axis of the N x N x N lattice on [0,5]^3")
                        ->check(CLI::Range(std::int64_t{2}, std::int64_t{1625}));
    cmd->add_option("--mesh", args->mesh,
                    "Mesh instead of the lattice: .vtu, .pvtu (pieces joined by node ids), .msh, or TetGen BASE "
                    "(BASE.node and BASE.ele)")
        ->excludes(lattice);
    cmd->add_option("--array", args->array, "With a .vtu, .pvtu or .msh: the field is this point array ($NodeData view)");
    cmd->add_option("--node-ids", args->node_ids, "With a .pvtu: the integer point array of global node ids "
                                                  "(default: the one the file marks, e.g. GlobalNodeIds)");
    cmd->add_option_function<int>(
        "--attribute", [args](int k) { args->attribute = k; },
        "With --mesh: the field is node attribute K of BASE.node (default: --field at the nodes)")
        ->check(index_check());
    cmd->add_option("--domains", args->domains, "Number of domains (recursive coordinate bisection)")
        ->check(domain_count_check());
    cmd->add_option("--field", args->field,
                    std::string("Built-in field (") + builtin_field_names() + ") or an expression in x, y, z")
        ->capture_default_str();
    add_level_option(*cmd, args->level, "Isosurface level (default: the field's own, 0.5 for paper)");
    add_threads_option(*cmd, args->threads, "Threads inside a domain (0 = all cores); output does not depend on it");
    add_device_options(*cmd, args->device, "the marching tetrahedra and the reduction");
    cmd->add_flag("--reduce", args->reduce, "Reduce the combined surface (parallel edge collapse and flip)");
    add_reduction_options(*cmd, args->reduce_options);
    cmd->add_option("--max-error", args->max_error_spacings,
                    "With --reduce: bound on the distance to the raw surface, in lattice spacings (mean tetrahedron edge lengths with --mesh; 0: none)")
        ->check(error_bound_check())
        ->capture_default_str();
    cmd->add_option("-o,--output", args->output, "Output surface, .ply or .vtp")->required();
    cmd->add_option("--report", args->report, "Write a JSON report here");
    cmd->callback([&run, args] { run = [args] { run_extract(*args); }; });
}

} // namespace tetiso::cli
