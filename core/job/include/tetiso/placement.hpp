// Placing a job's tasks on one node's devices (--device auto, and --device
// gpu under MPI): the node's ResourceManager, built from its CPU worker
// processes and its GPUs, and the requests a task makes of it.
//
// Units. The CPU counts worker processes, one per task. A GPU counts task
// slots, one: each GPU is driven by one process of its node, which keeps the
// device's context, compiled kernels and buffers from one task to the next,
// and runs its grants one after another. A grant on a GPU carries a batch of
// domain tasks (run_domain_tasks reduces them side by side, a run of them on
// each of the GPU's --gpu-streams streams): at most --gpu-batch, as many as
// the GPU's memory holds by the estimate below, and no more than half the
// GPUs' share of the domains still waiting, so that the batches shrink at
// the end of the queue, every GPU gets some and pieces keep coming back for
// the seams. Once every domain task is placed, a grant on a GPU may also
// carry a seam (request()). Processes that each open a context on
// one GPU pay its set-up each, and their kernels are time-sliced, not run
// side by side; one task at a time in one context is the fastest way to share
// a GPU and the safe one: its memory holds one task's buffers. The memory a
// task needs is therefore not a counter but a condition: a domain whose
// estimate does not fit the GPU may only run on the CPU.
//
// The CPU's prior. A domain takes a core seconds and a GPU a tenth of one:
// where every idle core took a domain before any model was calibrated, the
// job could not end before those tasks did, though the GPUs could have done
// them all by then. So where a GPU may take domain tasks and the job measured
// the CPU's speed at start-up (Job::probe_cpu: seconds per raw triangle of a
// small reduction on one core), the CPU takes no domain task until a first
// domain task has ended somewhere and each GPU has run batches of two sizes
// (the manager caps a GPU's second grant at kLearningBatch tasks, so that
// this takes a fraction of a second). The first domain task says how many
// raw triangles a domain has, and the CPU's prior for a domain task is the
// probe's rate times that count (the mean of the domain tasks ended so far);
// its own tasks replace the prior as they end. The cores wait at most about
// one GPU batch at the start.
#pragma once

#include <vector>

#include "tetiso/resources.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso {

// Device memory a domain task needs on a GPU: its tetrahedra, nodes, field
// values and the buffers of extraction and reduction, per tetrahedron of the
// domain, plus a margin for the kernels' scratch. An estimate from the sizes
// of the arrays, not a measurement; it errs large.
inline constexpr double kGpuBytesPerTet = 256;
inline constexpr double kGpuTaskMarginMiB = 64;
// Device memory a seam needs on a GPU per triangle of its two pieces: the
// region it reduces there is part of them (an estimate that errs large).
inline constexpr double kGpuBytesPerSeamTriangle = 1024;
// Device memory the driving process's CUDA context keeps, not available to
// tasks.
inline constexpr double kGpuContextMiB = 512;
// The share of a GPU's memory a task may plan on: the rest is left to the
// driver and to other users of the device.
inline constexpr double kGpuUsableShare = 0.95;
// The most domain tasks of one GPU grant unless --gpu-batch says otherwise:
// this many for each of the GPU's streams (--gpu-streams), which run a run of
// the grant's domains each.
inline constexpr int kGpuBatchPerStream = 32;
// The most domain tasks of one GPU grant under `config`: --gpu-batch, or
// its default.
inline int gpu_batch_of(const JobConfig& config) {
    return config.gpu_batch > 0 ? config.gpu_batch : kGpuBatchPerStream * config.gpu_streams;
}

// The memory of CUDA device `gpu` in MiB, from gpu_info(); 0 where unknown.
double gpu_memory_mib(int gpu);

class NodePlacement {
public:
    // `cpu_processes`: the node's processes that run tasks on the CPU, its
    // CPU capacity (at least 1); `gpus`: the CUDA indices of the GPUs the
    // node's tasks may use, of `gpu_mib` each (the first usable one's);
    // `domains_on_cpu`: false under --device gpu, where domain tasks run on
    // a GPU only.
    // `cpu_seconds_per_triangle`: the probe's rate, 0 where there was none
    // (the CPU then learns from its own first tasks, taken at once).
    NodePlacement(const Job& job, int cpu_processes, const std::vector<int>& gpus, double gpu_mib,
                  bool domains_on_cpu = true, double cpu_seconds_per_triangle = 0);

    // The request a task makes: a domain task one CPU process or one slot on
    // any GPU whose memory holds it, where it may come with up to
    // min(most_in_batch, batch_limit()) - 1 more domain tasks; a seam one
    // CPU process, or with `seams_on_gpus` one slot on a GPU whose memory
    // holds its region (the caller allows it once no domain task is left to
    // place: a GPU then has nothing else to do, and a seam of the job's last
    // ones, of up to the whole surface, would otherwise run on one worker's
    // cores). Throws tetiso::Error when a domain may run on a GPU only and
    // fits none.
    ResourceRequest request(int task, const Piece* left, const Piece* right, int most_in_batch = 1,
                            bool seams_on_gpus = false) const;

    // Whether the CPU may take a task of this kind now: a seam always; a
    // domain task under --device auto unless the CPU waits for its prior
    // (above).
    bool cpu_takes(TaskKind kind) const;
    // A domain task ended with `raw_triangles` extracted (on any node): the
    // CPU's prior follows the mean.
    void learn_domain_triangles(double raw_triangles);

    // The most domain tasks a GPU grant may carry: --gpu-batch, and what the
    // GPU's memory holds by the estimate (at least 1).
    int batch_limit() const { return batch_limit_; }

    // Tells the manager that the task of `grant` ended: it took `seconds` in
    // all, of which the record's upload and download were transfer, which the
    // manager learns apart from the device's time. The record gets the
    // grant's prediction.
    void finish(const Grant& grant, double seconds, TaskRecord& record);
    // The same for a grant's batch, which took `seconds` in all: each record
    // gets its share of the prediction.
    void finish(const Grant& grant, double seconds, std::vector<TaskRecord*> records);

    // The GPUs a node's tasks may use, of the `count` it has: every one,
    // or under --device gpu the one --gpu names where it names one.
    static std::vector<int> usable_gpus(const JobConfig& config, int count);

    // The CUDA index of a manager's device, -1 for the CPU.
    int gpu_of(int device) const { return manager.devices()[static_cast<std::size_t>(device)].gpu; }

    ResourceManager manager;

private:
    const Job& job_;
    double domain_tets_;
    double task_mib_;   // a domain task's estimated device memory
    double usable_mib_; // a GPU's memory less its context and a margin
    bool domains_on_cpu_;
    int batch_limit_;
    double cpu_seconds_per_triangle_;
    double domain_triangles_ = 0; // raw triangles of the domain tasks ended so far
    int domains_ended_ = 0;
};

} // namespace tetiso
