// The job: its configuration checked, its partition built, and one task run
// (schedule.hpp). The order of the tasks and who runs them is the
// scheduler's (core/job/scheduler.hpp).
#include "tetiso/schedule.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "tetiso/error.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"
#include "tetiso/pvtu.hpp"
#include "tetiso/seam.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {

namespace {

std::unique_ptr<Partition> make_partition(const JobConfig& config, std::unique_ptr<Field> field) {
    if ((config.lattice != 0) + !config.mesh.empty() + !config.split.empty() != 1)
        throw Error("give one of a lattice size, a mesh or a split mesh");
    if (!config.split.empty()) {
        if (!config.partition.empty()) throw Error("a split mesh is partitioned already: no partition file applies");
        if (config.attribute) throw Error("a split mesh holds its field values: no node attribute applies");
        auto split = std::make_unique<SplitMeshPartition>(config.split);
        if (config.domains != 0 && config.domains != split->domain_count())
            throw Error(config.split.string() + ": " + std::to_string(split->domain_count()) + " domains, where " +
                        std::to_string(config.domains) + " were asked for");
        return split;
    }
    if (config.mesh.empty()) {
        if (!config.partition.empty()) throw Error("a partition file applies to a mesh, not to the lattice");
        if (config.attribute) throw Error("a node attribute as the field needs a mesh");
        return std::make_unique<LatticePartition>(config.lattice, config.domains, std::move(field));
    }
    if (!config.array.empty() && config.mesh.empty()) throw Error("a point array as the field needs a mesh");
    MeshSource source{config.mesh, config.attribute, config.array, config.node_ids, field.get()};
    // A .pvtu is a decomposition already: its pieces are the domains, each
    // read only by the rank that runs its task.
    if (mesh_format(config.mesh) == MeshFormat::pvtu && config.partition.empty()) {
        if (config.attribute) throw Error(config.mesh.string() + ": --attribute applies to TetGen meshes; name a point array with --array");
        auto pieces = std::make_unique<PvtuPartition>(source, std::move(field), config.ranks);
        if (config.domains != 0 && config.domains != pieces->domain_count())
            throw Error(config.mesh.string() + ": " + std::to_string(pieces->domain_count()) + " pieces, where " +
                        std::to_string(config.domains) + " domains were asked for (the pieces are the domains)");
        return pieces;
    }
    return partition_mesh(source, config.partition, config.domains);
}

} // namespace

Job::Job(const JobConfig& config) : config_(config) {
    if (config.threads < 0 || config.threads > kMaxThreads)
        throw Error(std::to_string(config.threads) + " threads per task: give 0 (all cores) to " +
                    std::to_string(kMaxThreads));
    if (config.gpu_streams < 1 || config.gpu_streams > kMaxGpuStreams)
        throw Error(std::to_string(config.gpu_streams) + " streams per GPU: give 1 to " +
                    std::to_string(kMaxGpuStreams));
    if (!std::isfinite(config.max_error_spacings) || config.max_error_spacings < 0)
        throw Error("error bound " + std::to_string(config.max_error_spacings) + " is not a finite number >= 0");
    if (!std::isfinite(config.task_timeout) || config.task_timeout < 0)
        throw Error("task timeout " + std::to_string(config.task_timeout) + " is not a finite number of seconds >= 0");
    std::unique_ptr<Field> field = make_field(config.field);
    // An attribute has no level of its own; an analytic field does, and a
    // split mesh keeps the one it was written with.
    double default_level = config.attribute || !config.array.empty() ? 0.0 : field->default_level();
    partition_ = make_partition(config, std::move(field));
    if (const auto* split = dynamic_cast<const SplitMeshPartition*>(partition_.get())) default_level = split->default_level();
    const double level = config.level.value_or(default_level);
    if (!std::isfinite(level)) throw Error("isosurface level is not a finite number");
    if (std::abs(level) > std::numeric_limits<float>::max())
        throw Error("isosurface level " + std::to_string(level) + " does not fit a float, the type of field values");
    level_ = static_cast<float>(level);
    tree_ = task_tree(partition_->tree());
    reduce_options_ = config.reduce_options;
    if (config.max_error_spacings > 0) reduce_options_.max_error = config.max_error_spacings * partition_->spacing();
    // Under MPI the node layout checks each node's GPUs, asking CUDA on one
    // rank of each node rather than on all (node_layout.hpp).
    if (config.device == JobConfig::Device::gpu && config.ranks.size <= 1)
        if (const GpuInfo info = gpu_info(std::max(0, config.gpu)); !info.available)
            throw Error("--device gpu: " + info.description);
}

