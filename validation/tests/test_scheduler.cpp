// The job's scheduler (core/job/scheduler.hpp) on a simulated clock, driven
// through a fake transport whose workers take the seconds a test gives them:
// the order tasks go out in, rank 0 running the last seams alone, failures,
// lending idle cores, GPU drivers, deadlines of a rank that stops answering;
// and the surface of the single-process run, of the old one-task-at-a-time
// loop and of simulated multi-worker schedules, byte for byte the same.
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

using namespace tetiso;

namespace {

JobConfig lattice_job(int lattice, int domains) {
    JobConfig config;
    config.lattice = lattice;
    config.domains = domains;
    return config;
}

Piece piece_of(std::size_t triangles) {
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
    std::set<int> stopped, failing;
    bool execute = false;
    int silent_at_stop = -1; // a worker that does not answer the stop

    void send_task(int worker, TaskMessage message) override {
        sent.push_back({now_, worker, message.task, message.gpu});
        const double seconds = duration(message.task, worker);
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
            Piece piece = execute ? job_.execute(message.task, message.left ? &*message.left : nullptr,
                                                 message.right ? &*message.right : nullptr, record,
                                                 TaskThreads{1, {}, {}})
                                  : piece_of(10);
            event.result = result_message(record, seconds, 1, std::move(piece));
        }
        pending_.emplace(now_ + seconds, std::move(event));
    }
    // A batch takes the sum of its tasks' durations; it fails, naming the
    // first of its tasks in `failing`, where one is.
    void send_batch(int worker, BatchMessage message) override {
        const std::vector<int> tasks(message.tasks.begin(), message.tasks.end());
        batches.push_back({now_, worker, tasks, message.gpu, sent.size()});
        double seconds = 0;
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
DriveHooks hooks_here(FakeTransport& transport, const Job& job, double seconds, bool execute = false,
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

SchedulerSetup mpi_setup(int ranks, double task_timeout = 0) {
    SchedulerSetup setup;
    setup.ranks = ranks;
    setup.seams_here = true;
    setup.task_timeout = task_timeout;
    return setup;
}

std::vector<int> queue_order(const Job& job, int count) {
    TaskQueue queue(job);
    std::vector<int> order;
    for (int i = 0; i < count && queue.has_ready(); ++i) order.push_back(queue.pop());
    return order;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_surface(const Piece& a, const Piece& b) {
    return same_bytes(a.x, b.x) && same_bytes(a.y, b.y) && same_bytes(a.z, b.z) && same_bytes(a.key, b.key) &&
           same_bytes(a.flags, b.flags) && same_bytes(a.triangles, b.triangles) && same_bytes(a.domains, b.domains) &&
           same_bytes(a.error, b.error);
}

} // namespace

TEST(Scheduler, HandsOutTasksInQueueOrderToIdleWorkers) {
    const Job job(lattice_job(12, 8));
    Scheduler scheduler(job, mpi_setup(4));
    for (const int w : {3, 1, 2}) scheduler.on_ready(w, false, 0);
    const std::vector<SchedulerAction> actions = scheduler.decide(0);
    const std::vector<int> expected = queue_order(job, 3);
    ASSERT_EQ(actions.size(), 3u);
    for (std::size_t i = 0; i < actions.size(); ++i) {
        EXPECT_EQ(actions[i].kind, SchedulerAction::Kind::send_task);
        EXPECT_EQ(actions[i].task, expected[i]);
        EXPECT_EQ(actions[i].message.task, expected[i]);
        EXPECT_EQ(actions[i].message.gpu, -1);
        EXPECT_EQ(actions[i].worker, (std::vector<int>{3, 1, 2})[i]) << "workers are served in the order they became idle";
    }
    EXPECT_TRUE(scheduler.decide(0).empty()) << "no idle worker is left";
    EXPECT_EQ(scheduler.running().size(), 3u);
}

TEST(Scheduler, RankZeroRunsTheLastSeamsAloneAndTheRootAlways) {
    for (const int workers : {1, 2, 3, 5}) {
        SCOPED_TRACE(std::to_string(workers) + " workers");
        const Job job(lattice_job(12, 27));
        std::vector<int> ranks;
        for (int w = 1; w <= workers; ++w) ranks.push_back(w);
        FakeTransport transport(job, ranks, false);
        // Uneven times, so that the domain phase ends raggedly.
        transport.duration = [](int task, int worker) { return 0.5 + 0.37 * ((task * 7 + worker * 3) % 5); };
        Scheduler scheduler(job, mpi_setup(workers + 1));
        const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.25));
        ASSERT_TRUE(result.has_value());
        ASSERT_EQ(result->tasks.size(), static_cast<std::size_t>(job.task_count()));
        std::set<int> seen;
        bool root_here = false;
        for (const TaskRecord& r : result->tasks) {
            EXPECT_TRUE(seen.insert(r.task).second) << "task " << r.task << " twice";
            if (r.rank != 0) continue;
            root_here |= r.task == 0;
            EXPECT_EQ(r.kind, TaskKind::seam) << job.describe(r.task);
            for (const TaskRecord& other : result->tasks)
                if (&other != &r) {
                    EXPECT_TRUE(other.end <= r.start + 1e-9 || other.start >= r.end - 1e-9);
                }
        }
        EXPECT_TRUE(root_here);
        EXPECT_EQ(transport.stops, std::vector<bool>{false});
        // Before each seam it runs, rank 0 tells the workers how long it may be busy.
        EXPECT_EQ(transport.busy.size(),
                  static_cast<std::size_t>(std::count_if(result->tasks.begin(), result->tasks.end(),
                                                         [](const TaskRecord& r) { return r.rank == 0; })));
        for (const FakeTransport::Sent& s : transport.sent) EXPECT_NE(s.worker, 0);
    }
}

TEST(Scheduler, WithoutAControllerOfItsOwnEveryTaskGoesToTheWorker) {
    const Job job(lattice_job(12, 8));
    FakeTransport transport(job, {0}, false);
    SchedulerSetup setup; // the single process: rank 0 is the worker
    Scheduler scheduler(job, setup);
    const std::optional<JobResult> result = drive(job, scheduler, transport, DriveHooks{});
    ASSERT_TRUE(result.has_value());
    std::vector<int> order;
    for (const FakeTransport::Sent& s : transport.sent) order.push_back(s.task);
    // One at a time, in TaskQueue order.
    TaskQueue queue(job);
    std::vector<int> expected;
    while (!queue.finished()) {
        const int t = queue.pop();
        expected.push_back(t);
        queue.complete(t);
    }
    EXPECT_EQ(order, expected);
    EXPECT_TRUE(transport.busy.empty());
}

TEST(Scheduler, AWorkersFailureStopsTheHandingOutAndEndsOnceNothingRuns) {
    const Job job(lattice_job(12, 8));
    const int failing = queue_order(job, 2)[1]; // the second task out, on worker 2
    FakeTransport transport(job, {1, 2, 3}, false);
    transport.failing = {failing};
    transport.duration = [failing](int task, int) { return task == failing ? 0.5 : 2.0; };
    Scheduler scheduler(job, mpi_setup(4));
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_EQ(scheduler.failure()->task, failing);
    EXPECT_EQ(scheduler.failure()->rank, 2);
    EXPECT_EQ(scheduler.failure()->what, "injected");
    EXPECT_FALSE(scheduler.failure()->unresponsive);
    // The three first tasks went out at 0; nothing after the failure at 0.5,
    // and the job ended when the two others came back, stopping every worker.
    EXPECT_EQ(transport.sent.size(), 3u);
    EXPECT_EQ(transport.clock(), 2.0);
    EXPECT_EQ(transport.stops, std::vector<bool>{true});
}

TEST(Scheduler, ATaskThatFailsOnRankZeroEndsTheJob) {
    const Job job(lattice_job(12, 8));
    FakeTransport transport(job, {1, 2}, false);
    Scheduler scheduler(job, mpi_setup(3));
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1, false, 0)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_EQ(scheduler.failure()->task, 0);
    EXPECT_EQ(scheduler.failure()->rank, 0);
    EXPECT_EQ(scheduler.failure()->what, "injected here");
    EXPECT_EQ(transport.stops, std::vector<bool>{true});
}

