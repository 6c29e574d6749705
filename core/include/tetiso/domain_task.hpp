// One domain's task (paper, section "Load balancing and job scheduling"):
// its tetrahedra, marching tetrahedra, and the reduction of its piece, on
// the host or a GPU as its Device says, with the same bytes on either. On a
// GPU the piece stays on the device from the field values to the reduced
// piece, and a lattice domain is built there too (a built-in field
// evaluated there), so that only the piece crosses the bus.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include "tetiso/device.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

struct DomainTaskOptions {
    float level = 0;
    // Where the task runs, and the host's threads for its extraction (the
    // reduction's are reduce->threads and reduce->more_threads).
    Device device{};
    int threads = 1;
    // Reduce the extracted piece with these options (their device replaced
    // by the task's); none: extract only.
    std::optional<ReduceOptions> reduce;
    // On a GPU, the most raw triangles run_domain_tasks reduces side by side
    // in one batch (a batch's arrays must fit the GPU's memory, whatever its
    // other tasks hold); 0: every domain of the call in one batch. A domain
    // over it is a batch of its own. The pieces do not depend on it.
    std::size_t batch_triangles = 0;
    // On a GPU: more CUDA Devices (of the same GPU, each its own stream and
    // buffers) over which run_domain_tasks spreads its domains, one run of
    // consecutive domains per Device, each driven by a host thread of its
    // own. A round's kernels wait mostly on latency, not on the memory
    // system: a second stream's kernels fill the multiprocessors meanwhile
    // (batches of 32 domains on an H200: 6.3 M raw triangles/s on one
    // stream, 8.1 M on two; results/reduce-gpu). Each Device, `device`
    // included, must be a different one. The pieces do not depend on it.
    std::vector<Device> lanes;
};

struct DomainTaskResult {
    Piece piece;
    StageSeconds seconds;
    std::size_t triangles_extracted = 0;
    // The domain's lowest and highest field value where the host held them
    // (low > high where the values stayed on a GPU): a surface that comes
    // out empty says whether its level lies outside them.
    float field_low = std::numeric_limits<float>::infinity();
    float field_high = -std::numeric_limits<float>::infinity();
};

// Domain `domain` of a partition, made by the partition (a lattice domain by
// the GPU itself); a piece the partition says may be pinched is reduced by
// reduce_piece. Throws tetiso::Error as make_domain, extract and reduce do.
DomainTaskResult run_domain_task(const Partition& partition, int domain, const DomainTaskOptions& options);

// Several domains of one partition in one call, results in the order of
// `domains`. On a GPU, with a reduction, their pieces are extracted one after
// the other and reduced side by side in batches (reduce_batch,
// options.batch_triangles), so that the fixed cost of a round is paid once
// for a batch; elsewhere (the host, extraction only, a partition whose
// pieces may be pinched) the domains run one after the other: on the host a
// round's fixed cost is small beside its work, and batching measured slower
// there than one domain per thread (results/reduce-batch). On a GPU with
// options.lanes, the domains are cut into as many runs of consecutive ones
// as there are Devices, run side by side. Each result's piece is byte for
// byte what run_domain_task gives for that domain alone; its seconds are its
// extraction's and its share, by raw triangles, of its batch's reduction.
// Throws tetiso::Error as run_domain_task does for the first domain that
// fails.
std::vector<DomainTaskResult> run_domain_tasks(const Partition& partition, const std::vector<int>& domains,
                                               const DomainTaskOptions& options);

// A domain already built, whose piece is a 2-manifold (a convex domain's);
// it is released before the reduction runs.
DomainTaskResult run_domain_task(Domain domain, const DomainTaskOptions& options);

} // namespace tetiso
