// The scheduler with GPUs, on the simulated clock of scheduler_fakes.hpp:
// drivers run their GPUs' tasks, seams only once every domain task is
// placed, never lend cores and borrow them only for a seam; --device gpu
// sends every domain to a driver; a GPU's grant carries a batch of
// domain tasks, every GPU gets some, the batches shrink at the end of the
// queue, the CPU keeps domains under auto; a failure inside a batch names
// its task; Job::execute_batch gives each task's piece alone.
#include <gtest/gtest.h>

#include "scheduler_fakes.hpp"

using namespace tetiso;
using namespace tetiso::scheduler_test;

TEST(Scheduler, GpuDriversRunTheirGpusTasksAndSeamsOnlyAtTheEnd) {
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
    double last_domain_sent = 0;
    for (const FakeTransport::Sent& s : transport.sent)
        if (job.kind(s.task) == TaskKind::domain) last_domain_sent = std::max(last_domain_sent, s.at);
    // The seams a driver ran, each (start, end), to tell its borrowing.
    std::vector<std::pair<double, double>> driver_seams;
    for (const TaskRecord& r : result->tasks)
        if (r.rank == 1 && r.kind == TaskKind::seam) driver_seams.push_back({r.start, r.end});
    for (const FakeTransport::Sent& s : transport.sent) {
        if (s.worker == 1) {
            EXPECT_EQ(s.gpu, 0) << "the driver runs its GPU's tasks only";
            if (job.kind(s.task) == TaskKind::domain) {
                ++on_gpu;
            } else {
                EXPECT_GE(s.at, last_domain_sent) << job.describe(s.task) << " went to the GPU before every domain";
            }
        } else {
            EXPECT_EQ(s.gpu, -1) << "task " << s.task << " for a GPU went to rank " << s.worker;
        }
    }
    // Ten times faster, the GPU ends most domains first even behind a queue:
    // their grants wait for the driver rather than go to an idle CPU worker.
    EXPECT_GT(on_gpu, 27 / 2) << "of 27 domains";
    // And once the domains are placed, it takes seams too.
    EXPECT_FALSE(driver_seams.empty());
    // No rank ever holds two tasks.
    std::map<int, std::vector<std::pair<double, double>>> spans;
    for (const TaskRecord& r : result->tasks) spans[r.rank].push_back({r.start, r.end});
    for (auto& [rank, s] : spans) {
        std::sort(s.begin(), s.end());
        for (std::size_t i = 1; i < s.size(); ++i) EXPECT_LE(s[i - 1].second, s[i].first + 1e-9) << "rank " << rank;
    }
    for (const FakeTransport::Lent& l : transport.lent) {
        EXPECT_NE(l.lender, 1);
        if (l.borrower == 1) {
            EXPECT_TRUE(std::any_of(driver_seams.begin(), driver_seams.end(),
                                    [&](const auto& span) { return span.first <= l.at && l.at <= span.second; }))
                << "the driver borrowed cores at " << l.at << " s, running no seam";
        }
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
        double last_domain_sent = 0;
        for (const FakeTransport::Sent& s : transport.sent)
            if (job.kind(s.task) == TaskKind::domain) last_domain_sent = std::max(last_domain_sent, s.at);
        for (const FakeTransport::Sent& s : transport.sent) {
            if (job.kind(s.task) == TaskKind::domain) {
                EXPECT_EQ(s.worker, 1) << job.describe(s.task);
            } else if (s.worker == 1) {
                EXPECT_GE(s.at, last_domain_sent) << job.describe(s.task) << " went to the GPU before every domain";
            }
        }
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

// A GPU's batch has a cost of its own beside its tasks': under auto, a
// grant that would wait behind the GPU's others is never a remainder of a
// few tasks that pays that cost for little (the few that would end before
// a core could end one). Cores that fall idle one after another while the
// GPU is busy take such tasks themselves, and the GPU's batches stay
// nearly full until the queue runs low.
TEST(Scheduler, UnderAutoAGpuQueuesNoWastefulRemainders) {
    JobConfig config = lattice_job(48, 256);
    config.device = JobConfig::Device::automatic;
    config.gpu_batch = 8;
    const Job job(config);
    const int domains = domain_count_of(job);
    // Rank 1 drives the GPU; ranks 2-7 are cores.
    NodeLayout nodes;
    nodes.node_of.assign(8, 0);
    nodes.driving = {-1, 0, -1, -1, -1, -1, -1, -1};
    nodes.workers = {7};
    nodes.gpus = {{0}};
    nodes.gpu_mib = {80000};
    SchedulerSetup setup = mpi_setup(8);
    setup.nodes = nodes;
    setup.cpu_seconds_per_triangle = 1e-4;
    FakeTransport transport(job, {1, 2, 3, 4, 5, 6, 7}, true);
    transport.raw_triangles = 10000; // a domain takes a core 1 s by the probe
    // A GPU's grant of c tasks takes 0.2 + 0.05 c s; the cores' domains
    // take 0.9-1.1 s, so that they fall idle at different times.
    transport.batch_seconds = 0.2;
    transport.duration = [&](int task, int worker) {
        if (job.kind(task) != TaskKind::domain) return 0.01;
        return worker == 1 ? 0.05 : 0.9 + 0.05 * (task % 5);
    };
    const auto seconds_per_task = [](std::size_t c) { return (0.2 + 0.05 * static_cast<double>(c)) / static_cast<double>(c); };
    Scheduler scheduler(job, setup);
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.01));
    ASSERT_TRUE(result.has_value());
    int on_cpu = 0;
    for (const FakeTransport::Sent& s : transport.sent) on_cpu += job.kind(s.task) == TaskKind::domain && s.worker != 1;
    EXPECT_GT(on_cpu, 0) << "the cores take domains";
    // The GPU's first four grants are placed before its model has three
    // samples of batches (one task, the learning batch, and two placed as
    // that ends). Every later one sent while four full batches' worth of
    // domains were unsent takes at most kRemainderWaste times a full
    // batch's seconds per task.
    int grants = 0;
    for (std::size_t i = 0, b = 0; i < transport.sent.size();) {
        const bool batch = b < transport.batches.size() && transport.batches[b].sent_before == i;
        const std::size_t size = batch ? transport.batches[b++].tasks.size() : 1;
        if (transport.sent[i].worker == 1 && job.kind(transport.sent[i].task) == TaskKind::domain && grants++ >= 4) {
            int unsent = domains;
            for (std::size_t j = 0; j < i; ++j) unsent -= job.kind(transport.sent[j].task) == TaskKind::domain;
            if (unsent >= 4 * 8) {
                EXPECT_LE(seconds_per_task(size), ResourceManager::kRemainderWaste * seconds_per_task(8))
                    << "a grant of " << size << " sent at " << transport.sent[i].at << " s, " << unsent << " domains unsent";
            }
        }
        i += size;
    }
    EXPECT_GT(grants, 10);
}