TEST(Scheduler, IdleWorkersLendTheirCoresOnceNothingIsReady) {
    const Job job(lattice_job(12, 4)); // 4 domains, 3 seams
    Scheduler scheduler(job, mpi_setup(6));
    for (int w = 1; w <= 5; ++w) scheduler.on_ready(w, true, 0);
    const std::vector<SchedulerAction> first = scheduler.decide(0);
    // Four domains to four workers; worker 5 has nothing to run and lends to
    // one of their tasks (all sent at once: the first among equals).
    ASSERT_EQ(first.size(), 5u);
    EXPECT_EQ(first[4].kind, SchedulerAction::Kind::lend_cores);
    EXPECT_EQ(first[4].lender, 5);
    const int borrower = first[4].worker;
    EXPECT_EQ(borrower, first[0].worker);
    // Once that task ends, its lender lends again, and so does the worker
    // that ran it, each to a task that has no lend yet.
    TaskRecord record;
    record.task = first[0].task;
    scheduler.on_result(borrower, result_message(record, 1.0, 2, piece_of(5)), 1.0);
    const std::vector<SchedulerAction> second = scheduler.decide(1.0);
    std::set<int> lenders, borrowers;
    for (const SchedulerAction& a : second) {
        ASSERT_EQ(a.kind, SchedulerAction::Kind::lend_cores);
        lenders.insert(a.lender);
        EXPECT_TRUE(borrowers.insert(a.worker).second) << "two lends to rank " << a.worker;
        EXPECT_TRUE(scheduler.running().count(a.worker)) << "rank " << a.worker << " runs nothing";
    }
    EXPECT_EQ(lenders, (std::set<int>{5, borrower}));
    // Workers whose cores are unknown lend nothing.
    Scheduler blind(job, mpi_setup(6));
    for (int w = 1; w <= 5; ++w) blind.on_ready(w, false, 0);
    for (const SchedulerAction& a : blind.decide(0)) EXPECT_NE(a.kind, SchedulerAction::Kind::lend_cores);
}

