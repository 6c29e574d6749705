// Internal: the job's task tree (schedule.hpp, task_tree) run over the
// ranks of an in-situ call. The tree is the file route's, so the same
// pieces meet in the same order; only who runs each task differs: a domain
// task on the rank that holds its piece, a seam on the rank of its left
// child, the right child's piece sent there. Every rank walks its own tasks
// from the last index to the first (children come after their parent), so
// a wait for a piece is a wait for a task no later in that order: the walk
// cannot deadlock. A task that fails sends a failure in place of its piece,
// so every wait ends; the caller agrees on the failure afterwards.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tetiso/device.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::insitu {

struct TreeOptions {
    float level = 0;
    bool reduce = true;
    ReduceOptions reduce_options; // max_error set already
    int seam_rings = 1, sample_rings = 1;
    int threads = 1;
    Device device{};
    int root = 0;
};

struct TreeRun {
    std::optional<Piece> surface; // on the root, unless a task failed
    std::string problem;          // this rank's own failure, if any
    double domain_seconds = 0, seam_seconds = 0;
    StageSeconds stages;
    std::int64_t triangles_extracted = 0, triangles_reduced = 0;
    int seams = 0;
    std::int64_t bytes_sent = 0, bytes_received = 0;
};

// Collective over `comm`. Rank r holds domain `domain_of_rank[r]` (which
// `partition.make_domain` builds on that rank only). Never throws for a
// task's failure: it is in `problem` on the rank where it happened.
TreeRun run_tree(MPI_Comm comm, const Partition& partition, const std::vector<int>& domain_of_rank, const TreeOptions& options);

} // namespace tetiso::insitu
