// Which node each rank is on, its GPUs and their drivers (node_layout.hpp).
#include "node_layout.hpp"

#include <algorithm>
#include <map>

#include "tetiso/device.hpp"
#include "tetiso/placement.hpp"

#ifdef TETISO_HAVE_MPI
#include <mpi.h>
#endif

namespace tetiso {

NodeLayout single_process_layout(const std::vector<int>& gpus, double gpu_mib) {
    NodeLayout layout;
    layout.node_of = {0};
    layout.driving = {-1};
    layout.workers = {1};
    layout.gpus = {gpus};
    layout.gpu_mib = {gpu_mib};
    return layout;
}

#ifdef TETISO_HAVE_MPI

NodeLayout node_layout(int rank, int ranks, const JobConfig& config) {
    MPI_Comm local;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &local);
    int leader = rank, local_rank = 0, local_size = 1;
    MPI_Allreduce(&rank, &leader, 1, MPI_INT, MPI_MIN, local);
    MPI_Comm_rank(local, &local_rank);
    MPI_Comm_size(local, &local_size);
    // Ranks keep their order within the node (the split's key), and rank 0,
    // the lowest, is no worker.
    const int with_controller = leader == 0 ? 1 : 0;
    // One rank of the node asks CUDA what it has, the node's first worker
    // (its first GPU's driver, which needs CUDA anyway): starting CUDA's
    // driver in every rank at once took seconds that grew with the GPUs,
    // all before the first task.
    const int asking = std::min(with_controller, local_size - 1);
    int found[2] = {0, 0}; // GPUs, the first usable one's MiB
    if (local_rank == asking) {
        found[0] = gpu_count();
        const std::vector<int> usable = NodePlacement::usable_gpus(config, found[0]);
        found[1] = usable.empty() ? 0 : static_cast<int>(gpu_memory_mib(usable.front()));
    }
    MPI_Bcast(found, 2, MPI_INT, asking, local);
    MPI_Comm_free(&local);
    const int count = found[0], mib = found[1];
    const std::vector<int> usable = NodePlacement::usable_gpus(config, count);
    const int worker_index = local_rank - with_controller;
    const int drivers = driver_count(local_size - with_controller, static_cast<int>(usable.size()));
    NodeLayout layout;
    if (rank != 0 && worker_index < drivers) layout.my_gpu = usable[static_cast<std::size_t>(worker_index)];

    const int mine[4] = {leader, count, mib, layout.my_gpu};
    std::vector<int> all(4 * static_cast<std::size_t>(ranks));
    MPI_Gather(mine, 4, MPI_INT, all.data(), 4, MPI_INT, 0, MPI_COMM_WORLD);
    if (rank != 0) return layout;
    std::map<int, int> node_of_leader;
    std::vector<int> gpu_count_of;         // by node
    std::vector<std::vector<int>> driven;  // by node: the GPUs its ranks drive, in rank order
    for (int r = 0; r < ranks; ++r) {
        const int* row = &all[4 * static_cast<std::size_t>(r)];
        const auto [it, added] = node_of_leader.try_emplace(row[0], static_cast<int>(layout.workers.size()));
        if (added) {
            layout.workers.push_back(0);
            gpu_count_of.push_back(row[1]);
            layout.gpu_mib.push_back(row[2]);
            driven.emplace_back();
        }
        const auto node = static_cast<std::size_t>(it->second);
        layout.node_of.push_back(it->second);
        layout.driving.push_back(row[3]);
        if (r != 0) ++layout.workers[node];
        if (row[3] >= 0) driven[node].push_back(row[3]);
    }
    // A node's tasks go to the GPUs its ranks drive (GPUs beyond the drivers
    // stay unused: a worker that ran their tasks would be a second process
    // on them), or, for a lone worker, to every usable GPU, which it runs
    // itself.
    for (std::size_t node = 0; node < layout.workers.size(); ++node)
        layout.gpus.push_back(layout.workers[node] == 1 ? NodePlacement::usable_gpus(config, gpu_count_of[node]) : driven[node]);
    return layout;
}

#endif

} // namespace tetiso