TEST(Scheduler, GpuDriversRunTheirGpusTasksAndNeitherLendNorBorrow) {
    JobConfig config = lattice_job(12, 27);
    config.device = JobConfig::Device::automatic;
    const Job job(config);
    // One node: rank 0 and workers 1-3; rank 1 drives GPU 0.
    NodeLayout nodes;
    nodes.node_of = {0, 0, 0, 0};
    nodes.driving = {-1, 0, -1, -1};
    nodes.workers = {3};
    nodes.gpus = {{0}};
    nodes.gpu_mib = {80000};
    SchedulerSetup setup = mpi_setup(4);
    setup.nodes = nodes;
    FakeTransport transport(job, {1, 2, 3}, true);
    // The GPU is fast: once calibrated, it gets most domains.
    transport.duration = [](int, int worker) { return worker == 1 ? 0.1 : 1.0; };
    Scheduler scheduler(job, setup);
    ASSERT_TRUE(scheduler.places_tasks());
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.1));
    ASSERT_TRUE(result.has_value());
    int on_gpu = 0;
    for (const FakeTransport::Sent& s : transport.sent) {
        if (s.worker == 1) {
            EXPECT_EQ(s.gpu, 0) << "the driver runs its GPU's tasks only";
            EXPECT_EQ(job.kind(s.task), TaskKind::domain);
            ++on_gpu;
        } else {
            EXPECT_EQ(s.gpu, -1) << "task " << s.task << " for a GPU went to rank " << s.worker;
        }
    }
    // Ten times faster, the GPU ends most domains first even behind a queue:
    // their grants wait for the driver rather than go to an idle CPU worker.
    EXPECT_GT(on_gpu, 27 / 2) << "of 27 domains";
    // No rank ever holds two tasks.
    std::map<int, std::vector<std::pair<double, double>>> spans;
    for (const TaskRecord& r : result->tasks) spans[r.rank].push_back({r.start, r.end});
    for (auto& [rank, s] : spans) {
        std::sort(s.begin(), s.end());
        for (std::size_t i = 1; i < s.size(); ++i) EXPECT_LE(s[i - 1].second, s[i].first + 1e-9) << "rank " << rank;
    }
    for (const FakeTransport::Lent& l : transport.lent) {
        EXPECT_NE(l.lender, 1);
        EXPECT_NE(l.borrower, 1);
    }
    // Every task a worker ran was placed, with a prediction.
    for (const TaskRecord& r : result->tasks)
        if (r.rank != 0) {
            EXPECT_GT(r.predicted_seconds, 0) << job.describe(r.task);
        }
}

