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
#include "tetiso/extract.hpp"
#include "tetiso/gpu.hpp"
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
    if (config.device == JobConfig::Device::gpu)
        if (const GpuInfo info = gpu_info(config.gpu); !info.available) throw Error("--device gpu: " + info.description);
}

Job::~Job() = default;

Gpu& Job::gpu(int index) const {
    std::unique_ptr<Gpu>& made = gpus_[index];
    if (!made) made = std::make_unique<Gpu>(index);
    return *made;
}

void Job::prepare_gpu(int index) const {
    // The paper's field on a lattice of 24^3 nodes in one domain: every
    // kernel of a domain task runs, in a few milliseconds once loaded.
    const Lattice lattice(24);
    const Decomposition one(lattice, 1);
    const auto field = make_field("paper");
    ReduceOptions options = reduce_options_;
    options.keep_samples = true;
    gpu(index).extract_and_reduce(one, 0, *field, static_cast<float>(field->default_level()), options);
}

Piece Job::execute_on_gpu(int domain, int gpu_index, TaskRecord& record, const ReduceOptions& options) const {
    Gpu& gpu = this->gpu(gpu_index);
    const auto* lattice = dynamic_cast<const LatticePartition*>(partition_.get());
    const auto start = std::chrono::steady_clock::now();
    Piece piece;
    ReduceReport report;
    double reduce_seconds = 0; // a piece reduced by the host's rules around pinches
    std::size_t extracted = 0;
    if (lattice && !config_.reduce) {
        piece = gpu.extract(lattice->decomposition(), domain, lattice->field(), level_);
    } else if (lattice) {
        piece = gpu.extract_and_reduce(lattice->decomposition(), domain, lattice->field(), level_, options, &report);
    } else {
        const Domain d = partition_->make_domain(domain);
        record.stages.generate = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (!config_.reduce) {
            piece = gpu.extract(d, level_);
        } else if (partition_->pieces_are_manifold()) {
            piece = gpu.extract_and_reduce(d, level_, options, &report);
        } else {
            piece = gpu.extract(d, level_);
            extracted = piece.triangle_count();
            const auto t = std::chrono::steady_clock::now();
            const GpuTimings extraction = gpu.last_timings();
            piece = reduce_piece(piece, options, &report, [&gpu](const Piece& p, const ReduceOptions& o, ReduceReport* r) {
                return gpu.reduce(p, o, r);
            });
            reduce_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
            record.stages.upload = extraction.upload;
            record.stages.extract = extraction.extract;
            record.stages.download = extraction.download;
            record.stages.reduce = reduce_seconds;
        }
    }
    if (reduce_seconds == 0) {
        const GpuTimings& t = gpu.last_timings();
        record.stages.upload = t.upload;
        record.stages.extract = t.extract;
        record.stages.reduce = t.reduce;
        record.stages.download = t.download;
    }
    record.stages.gpu = gpu.device();
    record.triangles_in = extracted > 0 ? extracted : config_.reduce ? report.triangles_in : piece.triangle_count();
    return piece;
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
    auto t0 = clock::now();
    auto lap = [&t0] {
        const auto t1 = clock::now();
        const double s = std::chrono::duration<double>(t1 - t0).count();
        t0 = t1;
        return s;
    };
    const int gpu = threads.gpu ? *threads.gpu : config_.device == JobConfig::Device::gpu ? config_.gpu : -1;
    if (n.count == 1 && gpu >= 0) {
        ReduceOptions options = reduce_options(threads);
        options.keep_samples = true;
        Piece piece = execute_on_gpu(n.first, gpu, record, options);
        if (config_.reduce) keep_samples_near_locked(piece, config_.sample_rings);
        record.triangles_out = piece.triangle_count();
        record.samples_out = piece.sample_count();
        return piece;
    }
    if (n.count == 1) {
        Piece piece;
        {
            const Domain domain = partition_->make_domain(n.first);
            record.stages.generate = lap();
            if (!domain.f.empty()) {
                const auto [low, high] = std::minmax_element(domain.f.begin(), domain.f.end());
                record.field_low = *low;
                record.field_high = *high;
            }
            piece = extract(domain, level_, ExtractOptions{threads.count});
        } // the tetrahedra go before the reduction needs its memory
        record.stages.extract = lap();
        record.triangles_in = piece.triangle_count();
        if (config_.reduce) {
            ReduceOptions options = reduce_options(threads);
            options.keep_samples = true;
            piece = partition_->pieces_are_manifold() ? reduce(piece, options) : reduce_piece(piece, options);
            keep_samples_near_locked(piece, config_.sample_rings);
        }
        record.stages.reduce = lap();
        record.triangles_out = piece.triangle_count();
        record.samples_out = piece.sample_count();
        return piece;
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

} // namespace tetiso
