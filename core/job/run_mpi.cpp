// The MPI master/worker run (paper, section "Load balancing and job
// scheduling"): rank 0 runs the scheduler (scheduler.hpp) over the MPI
// transport; a worker says it is ready, receives a task with the pieces it
// needs, and returns the piece it made, which also says it is ready again
// (mpi_worker.hpp). Load balances itself and the output does not depend on
// it.
//
// Failure: a task that throws, on a worker or on rank 0, is reported to rank
// 0, which stops handing out work, waits for the tasks in flight, tells every
// worker to stop and raises the error — no rank is left blocked, so
// MPI_Finalize returns everywhere and the launcher exits with a non-zero
// status. A rank that stops answering cannot be stopped in order: rank 0
// names it, or a worker names rank 0, and the job is aborted.
#include "tetiso/schedule.hpp"

#ifdef TETISO_HAVE_MPI

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "affinity.hpp"
#include "mpi_transport.hpp"
#include "mpi_worker.hpp"
#include "node_layout.hpp"
#include "stop_signals.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Rank 0's side of the job.
JobResult control(const Job& job, int ranks, const Progress& progress, const std::optional<NodeLayout>& nodes) {
    TasksInFlight in_flight;
    SchedulerSetup setup;
    setup.ranks = ranks;
    setup.seams_here = true;
    setup.nodes = nodes;
    setup.task_timeout = job.config().task_timeout;
    // Rank 0 has nothing to do until the workers are ready, the GPUs' drivers
    // longest: the probe costs the job nothing.
    const bool gpus = nodes && std::any_of(nodes->gpus.begin(), nodes->gpus.end(), [](const auto& g) { return !g.empty(); });
    if (gpus && job.config().device == JobConfig::Device::automatic) setup.cpu_seconds_per_triangle = job.probe_cpu();
    Scheduler scheduler(job, setup);
    MpiTransport transport(ranks, setup.task_timeout);
    cpu_set_t own_cores;
    const bool own_cores_known = current_cores(own_cores);

    DriveHooks hooks;
    hooks.progress = progress;
    hooks.on_running = [&](const std::map<int, int>& running) {
        in_flight.update(job, running, ranks, scheduler.batches());
    };
    // A seam run here runs on the cores of rank 0 and of every worker, which
    // are all idle then and wait without spinning: one thread per rank's
    // share, on the union of the ranks' bindings. Threads do not change the
    // result. Otherwise the job's last seams, mostly their reduction near the
    // seam, would run on one rank's cores with the others idle.
    // The seams run here are the job's last, with every other rank idle: on
    // a node with GPUs their regions are reduced on its first (rank 0 opens
    // a context there at the first of them), the cores doing the rest.
    std::optional<int> seam_gpu;
    if (nodes && job.config().reduce)
        if (const auto& here = nodes->gpus[static_cast<std::size_t>(nodes->node_of[0])]; !here.empty())
            seam_gpu = here.front();
    hooks.run_here = [&](int task, const Piece* left, const Piece* right) {
        int threads = job.config().threads;
        cpu_set_t job_cores;
        if (own_cores_known && transport.job_cores(job_cores)) {
            threads = std::min(std::max(1, threads) * ranks, kMaxThreads);
            run_on(job_cores, threads);
        }
        const auto back_home = [&] {
            if (own_cores_known) run_on(own_cores, std::max(1, job.config().threads));
        };
        TaskRecord record;
        const auto started = Clock::now();
        Piece piece;
        try {
            // Between reduction rounds, heartbeats: the workers wait on rank 0.
            const auto keep_alive = [&transport] {
                transport.keep_alive();
                return 0;
            };
            piece = job.execute(task, left, right, record, TaskThreads{threads, keep_alive, seam_gpu});
        } catch (...) {
            back_home();
            throw;
        }
        back_home();
        const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
        return result_message(record, seconds, record.threads, std::move(piece));
    };
    std::optional<JobResult> result = drive(job, scheduler, transport, hooks);
    if (result) return std::move(*result);
    const SchedulerFailure& failure = *scheduler.failure();
    if (failure.unresponsive) {
        // Nothing is written yet; the stopped rank cannot be told to stop,
        // and MPI_Finalize would wait for it: the launcher ends every rank.
        in_flight.disarm();
        if (failure.task >= 0)
            std::fprintf(stderr,
                         "tetiso: rank %d stopped answering: its task '%s' did not end within %.0f s (the deadline; "
                         "--task-timeout sets it); the job is stopped\n",
                         failure.rank, job.describe(failure.task).c_str(), failure.allowed_seconds);
        else
            std::fprintf(stderr,
                         "tetiso: rank %d stopped answering: it did not answer the end of the job within %.0f s "
                         "(--task-timeout); the job is stopped\n",
                         failure.rank, failure.allowed_seconds);
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 2);
        std::abort();
    }
    throw Error("task '" + job.describe(failure.task) + "' failed on rank " + std::to_string(failure.rank) + ": " +
                failure.what);
}

} // namespace

std::optional<JobResult> run_mpi(const Job& job, const Progress& progress) {
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (ranks == 1) return run_local(job, progress);
    // Each rank built its own partition (read the mesh's files, ran METIS):
    // pieces of different partitions would not fit, so all must agree.
    const std::uint64_t mine = job.partition().fingerprint();
    std::uint64_t lowest = 0, highest = 0;
    MPI_Allreduce(&mine, &lowest, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(&mine, &highest, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
    if (lowest != highest) {
        if (rank != 0) throw JobStopped();
        throw Error("the ranks built different partitions of the mesh (its files, or METIS's parts, differ "
                    "between them); no task was run");
    }
    std::optional<NodeLayout> nodes;
    if (job.config().device != JobConfig::Device::cpu) nodes = node_layout(rank, ranks, job.config());
    if (nodes && job.config().device == JobConfig::Device::gpu) {
        // A node with workers but no GPU its tasks may use, by its lowest rank.
        int without = -1;
        if (rank == 0)
            for (int r = ranks - 1; r >= 1; --r) {
                const auto node = static_cast<std::size_t>(nodes->node_of[static_cast<std::size_t>(r)]);
                if (nodes->gpus[node].empty()) without = r;
            }
        MPI_Bcast(&without, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (without >= 0) {
            if (rank != 0) throw JobStopped();
            const int gpu = job.config().gpu;
            throw Error("--device gpu: the node of rank " + std::to_string(without) + " has no CUDA device" +
                        (gpu >= 0 ? " " + std::to_string(gpu) : std::string()) + " this build can use");
        }
    }
    if (rank != 0) {
        work(job, nodes ? nodes->my_gpu : -1);
        return std::nullopt;
    }
    return control(job, ranks, progress, nodes);
}

} // namespace tetiso

#else

#include "tetiso/error.hpp"

namespace tetiso {
std::optional<JobResult> run_mpi(const Job&, const Progress&) { throw Error("this tetiso was built without MPI"); }
} // namespace tetiso

#endif