TEST(Scheduler, DeviceGpuSendsEveryDomainToADriverAndRefusesWhatNoGpuHolds) {
    JobConfig config = lattice_job(12, 8);
    NodeLayout nodes;
    nodes.node_of = {0, 0, 0};
    nodes.driving = {-1, 0, -1};
    nodes.workers = {2};
    nodes.gpus = {{0}};
    nodes.gpu_mib = {80000};
    // Job's constructor checks --device gpu against this machine's GPU: the
    // layout is what says the node has one here.
    Job job(config);
    const_cast<JobConfig&>(job.config()).device = JobConfig::Device::gpu;
    SchedulerSetup setup = mpi_setup(3);
    setup.nodes = nodes;
    {
        FakeTransport transport(job, {1, 2}, false);
        Scheduler scheduler(job, setup);
        ASSERT_TRUE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
        for (const FakeTransport::Sent& s : transport.sent)
            EXPECT_EQ(s.worker == 1, job.kind(s.task) == TaskKind::domain) << job.describe(s.task);
    }
    // A GPU too small for a domain: the first request fails the job on rank 0.
    setup.nodes->gpu_mib = {100};
    FakeTransport transport(job, {1, 2}, false);
    Scheduler scheduler(job, setup);
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_EQ(scheduler.failure()->rank, 0);
    EXPECT_NE(scheduler.failure()->what.find("MiB of GPU memory"), std::string::npos) << scheduler.failure()->what;
    EXPECT_TRUE(transport.sent.empty());
}

namespace {

// One node: rank 0 controls, ranks 1 and 2 drive GPUs 0 and 1, ranks 3 and 4
// work on the CPU.
SchedulerSetup two_gpus_setup() {
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

int domain_count_of(const Job& job) {
    int domains = 0;
    for (int t = 0; t < job.task_count(); ++t) domains += job.kind(t) == TaskKind::domain;
    return domains;
}

} // namespace

TEST(Scheduler, UnderDeviceGpuEveryGpuGetsBatchesThatShrinkAtTheEnd) {
    JobConfig config = lattice_job(24, 64);
    config.gpu_batch = 8;
    Job job(config);
    const_cast<JobConfig&>(job.config()).device = JobConfig::Device::gpu;
    const int domains = domain_count_of(job);
    FakeTransport transport(job, {1, 2, 3, 4}, true);
    transport.duration = [](int, int worker) { return worker <= 2 ? 0.05 : 1.0; };
    Scheduler scheduler(job, two_gpus_setup());
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.1));
    ASSERT_TRUE(result.has_value());
    EXPECT_EQ(result->tasks.size(), static_cast<std::size_t>(job.task_count()));
    // Every domain task went to a GPU's driver once, with that GPU.
    std::map<int, int> domains_on; // driver -> domain tasks
    std::set<int> seen;
    for (const FakeTransport::Sent& s : transport.sent) {
        if (job.kind(s.task) != TaskKind::domain) continue;
        ASSERT_TRUE(s.worker == 1 || s.worker == 2) << job.describe(s.task) << " went to rank " << s.worker;
        EXPECT_EQ(s.gpu, s.worker - 1);
        EXPECT_TRUE(seen.insert(s.task).second) << job.describe(s.task) << " was sent twice";
        ++domains_on[s.worker];
    }
    EXPECT_EQ(static_cast<int>(seen.size()), domains);
    EXPECT_GT(domains_on[1], 0);
    EXPECT_GT(domains_on[2], 0);
    // Batches: at most --gpu-batch, at most half of each GPU's share of the
    // domains not sent yet (two GPUs share them), full while many wait,
    // smaller at the end.
    ASSERT_FALSE(transport.batches.empty());
    for (const FakeTransport::Batch& b : transport.batches) {
        int waiting = domains;
        for (std::size_t i = 0; i < b.sent_before; ++i) waiting -= job.kind(transport.sent[i].task) == TaskKind::domain;
        EXPECT_LE(b.tasks.size(), 8u);
        EXPECT_LE(static_cast<int>(b.tasks.size()), (waiting + 3) / 4) << waiting << " domains waited";
        for (const int t : b.tasks) EXPECT_EQ(job.kind(t), TaskKind::domain);
    }
    EXPECT_EQ(transport.batches.front().tasks.size(), 8u);
    // The last domain sent: alone, or in a batch smaller than the first.
    std::size_t last_domain = 0;
    for (std::size_t i = 0; i < transport.sent.size(); ++i)
        if (job.kind(transport.sent[i].task) == TaskKind::domain) last_domain = i;
    int last_grant = 1;
    for (const FakeTransport::Batch& b : transport.batches)
        if (b.sent_before <= last_domain && last_domain < b.sent_before + b.tasks.size())
            last_grant = static_cast<int>(b.tasks.size());
    EXPECT_LT(last_grant, 8);
    // The records stay per task, end to end within each batch: no rank
    // holds two tasks at once.
    std::map<int, std::vector<std::pair<double, double>>> spans;
    for (const TaskRecord& r : result->tasks) spans[r.rank].push_back({r.start, r.end});
    for (auto& [rank, span] : spans) {
        std::sort(span.begin(), span.end());
        for (std::size_t i = 1; i < span.size(); ++i) EXPECT_LE(span[i - 1].second, span[i].first + 1e-9) << "rank " << rank;
    }
}

