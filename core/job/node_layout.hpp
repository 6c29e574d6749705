// Which node each rank of a job is on, each node's GPUs and which rank
// drives each (node_layout.cpp finds it over MPI; a single process is one
// node whose only worker is itself).
#pragma once

#include <vector>

#include "tetiso/schedule.hpp"

namespace tetiso {

struct NodeLayout {
    int my_gpu = -1;                     // the GPU this rank drives, -1 for none
    std::vector<int> node_of;            // by rank
    std::vector<int> driving;            // by rank: the GPU it drives, -1 for none
    std::vector<int> workers;            // by node: its worker processes
    std::vector<std::vector<int>> gpus;  // by node: the GPUs its resource manager places tasks on
    std::vector<double> gpu_mib;         // by node: its first usable GPU's memory
};

// How many of a node's worker processes drive a GPU, one GPU each. One
// process per GPU keeps the device's context, kernels and buffers warm from
// task to task and runs its tasks one after another (placement.hpp says
// why); at least one worker is left for the seams, which run on the CPU. A
// lone worker drives none: it runs the tasks granted to its node's GPUs
// itself, as the only process that uses them.
inline int driver_count(int workers, int gpus) { return workers >= 2 ? (gpus < workers - 1 ? gpus : workers - 1) : 0; }

// The layout over MPI_COMM_WORLD: ranks that share memory
// (MPI_COMM_TYPE_SHARED) are a node, named by its lowest rank, and its
// lowest worker ranks drive its GPUs. A node's GPUs are counted, and the
// first usable one's memory taken, by its first worker alone, which tells
// the others. Every rank learns the GPU it drives; rank 0 learns the whole
// layout. Collective.
NodeLayout node_layout(int rank, int ranks, const JobConfig& config);

// One process alone: a node with one worker, rank 0, driving none of the
// GPUs `gpus` of `gpu_mib` each.
NodeLayout single_process_layout(const std::vector<int>& gpus, double gpu_mib);

} // namespace tetiso
