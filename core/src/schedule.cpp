// The job's tasks and their order (paper, section "Load balancing and job
// scheduling"), shared by the single-process and the MPI runs.
#include "tetiso/schedule.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "tetiso/placement.hpp"
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

// Appends a copy of the partition tree's subtree under `node`, in
// depth-first order; returns the copy's index.
int copy_subtree(const std::vector<DomainTreeNode>& partition_tree, int node, std::vector<TaskNode>& tree) {
    const DomainTreeNode& b = partition_tree[static_cast<std::size_t>(node)];
    const int at = static_cast<int>(tree.size());
    tree.push_back(TaskNode{b.first, b.count, -1, -1});
    if (b.left >= 0) {
        const int left = copy_subtree(partition_tree, b.left, tree);
        const int right = copy_subtree(partition_tree, b.right, tree);
        tree[static_cast<std::size_t>(at)].left = left;
        tree[static_cast<std::size_t>(at)].right = right;
    }
    return at;
}

} // namespace

std::vector<TaskNode> task_tree(const std::vector<DomainTreeNode>& partition_tree) {
    // The subtrees hanging off the partition tree's rightmost path, in
    // domain order: each left child on the path, then the path's last leaf.
    std::vector<int> hanging;
    int node = 0;
    while (partition_tree[static_cast<std::size_t>(node)].left >= 0) {
        hanging.push_back(partition_tree[static_cast<std::size_t>(node)].left);
        node = partition_tree[static_cast<std::size_t>(node)].right;
    }
    hanging.push_back(node);

    // The chain's seams first, root at 0: seam k (k = 0 .. h-2, h subtrees)
    // joins the first h-1-k subtrees, seam k+1's piece, with subtree h-1-k.
    // Then the subtrees in domain order, so leaf tasks keep it too.
    const int seams = static_cast<int>(hanging.size()) - 1;
    std::vector<TaskNode> tree(static_cast<std::size_t>(seams));
    std::vector<int> subtree_root;
    for (const int h : hanging) subtree_root.push_back(copy_subtree(partition_tree, h, tree));
    for (int k = 0; k < seams; ++k) {
        const int joined = seams - k; // the subtree this seam adds
        const int rest = k + 1 < seams ? k + 1 : subtree_root[0];
        TaskNode& seam = tree[static_cast<std::size_t>(k)];
        seam.left = rest;
        seam.right = subtree_root[static_cast<std::size_t>(joined)];
        seam.first = 0;
        seam.count = tree[static_cast<std::size_t>(seam.right)].first + tree[static_cast<std::size_t>(seam.right)].count;
    }
    return tree;
}

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
    if (!std::isfinite(config.max_error_spacings) || config.max_error_spacings < 0)
        throw Error("error bound " + std::to_string(config.max_error_spacings) + " is not a finite number >= 0");
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
    if (config.device == JobConfig::Device::gpu)
        if (const GpuInfo info = gpu_info(config.gpu); !info.available) throw Error("--device gpu: " + info.description);
}

Job::~Job() = default;

const Device& Job::gpu(int index) const {
    Device& made = gpus_[index];
    if (!made.is_gpu()) made = Device::cuda(index);
    return made;
}

void Job::prepare_gpu(int index) const {
    // The paper's field on a lattice of 24^3 nodes in one domain: every
    // kernel of a domain task runs, in a few milliseconds once loaded.
    const LatticePartition one(24, 1, make_field("paper"));
    DomainTaskOptions options;
    options.level = static_cast<float>(one.field().default_level());
    options.device = gpu(index);
    options.reduce = reduce_options_;
    options.reduce->keep_samples = true;
    run_domain_task(one, 0, options);
}

std::string Job::describe(int task) const {
    const TaskNode& n = node(task);
    if (n.count == 1) return partition_->domain_name(n.first);
    return "seam of domains " + std::to_string(n.first) + "-" + std::to_string(n.first + n.count - 1);
}