TEST(Scheduler, UnderAutoTheCpuKeepsDomainsAndTheGpusTakeBatches) {
    JobConfig config = lattice_job(24, 64);
    config.device = JobConfig::Device::automatic;
    const Job job(config);
    FakeTransport transport(job, {1, 2, 3, 4}, true);
    // Per task, the GPUs are ten times faster than a CPU worker; a batch
    // takes the sum of its tasks.
    transport.duration = [](int, int worker) { return worker <= 2 ? 0.1 : 1.0; };
    Scheduler scheduler(job, two_gpus_setup());
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.1));
    ASSERT_TRUE(result.has_value());
    int on_cpu = 0;
    for (const FakeTransport::Sent& s : transport.sent)
        if (job.kind(s.task) == TaskKind::domain && s.worker > 2) ++on_cpu;
    EXPECT_GT(on_cpu, 0) << "the CPU finishes some domains first";
    std::set<int> batched_on;
    std::size_t largest = 0;
    for (const FakeTransport::Batch& b : transport.batches) {
        batched_on.insert(b.worker);
        largest = std::max(largest, b.tasks.size());
    }
    EXPECT_EQ(batched_on, (std::set<int>{1, 2}));
    EXPECT_GT(largest, 1u);
    // Each GPU record carries its share of its batch's prediction.
    for (const TaskRecord& r : result->tasks)
        if (r.rank == 1 || r.rank == 2) {
            EXPECT_GT(r.predicted_seconds, 0) << job.describe(r.task);
        }
}

TEST(Scheduler, AFailureInsideABatchNamesItsTask) {
    JobConfig config = lattice_job(24, 64);
    config.gpu_batch = 8;
    Job job(config);
    const_cast<JobConfig&>(job.config()).device = JobConfig::Device::gpu;
    // The third domain in queue order: inside the first batch, not its first.
    std::vector<int> order = queue_order(job, job.task_count());
    order.erase(std::remove_if(order.begin(), order.end(), [&](int t) { return job.kind(t) != TaskKind::domain; }),
                order.end());
    const int failing = order[2];
    FakeTransport transport(job, {1, 2, 3, 4}, true);
    transport.failing = {failing};
    Scheduler scheduler(job, two_gpus_setup());
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_EQ(scheduler.failure()->task, failing);
    EXPECT_EQ(scheduler.failure()->what, "injected");
    ASSERT_FALSE(transport.batches.empty());
    const FakeTransport::Batch& first = transport.batches.front();
    EXPECT_GT(first.tasks.size(), 2u);
    EXPECT_EQ(first.tasks[2], failing);
    EXPECT_EQ(scheduler.failure()->rank, first.worker);
    EXPECT_EQ(transport.stops, std::vector<bool>{true});
}

// Job::execute_batch: each piece and record what the task alone gives, and
// a failing task named, the first that fails in the batch's order.
TEST(Scheduler, ABatchIsEachTaskAloneAndItsFailureNamesTheTask) {
    const Job job(lattice_job(20, 8));
    std::vector<int> tasks;
    for (int t = job.task_count() - 1; t >= 0; --t)
        if (job.kind(t) == TaskKind::domain) tasks.push_back(t); // not in queue order
    std::vector<TaskRecord> records;
    const std::vector<Piece> pieces = job.execute_batch(tasks, records, TaskThreads{1, {}, {}});
    ASSERT_EQ(pieces.size(), tasks.size());
    ASSERT_EQ(records.size(), tasks.size());
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        TaskRecord alone;
        const Piece piece = job.execute(tasks[i], nullptr, nullptr, alone, TaskThreads{1, {}, {}});
        EXPECT_TRUE(same_surface(pieces[i], piece)) << job.describe(tasks[i]);
        EXPECT_EQ(records[i].task, tasks[i]);
        EXPECT_EQ(records[i].triangles_in, alone.triangles_in);
        EXPECT_EQ(records[i].triangles_out, alone.triangles_out);
        EXPECT_EQ(records[i].samples_out, alone.samples_out);
    }
    EXPECT_THROW(job.execute_batch({0}, records, TaskThreads{1, {}, {}}), Error) << "a seam is no domain task";

    // A field that is not finite where x < 2: the domains there fail.
    JobConfig config = lattice_job(20, 8);
    config.field = "sqrt(x - 2)";
    config.level = 0.5;
    const Job partly(config);
    std::vector<int> fine, failing;
    std::map<int, std::string> why;
    for (const int t : tasks) {
        TaskRecord alone;
        try {
            partly.execute(t, nullptr, nullptr, alone, TaskThreads{1, {}, {}});
            fine.push_back(t);
        } catch (const Error& e) {
            failing.push_back(t);
            why[t] = e.what();
        }
    }
    ASSERT_FALSE(fine.empty());
    ASSERT_GE(failing.size(), 2u);
    const std::vector<int> batch{fine[0], failing[1], failing[0]};
    try {
        partly.execute_batch(batch, records, TaskThreads{1, {}, {}});
        ADD_FAILURE() << "the batch did not fail";
    } catch (const BatchTaskError& e) {
        EXPECT_EQ(e.task, failing[1]);
        EXPECT_EQ(std::string(e.what()), why[failing[1]]);
    }
}

