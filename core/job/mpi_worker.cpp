// A worker rank of the MPI job (mpi_worker.hpp).
#include "mpi_worker.hpp"

#ifdef TETISO_HAVE_MPI

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <new>

#include "affinity.hpp"
#include "mpi_transport.hpp"

namespace tetiso {
namespace {

// Cores that workers with nothing left to do lend to the task this worker
// runs (the scheduler lends them at the end of the domain phase). Each lend
// brings one worker's share of threads; the reduction takes them between
// rounds (ReduceOptions::more_threads), on the main thread, the only one that
// calls MPI.
class LentCores {
public:
    explicit LentCores(int threads_per_worker)
        : per_worker_(std::max(1, threads_per_worker)), known_(current_cores(own_)), cores_(own_) {}

    // Takes the lends that have arrived; returns the threads to use now, or
    // 0 when nothing changed.
    int take() {
        int taken = 0;
        for (;;) {
            int arrived = 0;
            MPI_Status status;
            MPI_Iprobe(0, kLend, MPI_COMM_WORLD, &arrived, &status);
            if (!arrived) break;
            cpu_set_t lent;
            if (cores_from_bytes(decode_lend(receive_probed(status)).cores, lent)) CPU_OR(&cores_, &cores_, &lent);
            ++taken;
        }
        if (taken == 0 || !known_) return 0;
        lends_ += taken;
        const int threads = std::min(per_worker_ * (1 + lends_), kMaxThreads);
        most_ = std::max(most_, threads);
        run_on(cores_, threads);
        return threads;
    }

    int most() const { return most_; }

    // After the task: back to this worker's own cores and threads (the
    // OpenMP threads too: run_on moved them onto the lent cores).
    void give_back() {
        if (known_ && lends_ > 0) run_on(own_, per_worker_);
        cores_ = own_;
        lends_ = 0;
        most_ = per_worker_;
    }

private:
    int per_worker_;
    cpu_set_t own_;
    bool known_;
    cpu_set_t cores_;
    int lends_ = 0;
    int most_ = per_worker_;
};

// How long rank 0 may stay silent: the patience its last heartbeat asked
// for, from the moment this worker started waiting or last heard from it.
// Workers after the first wait a little longer, so that one of them, not
// all at once, says that rank 0 stopped.
class RankZeroWatch {
public:
    RankZeroWatch(double task_timeout, int rank)
        : patience_(task_timeout), stagger_(0.25 * (rank - 1)), since_(Clock::now()) {}
    void heard(const MessageBytes& message, int tag) {
        since_ = Clock::now();
        if (tag == kHeartbeat) patience_ = decode_heartbeat(message).seconds;
    }
    void waiting() { since_ = std::max(since_, Clock::now()); }
    Clock::time_point deadline() const {
        const double seconds = patience_ + stagger_;
        if (patience_ <= 0 || !std::isfinite(seconds) || seconds > 1e9) return Clock::time_point::max();
        return since_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    }
    // Says so in one line and ends the job: rank 0 cannot, and MPI_Finalize
    // would wait for it.
    [[noreturn]] void silent() const {
        std::fprintf(stderr,
                     "tetiso: rank 0 sent nothing for %.0f s, past its deadline (it was stopped or hangs; "
                     "--task-timeout sets the deadlines); the job is stopped\n",
                     std::chrono::duration<double>(Clock::now() - since_).count());
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 2);
        std::abort();
    }

private:
    double patience_;
    double stagger_;
    Clock::time_point since_;
};

// A GPU grant's batch: its results in one message, or the task that failed.
template <class Deliver>
void run_batch(const Job& job, const BatchMessage& batch, Deliver& deliver) {
    const auto started = Clock::now();
    try {
        std::vector<TaskRecord> records;
        std::vector<Piece> pieces = job.execute_batch(std::vector<int>(batch.tasks.begin(), batch.tasks.end()), records,
                                                      TaskThreads{job.config().threads, {}, batch.gpu});
        const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
        deliver(encode(batch_result_message(records, seconds, job.config().threads, std::move(pieces))), kBatchResult);
    } catch (const BatchTaskError& e) {
        deliver(encode(FailureMessage{e.task, e.what()}), kFailure);
    } catch (const std::exception& e) {
        const std::string what = dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what();
        deliver(encode(FailureMessage{batch.tasks.empty() ? -1 : batch.tasks.front(), what}), kFailure);
    }
}

} // namespace

void work(const Job& job, int driven_gpu) {
    if (driven_gpu >= 0) {
        try {
            job.prepare_gpu(driven_gpu);
        } catch (const std::exception&) {
            // Its tasks there fail with the same error, which rank 0 reports.
        }
    }
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    RankZeroWatch rank_zero(job.config().task_timeout, rank);
    Sends sends;
    // Waits until rank 0 has what was sent to it.
    const auto deliver = [&](MessageBytes bytes, int tag) {
        sends.send(std::move(bytes), 0, tag);
        rank_zero.waiting();
        if (!sends.wait(rank_zero.deadline())) rank_zero.silent();
    };
    // The first "ready" names this worker's cores, which rank 0 lends to
    // other ranks when this worker has nothing to do.
    deliver(encode(ReadyMessage{cores_bytes()}), kReady);
    LentCores lent(job.config().threads);
    for (;;) {
        rank_zero.waiting();
        MPI_Status status;
        if (!wait_for_message(0, status, rank_zero.deadline(), [] { return false; })) rank_zero.silent();
        MessageBytes message = receive_probed(status);
        rank_zero.heard(message, status.MPI_TAG);
        if (status.MPI_TAG == kLend || status.MPI_TAG == kHeartbeat) continue; // a lend for a task that ended before it came
        if (status.MPI_TAG == kStop) {
            deliver(MessageBytes(), kStopped);
            if (decode_stop(message).failed) throw JobStopped();
            return;
        }
        if (status.MPI_TAG == kBatch) {
            run_batch(job, decode_batch(message), deliver);
            continue;
        }
        TaskMessage task = decode_task(message);
        // The pieces are decoded: the message's copy of them would only add
        // to the task's peak memory.
        MessageBytes().swap(message);
        TaskRecord record;
        const auto started = Clock::now();
        try {
            Piece piece = job.execute(task.task, task.left ? &*task.left : nullptr, task.right ? &*task.right : nullptr,
                                      record, TaskThreads{job.config().threads, [&lent] { return lent.take(); }, task.gpu});
            const int threads = lent.most();
            lent.give_back();
            task.left.reset();
            task.right.reset();
            const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
            MessageBytes bytes = encode(result_message(record, seconds, threads, std::move(piece)));
            deliver(std::move(bytes), kResult);
        } catch (const std::exception& e) {
            lent.give_back();
            // Report, then wait to be told to stop: rank 0 decides the end.
            const std::string what = dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what();
            deliver(encode(FailureMessage{task.task, what}), kFailure);
        }
    }
}

} // namespace tetiso

#endif