// Under auto, idle cores place domains ahead onto the GPUs' queues, split
// among the GPUs by predictions, which early in a job can run long for one
// GPU (here its first tasks ran three times slower than later ones). Once
// idle, that GPU takes the grants queued last on the other, where it would
// end them earlier, and a GPU that ended its work early takes new grants at
// once: the two end their domains within a batch of each other.
TEST(Scheduler, AnIdleGpuTakesTheGrantsQueuedOnAnother) {
    JobConfig config = lattice_job(48, 128);
    config.device = JobConfig::Device::automatic;
    config.gpu_batch = 8;
    const Job job(config);
    FakeTransport transport(job, {1, 2, 3, 4, 5, 6}, true);
    transport.raw_triangles = 10000; // a domain takes a core 10 s by the probe
    transport.batch_seconds = 0.1;
    int slow = 9;
    transport.duration = [&](int task, int worker) {
        if (job.kind(task) != TaskKind::domain) return 0.01;
        if (worker > 2) return 10.0;
        return worker == 1 && slow-- > 0 ? 0.15 : 0.05;
    };
    SchedulerSetup setup = two_gpus_setup();
    setup.ranks = 7;
    setup.nodes->node_of.assign(7, 0);
    setup.nodes->driving = {-1, 0, 1, -1, -1, -1, -1};
    setup.nodes->workers = {6};
    setup.cpu_seconds_per_triangle = 1e-3;
    Scheduler scheduler(job, setup);
    const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.01));
    ASSERT_TRUE(result.has_value());
    std::map<int, double> domains_end; // rank -> the end of its last domain task
    for (const TaskRecord& r : result->tasks)
        if (job.kind(r.task) == TaskKind::domain) domains_end[r.rank] = std::max(domains_end[r.rank], r.end);
    ASSERT_TRUE(domains_end.count(1) && domains_end.count(2));
    EXPECT_EQ(domains_end.size(), 2u) << "the cores, ten times slower than a batch of the GPUs, take none";
    const double full_batch = 0.1 + 8 * 0.05;
    EXPECT_LE(std::abs(domains_end[1] - domains_end[2]), full_batch)
        << "GPU 0's domains end at " << domains_end[1] << " s, GPU 1's at " << domains_end[2] << " s";
}