TEST(Scheduler, AStoppedWorkerIsNamedAtItsTasksDeadline) {
    const Job job(lattice_job(12, 27));
    const double floor = 5;
    FakeTransport transport(job, {1, 2, 3}, false);
    Scheduler scheduler(job, mpi_setup(4, floor));
    // Before any task ended nothing says how long one takes: no deadline yet.
    EXPECT_TRUE(std::isinf(scheduler.allowance(queue_order(job, 1)[0])));
    // Domains take 0.2 s; worker 2 stops in its second task, a domain.
    int stopped_task = -1;
    transport.duration = [&](int task, int worker) {
        if (worker == 2 && transport.clock() > 0) {
            transport.stopped.insert(2);
            stopped_task = task;
        }
        return 0.2;
    };
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.1));
    EXPECT_FALSE(result.has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    const SchedulerFailure& f = *scheduler.failure();
    EXPECT_TRUE(f.unresponsive);
    EXPECT_EQ(f.rank, 2);
    EXPECT_EQ(f.task, stopped_task);
    // Ten times 0.2 s is less than the floor: the deadline is the floor,
    // from when the task was sent (at 0.2 s), and the job noticed it then.
    EXPECT_DOUBLE_EQ(f.allowed_seconds, floor);
    EXPECT_DOUBLE_EQ(transport.clock(), 0.2 + floor);
    EXPECT_TRUE(transport.stops.empty()) << "a stopped rank cannot be stopped in order";
}

TEST(Scheduler, AWorkerStoppedInItsFirstTaskGetsADeadlineOnceAnotherTaskEnds) {
    const Job job(lattice_job(12, 27));
    FakeTransport transport(job, {1, 2, 3}, false);
    transport.stopped = {2};
    transport.duration = [](int, int worker) { return worker == 1 ? 1.0 : 1.5; };
    Scheduler scheduler(job, mpi_setup(4, 2));
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_TRUE(scheduler.failure()->unresponsive);
    EXPECT_EQ(scheduler.failure()->rank, 2);
    EXPECT_EQ(scheduler.failure()->task, transport.sent[1].task);
    // Sent at 0, it had no deadline until a domain ended (at 1 s); then ten
    // times the domains' predicted time, a mean of 1 s and 1.5 s ones, and
    // the job noticed it right then.
    const double allowed = scheduler.failure()->allowed_seconds;
    EXPECT_GT(allowed, Scheduler::kDeadlineFactor * 1.0);
    EXPECT_LT(allowed, Scheduler::kDeadlineFactor * 1.5);
    EXPECT_DOUBLE_EQ(transport.clock(), allowed);
}

TEST(Scheduler, AWorkerSilentAtTheEndFailsTheJobAsUnresponsive) {
    const Job job(lattice_job(12, 8));
    FakeTransport transport(job, {1, 2}, false);
    transport.silent_at_stop = 2;
    Scheduler scheduler(job, mpi_setup(3, 5));
    EXPECT_FALSE(drive(job, scheduler, transport, hooks_here(transport, job, 0.1)).has_value());
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_TRUE(scheduler.failure()->unresponsive);
    EXPECT_EQ(scheduler.failure()->rank, 2);
    EXPECT_EQ(scheduler.failure()->task, -1) << "it held no task";
    EXPECT_EQ(transport.stops, std::vector<bool>{false}) << "every task had ended";
}