Piece Job::execute(int task, const Piece* left, const Piece* right, TaskRecord& record,
                   const TaskThreads& threads) const {
    const TaskNode& n = node(task);
    record.task = task;
    record.kind = kind(task);
    record.first_domain = n.first;
    record.domain_count = n.count;
    record.threads = threads.count;
    using clock = std::chrono::steady_clock;
    if (n.count == 1) {
        const int gpu_index = threads.gpu ? *threads.gpu : config_.device == JobConfig::Device::gpu ? config_.gpu : -1;
        DomainTaskOptions options;
        options.level = level_;
        if (gpu_index >= 0) options.device = gpu(gpu_index);
        options.threads = threads.count;
        if (config_.reduce) {
            options.reduce = reduce_options(threads);
            options.reduce->keep_samples = true;
        }
        DomainTaskResult done = run_domain_task(*partition_, n.first, options);
        if (config_.reduce) {
            const auto start = clock::now();
            keep_samples_near_locked(done.piece, config_.sample_rings);
            done.seconds.reduce += std::chrono::duration<double>(clock::now() - start).count();
        }
        static_cast<StageSeconds&>(record.stages) = done.seconds;
        record.stages.gpu = gpu_index;
        record.field_low = done.field_low;
        record.field_high = done.field_high;
        record.triangles_in = done.triangles_extracted;
        record.triangles_out = done.piece.triangle_count();
        record.samples_out = done.piece.sample_count();
        return std::move(done.piece);
    }
    if (!left || !right) throw Error("seam task " + std::to_string(task) + " lacks a piece");
    record.triangles_in = left->triangle_count() + right->triangle_count();
    SeamOptions seam_options;
    seam_options.reduce = config_.reduce;
    seam_options.reduce_options = reduce_options(threads);
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

TaskQueue::TaskQueue(const Job& job) {
    const int count = job.task_count();
    parent_.assign(static_cast<std::size_t>(count), -1);
    children_done_.assign(static_cast<std::size_t>(count), 0);
    for (int t = 0; t < count; ++t) {
        const TaskNode& n = job.node(t);
        if (n.left >= 0) {
            parent_[static_cast<std::size_t>(n.left)] = t;
            parent_[static_cast<std::size_t>(n.right)] = t;
        } else {
            // Leaf task indices follow domain ids (task_tree): ordering leaves
            // by task index orders them by domain.
            ready_.insert({1, t});
        }
    }
}

int TaskQueue::pop() {
    const int task = ready_.begin()->second;
    ready_.erase(ready_.begin());
    return task;
}

void TaskQueue::complete(int task) {
    const int parent = parent_[static_cast<std::size_t>(task)];
    if (parent < 0) {
        done_root_ = true;
        return;
    }
    if (++children_done_[static_cast<std::size_t>(parent)] == 2) ready_.insert({0, parent});
}

JobResult run_local(const Job& job, const Progress& progress) {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    auto seconds = [&] { return std::chrono::duration<double>(clock::now() - start).count(); };
    TaskQueue queue(job);
    std::vector<std::optional<Piece>> pieces(static_cast<std::size_t>(job.task_count()));
    JobResult result;
    int done = 0;
    std::optional<NodePlacement> placement;
    if (job.config().device == JobConfig::Device::automatic) {
        const std::vector<int> gpus = NodePlacement::usable_gpus(job.config(), gpu_count());
        placement.emplace(job, 1, gpus, gpus.empty() ? 0.0 : gpu_memory_mib(gpus.front()));
    }
    while (!queue.finished()) {
        const int task = queue.pop();
        const TaskNode& n = job.node(task);
        TaskRecord record;
        record.start = seconds();
        const Piece* left = n.left >= 0 ? &*pieces[static_cast<std::size_t>(n.left)] : nullptr;
        const Piece* right = n.right >= 0 ? &*pieces[static_cast<std::size_t>(n.right)] : nullptr;
        TaskThreads threads{job.config().threads, {}, {}};
        // One process runs one task at a time: every grant starts at once,
        // and the choice is the device predicted fastest.
        Grant grant;
        if (placement) {
            grant = placement->manager.request(placement->request(task, left, right), seconds());
            placement->manager.start(grant.ticket, seconds());
            threads.gpu = placement->gpu_of(grant.device);
        }
        try {
            pieces[static_cast<std::size_t>(task)] = job.execute(task, left, right, record, threads);
        } catch (const Error& e) {
            throw Error("task '" + job.describe(task) + "' failed: " + e.what());
        } catch (const std::bad_alloc&) {
            throw Error("task '" + job.describe(task) + "' failed: out of memory");
        }
        if (n.left >= 0) {
            pieces[static_cast<std::size_t>(n.left)].reset();
            pieces[static_cast<std::size_t>(n.right)].reset();
        }
        record.end = seconds();
        if (placement) placement->finish(grant, record.end - record.start, record);
        result.tasks.push_back(record);
        queue.complete(task);
        if (progress) progress(++done, job.task_count(), seconds());
    }
    result.surface = std::move(*pieces[0]);
    result.seconds = seconds();
    return result;
}

bool launched_with_mpi() {
#ifdef TETISO_HAVE_MPI
    for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
        if (std::getenv(variable)) return true;
#endif
    return false;
}

} // namespace tetiso
