// Placing a job's tasks on one node's devices (--device auto): the node's
// ResourceManager, built from its worker processes and GPUs, and the
// requests a task makes of it.
#pragma once

#include <string>

#include "tetiso/resources.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso {

// Device memory a domain task is admitted with on a GPU: its tetrahedra,
// nodes, field values and the buffers of extraction and reduction, per
// tetrahedron of the domain, plus a margin for the kernels' scratch. An
// estimate from the sizes of the arrays, not a measurement; it errs large,
// so that processes sharing a GPU do not together exhaust it.
inline constexpr double kGpuBytesPerTet = 256;
inline constexpr double kGpuTaskMarginMiB = 64;
// Device memory each process that may use a GPU keeps for its CUDA context,
// not available to tasks.
inline constexpr double kGpuContextMiB = 512;

// The memory of CUDA device `gpu` in MiB, from gpu_info(); 0 where unknown.
double gpu_memory_mib(int gpu);

class NodePlacement {
public:
    // `processes`: the node's worker processes, its CPU capacity; `gpus`
    // GPUs of `gpu_mib` each (the smallest of the node's).
    NodePlacement(const Job& job, int processes, int gpus, double gpu_mib);

    // The request a task makes: a domain task one process on the CPU or its
    // memory on any GPU; a seam one process on the CPU (seams run there).
    ResourceRequest request(int task, const Piece* left, const Piece* right) const;

    // The CUDA index of a manager's device, -1 for the CPU.
    int gpu_of(int device) const { return manager.devices()[static_cast<std::size_t>(device)].gpu; }

    ResourceManager manager;

private:
    const Job& job_;
    double domain_tets_;
};

} // namespace tetiso
