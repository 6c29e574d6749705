// `tetiso split`: partition a mesh (or take a .pvtu's pieces) once and write
// one file per domain, so that `tetiso run --split DIR` never holds the
// whole mesh on any rank.
#include <iostream>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/field.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"
#include "tetiso/pvtu.hpp"

namespace tetiso::cli {
namespace {

struct SplitArguments {
    std::filesystem::path mesh, partition, output;
    int domains = 0;
    std::string field = "paper";
    std::optional<int> attribute;
    std::string array, node_ids;
    bool quiet = false;
};

void run_split(const SplitArguments& args) {
    require_new_split_directory(args.output); // before the mesh is read and partitioned
    const std::unique_ptr<Field> field = make_field(args.field);
    const MeshSource source{args.mesh, args.attribute, args.array, args.node_ids, field.get()};
    // A .pvtu's pieces are written one at a time: no whole mesh is held.
    const std::unique_ptr<Partition> partition =
        mesh_format(args.mesh) == MeshFormat::pvtu && args.partition.empty() && args.domains == 0
            ? std::unique_ptr<Partition>(std::make_unique<PvtuPartition>(source))
            : partition_mesh(source, args.partition, args.domains);
    const double level = source.field_from_file() ? 0.0 : field->default_level();
    write_mesh_split(*partition, level, args.output);
    if (!args.quiet)
        std::cerr << "tetiso split: " << partition->node_count() << " nodes, " << partition->tet_count()
                  << " tetrahedra in " << partition->domain_count() << " domains written to " << args.output.string()
                  << '\n';
}

} // namespace

void add_split_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<SplitArguments>();
    CLI::App* cmd = app.add_subcommand(
        "split", "Partition a mesh (.vtu, .pvtu, .msh or TetGen) and write one file per domain, for "
                 "`tetiso run --split` (no rank of that job holds the whole mesh)");
    CLI::Option* mesh = cmd->add_option("--mesh", args->mesh,
                                        "Mesh: .vtu, .pvtu (default: its pieces are the domains), .msh, or TetGen "
                                        "BASE (BASE.node and BASE.ele)")
                            ->required();
    cmd->add_option("--array", args->array, "With a .vtu, .pvtu or .msh: the field is this point array ($NodeData view)");
    cmd->add_option("--node-ids", args->node_ids, "With a .pvtu: the integer point array of global node ids "
                                                  "(default: the one the file marks, e.g. GlobalNodeIds)");
    CLI::Option* partition =
        cmd->add_option("--partition", args->partition,
                        "Each tetrahedron's domain, one id per line in .ele order, ids from 0 (as METIS's mpmetis "
                        "writes BASE.epart.D; default: METIS splits the mesh into --domains)");
    CLI::Option* domains =
        cmd->add_option("--domains", args->domains, "Number of domains (with --partition: its count, if given)")
            ->check(domain_count_check());
    cmd->add_option("--field", args->field,
                    std::string("Built-in field (") + builtin_field_names() +
                        ") or an expression in x, y, z, evaluated at the nodes and stored")
        ->capture_default_str();
    cmd->add_option_function<int>(
           "--attribute", [args](int k) { args->attribute = k; },
           "The field is node attribute K of BASE.node (default: --field at the nodes)")
        ->check(index_check());
    cmd->add_option("-o,--output", args->output, "Directory to write (new, or empty)")->required();
    cmd->add_flag("--quiet", args->quiet, "No summary line on stderr");
    cmd->callback([&run, args, partition, domains, mesh] {
        if (partition->count() == 0 && domains->count() == 0 && mesh_format(args->mesh) != MeshFormat::pvtu)
            throw CLI::ValidationError("give --domains D (METIS) or --partition FILE");
        run = [args] { run_split(*args); };
    });
}

} // namespace tetiso::cli
