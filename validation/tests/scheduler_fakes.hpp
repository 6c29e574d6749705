// What the scheduler's tests share (test_scheduler.cpp, test_scheduler_gpus.cpp):
// a fake transport whose workers take the seconds a test gives them on a
// simulated clock, rank 0's hook on that clock, and small jobs and layouts.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <vector>

#include "local_transport.hpp"
#include "scheduler.hpp"
#include "tetiso/error.hpp"
#include "transport.hpp"

namespace tetiso::scheduler_test {

inline JobConfig lattice_job(int lattice, int domains) {
    JobConfig config;
    config.lattice = lattice;
    config.domains = domains;
    return config;
}

inline Piece piece_of(std::size_t triangles) {
    Piece piece;
    piece.triangles.assign(3 * triangles, 0);
    return piece;
}

// Workers on a simulated clock. A task sent to a worker reports after
// duration(task, worker) seconds, with a piece of a few triangles (or, with
// `execute`, the piece the Job makes); a worker in `stopped` never reports;
// a task in `failing` fails.
class FakeTransport : public Transport {
public:
    struct Sent {
        double at;
        int worker, task, gpu;
    };
    struct Lent {
        double at;
        int borrower, lender;
    };

    FakeTransport(const Job& job, std::vector<int> workers, bool cores_known)
        : job_(job) {
        for (const int w : workers) {
            WorkerEvent ready;
            ready.kind = WorkerEvent::Kind::ready;
            ready.worker = w;
            ready.cores_known = cores_known;
            pending_.emplace(0.0, std::move(ready));
        }
    }

    std::function<double(int task, int worker)> duration = [](int, int) { return 1.0; };
    double batch_seconds = 0; // a GPU grant's own cost (one task or a batch), beside its tasks' durations
    std::set<int> stopped, failing;
    bool execute = false;
    std::size_t raw_triangles = 0; // what a domain task's record says it extracted, without `execute`
    int silent_at_stop = -1; // a worker that does not answer the stop

    void send_task(int worker, TaskMessage message) override {
        sent.push_back({now_, worker, message.task, message.gpu});
        const double seconds = duration(message.task, worker) + (message.gpu >= 0 ? batch_seconds : 0);
        if (stopped.count(worker)) return;
        WorkerEvent event;
        event.worker = worker;
        if (failing.count(message.task)) {
            event.kind = WorkerEvent::Kind::failure;
            event.failure = FailureMessage{message.task, "injected"};
        } else {
            event.kind = WorkerEvent::Kind::result;
            TaskRecord record;
            record.task = message.task;
            record.triangles_in = raw_triangles;
            Piece piece = execute ? job_.execute(message.task, message.left ? &*message.left : nullptr,
                                                 message.right ? &*message.right : nullptr, record,
                                                 TaskThreads{1, {}, {}})
                                  : piece_of(10);
            event.result = result_message(record, seconds, 1, std::move(piece));
        }
        pending_.emplace(now_ + seconds, std::move(event));
    }
    // A batch takes batch_seconds and the sum of its tasks' durations; it
    // fails, naming the first of its tasks in `failing`, where one is.
    void send_batch(int worker, BatchMessage message) override {
        const std::vector<int> tasks(message.tasks.begin(), message.tasks.end());
        batches.push_back({now_, worker, tasks, message.gpu, sent.size()});
        double seconds = batch_seconds;
        for (const int t : tasks) {
            sent.push_back({now_, worker, t, message.gpu});
            seconds += duration(t, worker);
        }
        if (stopped.count(worker)) return;
        WorkerEvent event;
        event.worker = worker;
        const auto failed = std::find_if(tasks.begin(), tasks.end(), [&](int t) { return failing.count(t) > 0; });
        if (failed != tasks.end()) {
            event.kind = WorkerEvent::Kind::failure;
            event.failure = FailureMessage{*failed, "injected"};
        } else {
            event.kind = WorkerEvent::Kind::batch_result;
            std::vector<TaskRecord> records(tasks.size());
            std::vector<Piece> pieces;
            if (execute) {
                pieces = job_.execute_batch(tasks, records, TaskThreads{1, {}, {}});
            } else {
                for (std::size_t i = 0; i < tasks.size(); ++i) {
                    records[i].task = tasks[i];
                    records[i].triangles_in = raw_triangles;
                    pieces.push_back(piece_of(10));
                }
            }
            event.batch = batch_result_message(records, seconds, 1, std::move(pieces));
        }
        pending_.emplace(now_ + seconds, std::move(event));
    }
    void lend_cores(int borrower, int lender) override { lent.push_back({now_, borrower, lender}); }
    std::optional<WorkerEvent> receive(double deadline) override {
        if (pending_.empty() || pending_.begin()->first > deadline) {
            if (!std::isfinite(deadline)) throw Error("the fake transport would wait for ever");
            now_ = std::max(now_, deadline);
            return std::nullopt;
        }
        auto first = pending_.begin();
        now_ = std::max(now_, first->first);
        WorkerEvent event = std::move(first->second);
        pending_.erase(first);
        return event;
    }
    void busy_for(double seconds) override { busy.push_back(seconds); }
    double clock() const override { return now_; }
    int stop(bool failed) override {
        stops.push_back(failed);
        return silent_at_stop;
    }
    void advance(double seconds) { now_ += seconds; }

