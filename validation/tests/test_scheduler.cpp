// The job's scheduler (core/job/scheduler.hpp) on a simulated clock, driven
// through a fake transport whose workers take the seconds a test gives them
// (scheduler_fakes.hpp): the order tasks go out in, rank 0 running the last
// seams alone, failures, lending idle cores, deadlines of a rank that stops
// answering; the surface of the single-process run, of the old
// one-task-at-a-time loop and of simulated multi-worker and two-GPU
// schedules, byte for byte the same; and the messages' codec. GPU drivers
// and batches: test_scheduler_gpus.cpp.
#include <gtest/gtest.h>

#include "scheduler_fakes.hpp"

using namespace tetiso;
using namespace tetiso::scheduler_test;

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