TEST(Scheduler, DeadlinesScaleWithThePredictedTimeAndCanBeOff) {
    const Job job(lattice_job(12, 8));
    const int domain = queue_order(job, 1)[0];
    Scheduler scheduler(job, mpi_setup(2, 2.0));
    scheduler.on_ready(1, false, 0);
    double now = 0;
    // Domains of 3 s each: ten times that beats the floor.
    for (int i = 0; i < 3; ++i) {
        const std::vector<SchedulerAction> a = scheduler.decide(now);
        ASSERT_EQ(a.size(), 1u);
        now += 3;
        TaskRecord record;
        record.task = a[0].task;
        scheduler.on_result(1, result_message(record, 3, 1, piece_of(4)), now);
    }
    EXPECT_DOUBLE_EQ(scheduler.allowance(domain), Scheduler::kDeadlineFactor * 3);
    const std::vector<SchedulerAction> next = scheduler.decide(now);
    ASSERT_EQ(next.size(), 1u);
    EXPECT_DOUBLE_EQ(scheduler.next_deadline(), now + Scheduler::kDeadlineFactor * 3);
    scheduler.on_time(now + Scheduler::kDeadlineFactor * 3 - 0.01);
    EXPECT_FALSE(scheduler.failure().has_value());
    scheduler.on_time(now + Scheduler::kDeadlineFactor * 3);
    ASSERT_TRUE(scheduler.failure().has_value());
    EXPECT_TRUE(scheduler.failure()->unresponsive);
    EXPECT_EQ(scheduler.failure()->task, next[0].task);

    Scheduler patient(job, mpi_setup(2, 0));
    patient.on_ready(1, false, 0);
    ASSERT_EQ(patient.decide(0).size(), 1u);
    EXPECT_TRUE(std::isinf(patient.next_deadline()));
    patient.on_time(1e12);
    EXPECT_FALSE(patient.failure().has_value());
}

TEST(Scheduler, TheSurfaceIsTheSameForEverySchedule) {
    JobConfig config = lattice_job(24, 12);
    config.field = "gyroid";
    const Job job(config);
    // The loop the single-process run used to be: one task after another in
    // TaskQueue order.
    TaskQueue queue(job);
    std::vector<std::optional<Piece>> pieces(static_cast<std::size_t>(job.task_count()));
    while (!queue.finished()) {
        const int t = queue.pop();
        const TaskNode& n = job.node(t);
        TaskRecord record;
        pieces[static_cast<std::size_t>(t)] =
            job.execute(t, n.left >= 0 ? &*pieces[static_cast<std::size_t>(n.left)] : nullptr,
                        n.right >= 0 ? &*pieces[static_cast<std::size_t>(n.right)] : nullptr, record, TaskThreads{1, {}, {}});
        queue.complete(t);
    }
    const Piece& reference = *pieces[0];
    ASSERT_GT(reference.triangle_count(), 0u);

    const JobResult local = run_local(job, {});
    EXPECT_TRUE(same_surface(local.surface, reference)) << "the in-process run";
    EXPECT_EQ(local.tasks.size(), static_cast<std::size_t>(job.task_count()));
    for (const TaskRecord& r : local.tasks) EXPECT_EQ(r.rank, 0);

    for (const int workers : {2, 3, 6}) {
        SCOPED_TRACE(std::to_string(workers) + " simulated workers");
        std::vector<int> ranks;
        for (int w = 1; w <= workers; ++w) ranks.push_back(w);
        FakeTransport transport(job, ranks, true);
        transport.execute = true;
        transport.duration = [workers](int task, int worker) { return 0.3 + ((task * 13 + worker * workers) % 7) * 0.2; };
        Scheduler scheduler(job, mpi_setup(workers + 1));
        const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.2, true));
        ASSERT_TRUE(result.has_value());
        EXPECT_TRUE(same_surface(result->surface, reference));
    }
    // Two GPUs' drivers given every domain in batches (run here on the host
    // by Job::execute_batch), two workers for the seams.
    SCOPED_TRACE("two GPUs, batches");
    FakeTransport transport(job, {1, 2, 3, 4}, true);
    transport.execute = true;
    transport.duration = [](int task, int worker) { return 0.1 + ((task * 7 + worker) % 5) * 0.1; };
    Scheduler scheduler(job, two_gpus_setup());
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.2, true));
    ASSERT_TRUE(result.has_value());
    EXPECT_TRUE(same_surface(result->surface, reference));
    std::size_t batched = 0;
    for (const FakeTransport::Batch& b : transport.batches) batched += b.tasks.size();
    EXPECT_GT(batched, 1u);
}