// With the CPU's probe (Job::probe_cpu), no CPU worker takes a domain until
// a first domain task has ended: then the probe's rate times its raw
// triangles is the CPU's prior. A small job the GPUs end before a CPU task
// could stays on the GPUs; a job on slow GPUs gives the CPU domains, only
// after that first result.
TEST(Scheduler, UnderAutoTheCpuWaitsForItsPriorBeforeItTakesADomain) {
    JobConfig config = lattice_job(24, 16);
    config.device = JobConfig::Device::automatic;
    const Job job(config);
    const auto run = [&](double gpu_seconds, double probe) {
        FakeTransport transport(job, {1, 2, 3, 4}, true);
        transport.raw_triangles = 10000;
        // A CPU worker takes what the probe says: 1e-4 s x 10,000 triangles.
        transport.duration = [gpu_seconds](int, int worker) { return worker <= 2 ? gpu_seconds : 1.0; };
        SchedulerSetup setup = two_gpus_setup();
        setup.cpu_seconds_per_triangle = probe;
        Scheduler scheduler(job, setup);
        const std::optional<JobResult> result = drive(job, scheduler, transport, hooks_here(transport, job, 0.1));
        EXPECT_TRUE(result.has_value());
        EXPECT_DOUBLE_EQ(result ? result->cpu_seconds_per_triangle : -1, probe);
        // While the cores wait, each GPU learns: one task, then a batch of
        // at most kLearningBatch, so that the wait ends soon.
        std::map<int, std::vector<std::size_t>> grants; // driver -> its grants' sizes, in order
        for (std::size_t i = 0, b = 0; i < transport.sent.size();) {
            const FakeTransport::Sent& s = transport.sent[i];
            const bool batch = b < transport.batches.size() && transport.batches[b].sent_before == i;
            const std::size_t size = batch ? transport.batches[b++].tasks.size() : 1;
            if (s.worker <= 2 && job.kind(s.task) == TaskKind::domain) grants[s.worker].push_back(size);
            i += size;
        }
        for (const auto& [driver, sizes] : grants) {
            if (sizes.size() < 2) {
                ADD_FAILURE() << "GPU driver " << driver << " had " << sizes.size() << " grants";
                continue;
            }
            EXPECT_EQ(sizes[0], 1u) << "GPU driver " << driver;
            EXPECT_LE(sizes[1], static_cast<std::size_t>(ResourceManager::kLearningBatch)) << "GPU driver " << driver;
        }
        return transport.sent;
    };
    const auto domains_on_cpu = [&](const std::vector<FakeTransport::Sent>& sent) {
        std::vector<double> at;
        for (const FakeTransport::Sent& s : sent)
            if (job.kind(s.task) == TaskKind::domain && s.worker > 2) at.push_back(s.at);
        return at;
    };
    // GPUs 20 times faster than a core: 16 domains take them 0.4 s, less
    // than one domain on a core.
    EXPECT_TRUE(domains_on_cpu(run(0.05, 1e-4)).empty());
    // Without the probe the idle cores take domains at once, as they always
    // did: those are what the job then waits for.
    const std::vector<double> blind = domains_on_cpu(run(0.05, 0));
    ASSERT_FALSE(blind.empty());
    EXPECT_EQ(blind.front(), 0.0);
    // GPUs three times slower than a core: the CPU takes domains, from the
    // end of the first GPU task on.
    const std::vector<double> slow = domains_on_cpu(run(3.0, 1e-4));
    ASSERT_FALSE(slow.empty());
    for (const double at : slow) EXPECT_GE(at, 3.0);
}

// The single process of a job without MPI drives no GPU: its one worker
// runs the GPU's grants too, so it is room for them while the CPU waits for
// its prior.
TEST(Scheduler, ASingleProcessWaitingForTheCpusPriorRunsTheGpusGrants) {
    JobConfig config = lattice_job(12, 8);
    config.device = JobConfig::Device::automatic;
    const Job job(config);
    FakeTransport transport(job, {0}, false);
    transport.raw_triangles = 10000;
    transport.duration = [](int, int) { return 0.1; };
    SchedulerSetup setup;
    setup.nodes = single_process_layout({0}, 80000);
    setup.cpu_seconds_per_triangle = 1e-4;
    Scheduler scheduler(job, setup);
    const std::optional<JobResult> result = drive(job, scheduler, transport, DriveHooks{});
    ASSERT_TRUE(result.has_value());
    EXPECT_EQ(result->tasks.size(), static_cast<std::size_t>(job.task_count()));
    EXPECT_EQ(transport.sent.front().gpu, 0) << "the first domain task, on the GPU";
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