Job::~Job() = default;

const std::vector<Device>& Job::gpu_lanes(int index) const {
    std::vector<Device>& made = gpus_[index];
    while (made.size() < static_cast<std::size_t>(std::max(1, config_.gpu_streams)))
        made.push_back(Device::cuda(index));
    return made;
}

const Device& Job::gpu(int index) const { return gpu_lanes(index).front(); }

void Job::use_gpu(int index, DomainTaskOptions& options) const {
    const std::vector<Device>& lanes = gpu_lanes(index);
    options.device = lanes.front();
    options.lanes.assign(lanes.begin() + 1, lanes.end());
}

void Job::prepare_gpu(int index) const {
    // The paper's field on a lattice of 24^3 nodes in two domains a stream,
    // run as one grant, the way the driver's grants run: every kernel of a
    // domain task runs on every stream, in a few milliseconds once loaded.
    const int count = 2 * static_cast<int>(gpu_lanes(index).size());
    const LatticePartition small(24, count, make_field("paper"));
    DomainTaskOptions options;
    options.level = static_cast<float>(small.field().default_level());
    use_gpu(index, options);
    options.reduce = reduce_options_;
    options.reduce->keep_samples = true;
    std::vector<int> domains(static_cast<std::size_t>(count));
    for (int d = 0; d < count; ++d) domains[static_cast<std::size_t>(d)] = d;
    run_domain_tasks(small, domains, options);
}

