// Placing a job's tasks on one node's devices (placement.hpp).
#include "tetiso/placement.hpp"

#include <algorithm>
#include <cmath>

#include "tetiso/error.hpp"
#include "tetiso/device.hpp"

namespace tetiso {

double gpu_memory_mib(int gpu) {
    const GpuInfo info = gpu_info(gpu);
    return info.available ? static_cast<double>(info.memory_bytes) / (1 << 20) : 0;
}

namespace {

std::vector<ManagedDevice> node_devices(int cpu_processes, const std::vector<int>& gpus) {
    std::vector<ManagedDevice> devices{{"cpu", -1, static_cast<double>(std::max(1, cpu_processes)), 0}};
    for (const int g : gpus) devices.push_back({"gpu " + std::to_string(g), g, 1, 0});
    return devices;
}

} // namespace

NodePlacement::NodePlacement(const Job& job, int cpu_processes, const std::vector<int>& gpus, double gpu_mib,
                             bool domains_on_cpu, double cpu_seconds_per_triangle)
    : manager(node_devices(cpu_processes, gpus)),
      job_(job),
      domain_tets_(std::max(1.0, static_cast<double>(job.partition().tet_count()) / job.partition().domain_count())),
      task_mib_(domain_tets_ * kGpuBytesPerTet / (1 << 20) + kGpuTaskMarginMiB),
      usable_mib_(gpu_mib * kGpuUsableShare - kGpuContextMiB),
      domains_on_cpu_(domains_on_cpu),
      batch_limit_(static_cast<int>(
          std::clamp(std::floor(usable_mib_ / task_mib_), 1.0, static_cast<double>(gpu_batch_of(job.config()))))),
      cpu_seconds_per_triangle_(cpu_seconds_per_triangle) {}

bool NodePlacement::cpu_takes(TaskKind kind) const {
    if (kind == TaskKind::seam) return true;
    if (!domains_on_cpu_) return false;
    // Waiting for the prior only makes sense where a GPU could take the task.
    const bool gpu_fits = manager.devices().size() > 1 && task_mib_ <= usable_mib_;
    if (!gpu_fits || !(cpu_seconds_per_triangle_ > 0)) return true;
    const int domain = static_cast<int>(TaskKind::domain);
    if (!manager.has_prior(domain, 0) && !manager.model(domain, 0)) return false;
    // Nor before each GPU has run batches of two sizes: until then its
    // batches are assumed to take their tasks' time one after another, often
    // several times too long, and the cores would take domains the GPUs end
    // first.
    if (batch_limit_ <= 1) return true;
    for (std::size_t d = 1; d < manager.devices().size(); ++d) {
        const PerformanceModel* m = manager.model(domain, static_cast<int>(d));
        if (!m || m->sizes() < 2) return false;
    }
    return true;
}

void NodePlacement::learn_domain_triangles(double raw_triangles) {
    domain_triangles_ += std::max(raw_triangles, 0.0);
    ++domains_ended_;
    if (!(cpu_seconds_per_triangle_ > 0) || !domains_on_cpu_) return;
    // An empty domain still costs its generation and extraction: at least one
    // triangle's worth, so that the prior stays a time.
    const double triangles = std::max(1.0, domain_triangles_ / domains_ended_);
    manager.set_prior(static_cast<int>(TaskKind::domain), 0, cpu_seconds_per_triangle_ * triangles / domain_tets_);
}

void NodePlacement::finish(const Grant& grant, double seconds, TaskRecord& record) {
    const double transfer = record.stages.upload + record.stages.download;
    manager.finish(grant.ticket, std::max(0.0, seconds - transfer), transfer);
    record.predicted_seconds = grant.predicted_seconds;
}

void NodePlacement::finish(const Grant& grant, double seconds, std::vector<TaskRecord*> records) {
    double transfer = 0;
    for (const TaskRecord* r : records) transfer += r->stages.upload + r->stages.download;
    manager.finish(grant.ticket, std::max(0.0, seconds - transfer), transfer);
    for (TaskRecord* r : records) r->predicted_seconds = grant.predicted_seconds / static_cast<double>(records.size());
}

std::vector<int> NodePlacement::usable_gpus(const JobConfig& config, int count) {
    std::vector<int> gpus;
    for (int g = 0; g < count; ++g)
        if (config.device != JobConfig::Device::gpu || config.gpu < 0 || g == config.gpu) gpus.push_back(g);
    return gpus;
}

ResourceRequest NodePlacement::request(int task, const Piece* left, const Piece* right, int most_in_batch,
                                       bool seams_on_gpus) const {
    ResourceRequest r;
    r.kind = static_cast<int>(job_.kind(task));
    r.units.assign(manager.devices().size(), 0.0);
    r.units[0] = 1; // one worker process on the CPU
    if (job_.kind(task) == TaskKind::seam) {
        r.size = static_cast<double>((left ? left->triangle_count() : 0) + (right ? right->triangle_count() : 0));
        const bool fits = r.size * kGpuBytesPerSeamTriangle / (1 << 20) + kGpuTaskMarginMiB <= usable_mib_;
        for (std::size_t d = 1; d < r.units.size(); ++d) r.units[d] = seams_on_gpus && fits ? 1 : 0;
        return r;
    }
    // Domains differ little in size (bisection or METIS balances them):
    // the mean is the task's size, and the models see each kind of task.
    r.size = domain_tets_;
    if (!cpu_takes(TaskKind::domain)) {
        r.units[0] = 0;
        r.alone_elsewhere_later = domains_on_cpu_;
    }
    const bool fits = task_mib_ <= usable_mib_;
    for (std::size_t d = 1; d < r.units.size(); ++d) r.units[d] = fits ? 1 : 0;
    r.batch.assign(r.units.size(), std::clamp(most_in_batch, 1, batch_limit_));
    r.batch[0] = 1; // the CPU runs one task per process
    if (!domains_on_cpu_ && (!fits || r.units.size() < 2))
        throw Error("--device gpu: " + job_.describe(task) + " needs about " + std::to_string(std::lround(task_mib_)) +
                    " MiB of GPU memory, more than the " + std::to_string(std::lround(std::max(0.0, usable_mib_))) +
                    " MiB a GPU of its node has for tasks");
    return r;
}

} // namespace tetiso
