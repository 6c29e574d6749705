// Placing a job's tasks on one node's devices (placement.hpp).
#include "tetiso/placement.hpp"

#include <algorithm>

#include "tetiso/gpu.hpp"

namespace tetiso {

double gpu_memory_mib(int gpu) {
    const GpuInfo info = gpu_info(gpu);
    return info.available ? static_cast<double>(info.memory_bytes) / (1 << 20) : 0;
}

namespace {

std::vector<ManagedDevice> node_devices(int processes, int gpus, double gpu_mib) {
    std::vector<ManagedDevice> devices{{"cpu", -1, static_cast<double>(std::max(1, processes)), 0}};
    const double per_gpu = gpu_mib * 0.95 - kGpuContextMiB * std::max(1, processes);
    if (per_gpu > kGpuTaskMarginMiB)
        for (int g = 0; g < gpus; ++g) devices.push_back({"gpu " + std::to_string(g), g, per_gpu, 0});
    return devices;
}

} // namespace

NodePlacement::NodePlacement(const Job& job, int processes, int gpus, double gpu_mib)
    : manager(node_devices(processes, gpus, gpu_mib)),
      job_(job),
      domain_tets_(std::max(1.0, static_cast<double>(job.partition().tet_count()) / job.partition().domain_count())) {}

ResourceRequest NodePlacement::request(int task, const Piece* left, const Piece* right) const {
    ResourceRequest r;
    r.kind = static_cast<int>(job_.kind(task));
    r.units.assign(manager.devices().size(), 0.0);
    r.units[0] = 1; // one worker process on the CPU
    if (job_.kind(task) == TaskKind::seam) {
        r.size = static_cast<double>((left ? left->triangle_count() : 0) + (right ? right->triangle_count() : 0));
        return r;
    }
    // Domains differ little in size (bisection or METIS balances them):
    // the mean is the task's size, and the models see each kind of task.
    r.size = domain_tets_;
    const double mib = domain_tets_ * kGpuBytesPerTet / (1 << 20) + kGpuTaskMarginMiB;
    for (std::size_t d = 1; d < r.units.size(); ++d) r.units[d] = mib;
    return r;
}

} // namespace tetiso