TEST(Messages, EachDecodesWhatItsEncoderWrote) {
    TaskMessage task{7, 1, piece_of(3), piece_of(4)};
    task.left->x = {1.5f, 2.5f};
    task.right->key = {EdgeKey{42}};
    const TaskMessage t = decode_task(encode(task));
    EXPECT_EQ(t.task, 7);
    EXPECT_EQ(t.gpu, 1);
    ASSERT_TRUE(t.left && t.right);
    EXPECT_EQ(t.left->x, task.left->x);
    EXPECT_EQ(t.right->key, task.right->key);
    EXPECT_EQ(t.right->triangle_count(), 4u);
    const TaskMessage domain = decode_task(encode(TaskMessage{3, -1, {}, {}}));
    EXPECT_FALSE(domain.left || domain.right);

    TaskRecord record;
    record.task = 5;
    record.triangles_in = 100;
    record.triangles_out = 40;
    record.samples_out = 9;
    record.stages.reduce = 0.25;
    record.stages.gpu = 2;
    record.field_low = -1;
    record.field_high = 3;
    const ResultMessage r = decode_result(encode(result_message(record, 1.5, 4, piece_of(6))));
    EXPECT_EQ(r.record.task, 5);
    EXPECT_EQ(r.seconds, 1.5);
    EXPECT_EQ(r.record.threads, 4);
    EXPECT_EQ(r.record.triangles_in, 100u);
    EXPECT_EQ(r.record.triangles_out, 40u);
    EXPECT_EQ(r.record.samples_out, 9u);
    EXPECT_EQ(r.record.stages.reduce, 0.25);
    EXPECT_EQ(r.record.stages.gpu, 2);
    EXPECT_EQ(r.record.field_low, -1);
    EXPECT_EQ(r.record.field_high, 3);
    EXPECT_EQ(r.piece.triangle_count(), 6u);

    EXPECT_EQ(decode_failure(encode(FailureMessage{4, "out of memory"})).what, "out of memory");
    EXPECT_TRUE(decode_stop(encode(StopMessage{true})).failed);
    EXPECT_FALSE(decode_stop(encode(StopMessage{false})).failed);
    EXPECT_EQ(decode_heartbeat(encode(HeartbeatMessage{12.5})).seconds, 12.5);
    const MessageBytes cores{std::byte{1}, std::byte{2}};
    EXPECT_EQ(decode_ready(encode(ReadyMessage{cores})).cores, cores);
    EXPECT_EQ(decode_lend(encode(LendMessage{cores})).cores, cores);

    const BatchMessage batch = decode_batch(encode(BatchMessage{1, {4, 9, 11}}));
    EXPECT_EQ(batch.gpu, 1);
    EXPECT_EQ(batch.tasks, (std::vector<std::int32_t>{4, 9, 11}));
    TaskRecord second = record;
    second.task = 6;
    second.stages.reduce = 0.75;
    const BatchResultMessage results =
        decode_batch_result(encode(batch_result_message({record, second}, 2.0, 3, {piece_of(2), piece_of(5)})));
    ASSERT_EQ(results.results.size(), 2u);
    EXPECT_EQ(results.results[0].record.task, 5);
    EXPECT_EQ(results.results[1].record.task, 6);
    EXPECT_EQ(results.results[1].piece.triangle_count(), 5u);
    EXPECT_EQ(results.results[0].record.threads, 3);
    // The batch's seconds shared out by the tasks' stage seconds.
    EXPECT_DOUBLE_EQ(results.results[0].seconds, 0.5);
    EXPECT_DOUBLE_EQ(results.results[1].seconds, 1.5);

    // Bytes that end early are an error, not a read past them.
    MessageBytes cut = encode(result_message(record, 1.5, 4, piece_of(6)));
    cut.resize(cut.size() - 1);
    EXPECT_THROW(decode_result(cut), Error);
    EXPECT_THROW(decode_task(MessageBytes(3)), Error);
    MessageBytes cut_batch = encode(batch_result_message({record, second}, 2.0, 3, {piece_of(2), piece_of(5)}));
    cut_batch.resize(cut_batch.size() - 1);
    EXPECT_THROW(decode_batch_result(cut_batch), Error);
    EXPECT_THROW(decode_batch(MessageBytes(6)), Error);
}