double Job::probe_cpu() const {
    // The paper's field on a small lattice, one domain reduced on one thread
    // with the job's bound in that lattice's spacings: a rate per raw
    // triangle near a domain task's on the same core (kCpuProbeLattice),
    // which NodePlacement scales by the domains' triangle count.
    const LatticePartition probe(kCpuProbeLattice, 1, make_field("paper"));
    DomainTaskOptions options;
    options.level = static_cast<float>(probe.field().default_level());
    options.threads = 1;
    if (config_.reduce) {
        options.reduce = reduce_options(TaskThreads{1, {}, -1});
        if (config_.max_error_spacings > 0) options.reduce->max_error = config_.max_error_spacings * probe.spacing();
        options.reduce->keep_samples = true;
    }
    const auto started = std::chrono::steady_clock::now();
    const DomainTaskResult done = run_domain_task(probe, 0, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return seconds / static_cast<double>(std::max<std::size_t>(1, done.triangles_extracted));
}

std::string Job::describe(int task) const {
    const TaskNode& n = node(task);
    if (n.count == 1) return partition_->domain_name(n.first);
    return "seam of domains " + std::to_string(n.first) + "-" + std::to_string(n.first + n.count - 1);
}

namespace {

// What a domain task's record says of its run.
Piece record_domain(DomainTaskResult& done, int gpu_index, TaskRecord& record) {
    static_cast<StageSeconds&>(record.stages) = done.seconds;
    record.stages.gpu = gpu_index;
    record.field_low = done.field_low;
    record.field_high = done.field_high;
    record.triangles_in = done.triangles_extracted;
    record.triangles_out = done.piece.triangle_count();
    record.samples_out = done.piece.sample_count();
    return std::move(done.piece);
}

void start_record(const Job& job, int task, const TaskThreads& threads, TaskRecord& record) {
    const TaskNode& n = job.node(task);
    record.task = task;
    record.kind = job.kind(task);
    record.first_domain = n.first;
    record.domain_count = n.count;
    record.threads = threads.count;
}

} // namespace

int Job::gpu_of(const TaskThreads& threads) const {
    if (threads.gpu) return *threads.gpu;
    return config_.device == JobConfig::Device::gpu ? std::max(0, config_.gpu) : -1;
}

DomainTaskOptions Job::domain_options(const TaskThreads& threads) const {
    const int gpu_index = gpu_of(threads);
    DomainTaskOptions options;
    options.level = level_;
    if (gpu_index >= 0) use_gpu(gpu_index, options);
    options.threads = threads.count;
    if (config_.reduce) {
        options.reduce = reduce_options(threads);
        options.reduce->keep_samples = true;
    }
    return options;
}

// The samples a piece of the job keeps for later seams: those near open
// interfaces, timed as part of the reduction.
void Job::keep_samples(DomainTaskResult& done) const {
    if (!config_.reduce) return;
    const auto start = std::chrono::steady_clock::now();
    keep_samples_near_locked(done.piece, config_.sample_rings);
    done.seconds.reduce += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<Piece> Job::execute_batch(const std::vector<int>& tasks, std::vector<TaskRecord>& records,
                                      const TaskThreads& threads) const {
    std::vector<int> domains;
    for (const int task : tasks) {
        if (kind(task) != TaskKind::domain) throw Error("a batch holds domain tasks only, not " + describe(task));
        domains.push_back(node(task).first);
    }
    std::vector<DomainTaskResult> done;
    try {
        done = run_domain_tasks(*partition_, domains, domain_options(threads));
    } catch (const std::exception& batch_error) {
        // Which task: the first that fails alone (the same inputs fail the
        // same way); none, and the batch as a whole failed.
        for (const int task : tasks) {
            TaskRecord alone;
            try {
                execute(task, nullptr, nullptr, alone, threads);
            } catch (const std::exception& e) {
                throw BatchTaskError(task, e.what());
            }
        }
        throw BatchTaskError(tasks.front(), "in a batch of " + std::to_string(tasks.size()) +
                                                " domain tasks on a GPU: " + batch_error.what());
    }
    records.assign(tasks.size(), TaskRecord{});
    std::vector<Piece> pieces;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        start_record(*this, tasks[i], threads, records[i]);
        keep_samples(done[i]);
        pieces.push_back(record_domain(done[i], gpu_of(threads), records[i]));
    }
    return pieces;
}

Piece Job::execute(int task, const Piece* left, const Piece* right, TaskRecord& record,
                   const TaskThreads& threads) const {
    const TaskNode& n = node(task);
    start_record(*this, task, threads, record);
    if (n.count == 1) {
        DomainTaskResult done = run_domain_task(*partition_, n.first, domain_options(threads));
        keep_samples(done);
        return record_domain(done, gpu_of(threads), record);
    }
    if (!left || !right) throw Error("seam task " + std::to_string(task) + " lacks a piece");
    record.triangles_in = left->triangle_count() + right->triangle_count();
    SeamOptions seam_options;
    seam_options.reduce = config_.reduce;
    seam_options.reduce_options = reduce_options(threads);
    // A seam given a GPU (rank 0's last seams) reduces its region there:
    // the same bytes, in a fraction of the cores' time.
    if (threads.gpu && *threads.gpu >= 0) {
        seam_options.reduce_options.device = gpu(*threads.gpu);
        record.stages.gpu = *threads.gpu;
    }
    seam_options.rings = config_.seam_rings;
    seam_options.sample_rings = config_.sample_rings;
    SeamReport seam_report;
    Piece piece = seam(*left, *right,
                       partition_->edge_domains(n.first, n.count),
                       seam_options, &seam_report);
    record.stages.merge = seam_report.seconds.merge;
    record.stages.region = seam_report.seconds.region;
    record.stages.reduce = seam_report.seconds.reduce;
    record.stages.splice = seam_report.seconds.splice;
    record.triangles_out = piece.triangle_count();
    record.samples_out = piece.sample_count();
    return piece;
}

} // namespace tetiso
