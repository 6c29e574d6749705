// `tetiso run`: the main job. Under mpirun, rank 0 controls and the other
// ranks work; without it, one process runs every task.
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <limits>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/placement.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso::cli {
namespace {

struct RunArguments {
    JobConfig job;
    DeviceChoice device;
    std::filesystem::path output;
    std::filesystem::path report;
    bool quiet = false;
};

// Where a task ran: "cpu", or "gpu N" for CUDA device N of its rank's node.
std::string device_name(const TaskRecord& t) {
    return t.stages.gpu < 0 ? std::string("cpu") : "gpu " + std::to_string(t.stages.gpu);
}

// What each device took: its tasks, their seconds, their input triangles
// (the work: a domain's extracted triangles, a seam's two pieces'), and the
// seconds they waited for a grant; devices by name.
nlohmann::json device_summary(const std::vector<TaskRecord>& tasks) {
    nlohmann::json summary = nlohmann::json::object();
    for (const TaskRecord& t : tasks) {
        nlohmann::json& d = summary[device_name(t)];
        if (d.is_null()) d = {{"tasks", 0}, {"domain_tasks", 0}, {"seconds", 0.0}, {"triangles_in", 0}, {"wait_seconds", 0.0}};
        d["tasks"] = d["tasks"].get<int>() + 1;
        if (t.kind == TaskKind::domain) d["domain_tasks"] = d["domain_tasks"].get<int>() + 1;
        d["seconds"] = d["seconds"].get<double>() + (t.end - t.start);
        d["triangles_in"] = d["triangles_in"].get<std::uint64_t>() + t.triangles_in;
        d["wait_seconds"] = d["wait_seconds"].get<double>() + t.wait_seconds;
    }
    return summary;
}

nlohmann::json task_json(const TaskRecord& t) {
    nlohmann::json stages;
    if (t.kind == TaskKind::domain)
        stages = {{"generate", t.stages.generate}, {"extract", t.stages.extract}, {"reduce", t.stages.reduce}};
    else
        stages = {{"merge", t.stages.merge},
                  {"region", t.stages.region},
                  {"reduce", t.stages.reduce},
                  {"splice", t.stages.splice}};
    if (t.stages.gpu >= 0) {
        stages["upload"] = t.stages.upload;
        stages["download"] = t.stages.download;
    }
    return {{"task", t.task},
            {"kind", t.kind == TaskKind::domain ? "domain" : "seam"},
            {"device", device_name(t)},
            {"first_domain", t.first_domain},
            {"domain_count", t.domain_count},
            {"rank", t.rank},
            {"threads", t.threads},
            {"start", t.start},
            {"end", t.end},
            {"triangles_in", t.triangles_in},
            {"triangles_out", t.triangles_out},
            {"samples_out", t.samples_out},
            {"predicted_seconds", t.predicted_seconds},
            {"wait_seconds", t.wait_seconds},
            {"stage_seconds", stages}};
}

// Every rank of the job runs task after task of about the same shape, each
// allocating and freeing the same large arrays. glibc would hand the large
// ones back to the kernel when freed (mmap above a threshold, heap trimming),
// so every task faulted its working memory in again, page by page, zeroed.
// Kept in the process instead, the next task reuses it: the peak is the same
// (it is the largest task's), with far fewer page faults and a faster job.
// The thresholds are above any single array of a
// task (a 10^6-cell domain's tetrahedra are 96 MB).
void keep_freed_memory() {
    constexpr int kThreshold = 1 << 30;
    mallopt(M_MMAP_THRESHOLD, kThreshold);
    mallopt(M_TRIM_THRESHOLD, kThreshold);
}

void run_job(const RunArguments& args) {
    const double start = now_seconds();
    keep_freed_memory();
    MpiSession mpi;
    // Every rank validates the configuration and reads the mesh's files; a
    // rank that cannot (a file missing on its node) must not leave the
    // others waiting for it.
    std::unique_ptr<Job> built;
    std::string setup_problem;
    try {
        JobConfig config = args.job;
        config.ranks = mpi.group(); // a .pvtu's pieces are scanned once in all, shared out
        built = std::make_unique<Job>(config);
    } catch (const Error& e) {
        setup_problem = e.what();
    } catch (const std::bad_alloc&) {
        // Left to propagate, it would finalise MPI on this rank alone while
        // the others wait below for its answer.
        setup_problem = "out of memory while setting up the job";
    }
    if (!mpi.all(setup_problem.empty())) {
        if (!setup_problem.empty()) throw Error(setup_problem);
        if (mpi.rank() == 0) throw Error("another rank could not set up the job (its message is above)");
        throw JobStopped();
    }
    const Job& job = *built;

    // Only rank 0 writes; the others learn whether it can.
    std::string output_problem;
    if (mpi.rank() == 0) {
        try {
            surface_format(args.output);
            require_writable(args.output);
            if (!args.report.empty()) require_writable(args.report);
            std::vector<NamedFile> inputs = args.job.mesh.empty() ? split_files(args.job.split) : mesh_files(args.job.mesh);
            if (!args.job.partition.empty()) inputs.push_back({"--partition", args.job.partition});
            require_distinct_files({{"-o", args.output}, {"--report", args.report}}, inputs);
        } catch (const Error& e) {
            output_problem = e.what();
        }
    }
    if (!mpi.broadcast(output_problem.empty())) {
        if (mpi.rank() == 0) throw Error(output_problem);
        throw JobStopped();
    }

    double last_report = 0;
    const bool show = !args.quiet && mpi.rank() == 0;
    const Progress progress = [&](int done, int total, double elapsed) {
        if (!show || elapsed < 2.0 || (elapsed - last_report < 1.0 && done < total)) return;
        last_report = elapsed;
        std::cerr << "tetiso: " << done << "/" << total << " tasks, " << elapsed << " s" << std::endl;
    };
    std::optional<JobResult> result = mpi.size() > 1 ? run_mpi(job, progress) : run_local(job, progress);
    if (!result) return; // a worker
    if (result->surface.triangle_count() == 0) {
        float lowest = std::numeric_limits<float>::infinity(), highest = -lowest;
        for (const TaskRecord& t : result->tasks) {
            lowest = std::min(lowest, t.field_low);
            highest = std::max(highest, t.field_high);
        }
        note_empty_surface(job.level(), lowest, highest);
    }

    const double t_write = now_seconds();
    OutputFiles output;
    write_piece(result->surface, args.output, output);
    const double write_seconds = now_seconds() - t_write;
    if (args.report.empty()) return output.commit();

    std::uint64_t raw = 0;
    nlohmann::json tasks = nlohmann::json::array();
    for (const TaskRecord& t : result->tasks) {
        if (t.kind == TaskKind::domain) raw += t.triangles_in;
        tasks.push_back(task_json(t));
    }
    const JobConfig& c = args.job;
    const Partition& partition = job.partition();
    nlohmann::json report = {
        {"command", "run"},
        {"lattice", c.lattice},
        {"mesh", c.mesh.string()},
        {"split", c.split.string()},
        {"partition", !c.split.empty() ? "as split" : c.mesh.empty() ? "bisection" : !c.partition.empty() ? c.partition.string() : mesh_format(c.mesh) == MeshFormat::pvtu ? "pieces" : "METIS"},
        {"domains", partition.domain_count()},
        {"field", !c.split.empty() ? "as split" : c.attribute ? "attribute " + std::to_string(*c.attribute) : !c.array.empty() ? "array " + c.array : c.field},
        {"level", job.level()},
        {"reduce", c.reduce},
        {"phi", c.reduce_options.phi},
        {"max_error", c.reduce ? c.max_error_spacings * partition.spacing() : 0.0},
        {"seam_rings", c.seam_rings},
        {"sample_rings", c.sample_rings},
        {"ranks", mpi.size()},
        {"workers", std::max(1, mpi.size() - 1)},
        {"threads", c.threads},
        {"gpu_batch", gpu_batch_of(c)},
        {"gpu_streams", c.gpu_streams},
        {"device", c.device == JobConfig::Device::gpu ? (c.gpu >= 0 ? "gpu " + std::to_string(c.gpu) : std::string("gpu"))
                   : c.device == JobConfig::Device::automatic ? std::string("auto") : std::string("cpu")},
        {"devices", device_summary(result->tasks)},
        {"cpu_probe_seconds_per_triangle", result->cpu_seconds_per_triangle},
        {"spacing", partition.spacing()},
        {"nodes", partition.node_count()},
        {"tets", partition.tet_count()},
        {"raw_triangles", raw},
        {"vertices", result->surface.vertex_count()},
        {"triangles", result->surface.triangle_count()},
        {"output", args.output.string()},
        {"seconds", {{"job", result->seconds}, {"write", write_seconds}, {"total", now_seconds() - start}}},
        {"tasks", tasks},
    };
    write_report(report, args.report, output);
    output.commit();
}

} // namespace

void add_run_command(CLI::App& app, Command& run) {
    auto args = std::make_shared<RunArguments>();
    CLI::App* cmd = app.add_subcommand(
        "run", "The main job: extract and reduce every domain, seam pairwise until one surface remains "
               "(under mpirun: rank 0 controls, the others work)");
    JobConfig& job = args->job;
    CLI::Option* lattice = cmd->add_option("--lattice", job.lattice, "Nodes per axis of the N x N x N lattice on [0,5]^3")
                               ->check(CLI::Range(std::int64_t{2}, std::int64_t{1625}));
    CLI::Option* mesh = cmd->add_option("--mesh", job.mesh,
                                        "Mesh instead of the lattice: .vtu, .pvtu (its pieces are the domains), .msh, "
                                        "or TetGen BASE (BASE.node and BASE.ele)");
    lattice->excludes(mesh);
    CLI::Option* split = cmd->add_option("--split", job.split,
                                         "A mesh written by `tetiso split` (a directory): each rank reads only the "
                                         "domains it works on; the field and its level come with it");
    split->excludes(lattice)->excludes(mesh);
    cmd->add_option("--partition", job.partition,
                    "With --mesh: each tetrahedron's domain, one id per line in .ele order, ids from 0 "
                    "(as METIS's mpmetis writes BASE.epart.D; default: METIS splits the mesh into --domains)")
        ->needs(mesh);
    CLI::Option* domains = cmd->add_option("--domains", job.domains,
                                           "Number of domains (the lattice: recursive coordinate bisection; a mesh "
                                           "without --partition: METIS; with it, its domain count if given)")
                               ->check(domain_count_check());
    cmd->add_option("--field", job.field,
                    std::string("Built-in field (") + builtin_field_names() + ") or an expression in x, y, z")
        ->capture_default_str()
        ->excludes(split);
    cmd->add_option_function<int>(
           "--attribute", [args](int k) { args->job.attribute = k; },
           "With --mesh: the field is node attribute K of BASE.node (default: --field at the nodes)")
        ->check(index_check())
        ->needs(mesh);
    cmd->add_option("--array", job.array, "With a .vtu, .pvtu or .msh: the field is this point array ($NodeData view)")
        ->needs(mesh);
    cmd->add_option("--node-ids", job.node_ids, "With a .pvtu: the integer point array of global node ids "
                                                "(default: the one the file marks, e.g. GlobalNodeIds)")
        ->needs(mesh);
    add_level_option(*cmd, job.level, "Isosurface level (default: the field's own, 0.5 for paper; 0 for --attribute or --array)");
    add_reduction_options(*cmd, job.reduce_options);
    cmd->add_option("--max-error", job.max_error_spacings,
                    "Bound on the distance to the raw surface, in spacings: the lattice's, or a mesh's mean "
                    "edge length (0: none)")
        ->check(error_bound_check())
        ->capture_default_str();
    cmd->add_option("--seam-rings", job.seam_rings,
                    "How far from a seam its reduction reaches, in edges (the rest of the pieces is left as it is)")
        ->check(CLI::Range(0, 64))
        ->capture_default_str();
    cmd->add_option("--sample-rings", job.sample_rings,
                    "Raw vertices each piece keeps for later seams: those of the triangles within this many "
                    "edges of an open interface (-1: none; more reduces the seams further, at a cost in memory)")
        ->check(CLI::Range(-1, 64))
        ->capture_default_str();
    cmd->add_flag("!--no-reduce", job.reduce, "Extract and seam only");
    add_threads_option(*cmd, job.threads, "Threads inside each task (0 = all cores)");
    cmd->add_option("-o,--output", args->output, "Output surface, .ply or .vtp")->required();
    cmd->add_option("--report", args->report, "Write a JSON report (totals and one record per task) here");
    cmd->add_flag("--quiet", args->quiet, "No progress lines on stderr");
    cmd->add_option("--task-timeout", job.task_timeout,
                    "Under mpirun: the shortest deadline of a task, in seconds; a rank whose task has not ended by "
                    "max(this, 10 x its predicted time), or a rank 0 silent as long, is named and the job aborted "
                    "(0: no deadline)")
        ->check(error_bound_check())
        ->capture_default_str();
    add_device_options(*cmd, args->device, "the domain tasks (extraction and reduction; the last seams too, once no domain task is left)", true);
    CLI::Option* gpu = cmd->get_option("--gpu");
    gpu->description("With --device gpu: the one CUDA device of each node to use (0-based, after "
                     "CUDA_VISIBLE_DEVICES; default: every GPU of each node, one process driving each)")
        ->default_str("every");
    cmd->add_option("--gpu-batch", job.gpu_batch,
                    "The most domain tasks one GPU grant carries, reduced side by side (fewer where the GPU's memory "
                    "or the end of the queue asks for it; 1: one at a time)")
        ->check(CLI::Range(1, 4096))
        ->default_str(std::to_string(kGpuBatchPerStream) + " per stream");
    cmd->add_option("--gpu-streams", job.gpu_streams,
                    "The streams a GPU runs a grant's domains on, side by side, a run of consecutive domains and a "
                    "host thread each (the surface does not depend on it)")
        ->check(CLI::Range(1, kMaxGpuStreams))
        ->capture_default_str();
    cmd->callback([&run, args, domains, gpu] {
        args->job.device = args->device.on_gpu()      ? JobConfig::Device::gpu
                           : args->device.automatic() ? JobConfig::Device::automatic
                                                      : JobConfig::Device::cpu;
        args->job.gpu = gpu->count() ? args->device.gpu : -1;
        if (args->job.lattice == 0 && args->job.mesh.empty() && args->job.split.empty())
            throw CLI::ValidationError("give --lattice N, --mesh BASE or --split DIR");
        // With a partition file or a split the count is theirs, unless one is asked for.
        if ((!args->job.partition.empty() || !args->job.split.empty() || mesh_format(args->job.mesh) == MeshFormat::pvtu) &&
            domains->count() == 0)
            args->job.domains = 0;
        run = [args] { run_job(*args); };
    });
}

} // namespace tetiso::cli