    struct Batch {
        double at;
        int worker;
        std::vector<int> tasks;
        int gpu;
        std::size_t sent_before; // tasks sent before it, batches' or not
    };
    std::vector<Sent> sent; // every task, those of batches too
    std::vector<Batch> batches;
    std::vector<Lent> lent;
    std::vector<double> busy;
    std::vector<bool> stops;

private:
    const Job& job_;
    double now_ = 0;
    std::multimap<double, WorkerEvent> pending_;
};

// Rank 0's run_here hook on the fake clock: `seconds` per task.
inline DriveHooks hooks_here(FakeTransport& transport, const Job& job, double seconds, bool execute = false,
                      int failing = -1) {
    DriveHooks hooks;
    hooks.run_here = [&transport, &job, seconds, execute, failing](int task, const Piece* left, const Piece* right) {
        transport.advance(seconds);
        if (task == failing) throw Error("injected here");
        TaskRecord record;
        record.task = task;
        Piece piece = execute ? job.execute(task, left, right, record, TaskThreads{1, {}, {}}) : piece_of(10);
        return result_message(record, seconds, 1, std::move(piece));
    };
    return hooks;
}

inline SchedulerSetup mpi_setup(int ranks, double task_timeout = 0) {
    SchedulerSetup setup;
    setup.ranks = ranks;
    setup.seams_here = true;
    setup.task_timeout = task_timeout;
    return setup;
}

inline std::vector<int> queue_order(const Job& job, int count) {
    TaskQueue queue(job);
    std::vector<int> order;
    for (int i = 0; i < count && queue.has_ready(); ++i) order.push_back(queue.pop());
    return order;
}

template <class T>
inline bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

inline bool same_surface(const Piece& a, const Piece& b) {
    return same_bytes(a.x, b.x) && same_bytes(a.y, b.y) && same_bytes(a.z, b.z) && same_bytes(a.key, b.key) &&
           same_bytes(a.flags, b.flags) && same_bytes(a.triangles, b.triangles) && same_bytes(a.domains, b.domains) &&
           same_bytes(a.error, b.error);
}

// One node: rank 0 controls, ranks 1 and 2 drive GPUs 0 and 1, ranks 3 and 4
// work on the CPU.
inline SchedulerSetup two_gpus_setup() {
    NodeLayout nodes;
    nodes.node_of = {0, 0, 0, 0, 0};
    nodes.driving = {-1, 0, 1, -1, -1};
    nodes.workers = {4};
    nodes.gpus = {{0, 1}};
    nodes.gpu_mib = {80000};
    SchedulerSetup setup = mpi_setup(5);
    setup.nodes = nodes;
    return setup;
}

inline int domain_count_of(const Job& job) {
    int domains = 0;
    for (int t = 0; t < job.task_count(); ++t) domains += job.kind(t) == TaskKind::domain;
    return domains;
}

} // namespace tetiso::scheduler_test
