// The node's resource manager on a simulated clock with synthetic devices:
// it grants the device where a task would end first, learns each device's
// times from finished tasks, never puts more units on a device than it has,
// and serves waiting clients in the order they asked.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tetiso/error.hpp"
#include "tetiso/placement.hpp"
#include "tetiso/resources.hpp"
#include "tetiso/schedule.hpp"

using namespace tetiso;

namespace {

constexpr int kDomain = 0;
constexpr int kCpu = 0, kGpu = 1;

ManagedDevice cpu(double processes) { return {"cpu", -1, processes, 0}; }
ManagedDevice gpu(int index, double mib) { return {"gpu " + std::to_string(index), index, mib, 0}; }

// Runs `count` tasks of `size` on `device` through the manager, each taking
// `seconds`, so that its model there is calibrated.
void calibrate(ResourceManager& manager, int device, double size, double seconds, int count = PerformanceModel::kMinSamples) {
    for (int i = 0; i < count; ++i) {
        ResourceRequest r{kDomain, size, std::vector<double>(manager.devices().size(), 0.0)};
        r.units[static_cast<std::size_t>(device)] = 1;
        const Grant g = manager.request(r, 0);
        ASSERT_EQ(g.device, device);
        ASSERT_TRUE(manager.start(g.ticket, 0));
        manager.finish(g.ticket, seconds);
    }
}

} // namespace

TEST(PerformanceModel, NoPredictionBeforeEnoughSamples) {
    PerformanceModel m;
    EXPECT_FALSE(m.predict(100));
    m.add(100, 2.0);
    m.add(100, 4.0);
    EXPECT_FALSE(m.predict(100));
    m.add(100, 3.0);
    ASSERT_TRUE(m.predict(100));
    EXPECT_DOUBLE_EQ(*m.predict(100), 3.0); // the history's mean for a size it has seen
}

TEST(PerformanceModel, RegressionOverSizes) {
    PerformanceModel m;
    // seconds = 2e-6 * size^1.5: the fit in log-log space recovers it.
    for (const double size : {1000.0, 2000.0, 4000.0}) m.add(size, 2e-6 * std::pow(size, 1.5));
    ASSERT_TRUE(m.predict(8000));
    EXPECT_NEAR(*m.predict(8000), 2e-6 * std::pow(8000.0, 1.5), 1e-6);
    EXPECT_NEAR(*m.predict(1500), 2e-6 * std::pow(1500.0, 1.5), 1e-6);
}

TEST(ResourceManager, PicksTheFasterFreeDevice) {
    ResourceManager manager({cpu(4), gpu(0, 1000)});
    calibrate(manager, kCpu, 100, 1.0);
    calibrate(manager, kGpu, 100, 0.1);
    const Grant g = manager.request({kDomain, 100, {1, 200}}, 10.0);
    EXPECT_EQ(g.device, kGpu);
    EXPECT_DOUBLE_EQ(g.start, 10.0);
    EXPECT_NEAR(g.predicted_seconds, 0.1, 1e-12);
    // The same task where only the CPU is fast.
    ResourceManager slow_gpu({cpu(4), gpu(0, 1000)});
    calibrate(slow_gpu, kCpu, 100, 0.2);
    calibrate(slow_gpu, kGpu, 100, 0.5);
    EXPECT_EQ(slow_gpu.request({kDomain, 100, {1, 200}}, 0).device, kCpu);
}

TEST(ResourceManager, FallsBackToTheCpuWhenTheGpuQueueIsLong) {
    // The GPU holds one task at a time (its memory) and takes 0.4 s; the CPU
    // has four processes and takes 1 s. Two tasks queue on the GPU (ending
    // at 0.4 and 0.8); a third would end there at 1.2, on the CPU at 1.0.
    ResourceManager manager({cpu(4), gpu(0, 100)});
    calibrate(manager, kCpu, 50, 1.0);
    calibrate(manager, kGpu, 50, 0.4);
    const ResourceRequest r{kDomain, 50, {1, 100}};
    const Grant a = manager.request(r, 0);
    const Grant b = manager.request(r, 0);
    const Grant c = manager.request(r, 0);
    EXPECT_EQ(a.device, kGpu);
    EXPECT_DOUBLE_EQ(a.start, 0.0);
    EXPECT_EQ(b.device, kGpu);
    EXPECT_NEAR(b.start, 0.4, 1e-12); // t_b: when the first frees the memory
    EXPECT_EQ(c.device, kCpu);
    EXPECT_DOUBLE_EQ(c.start, 0.0);
}

TEST(ResourceManager, TransferTimeCounts) {
    // The GPU computes faster, but moving the task there and back costs more
    // than it saves; once a transfer has been measured it replaces the guess.
    ResourceManager manager({cpu(1), {"gpu 0", 0, 1000, 0.0}});
    calibrate(manager, kCpu, 100, 0.5);
    calibrate(manager, kGpu, 100, 0.1);
    EXPECT_EQ(manager.request({kDomain, 100, {1, 10}}, 0).device, kGpu);
    ResourceManager measured({cpu(1), {"gpu 0", 0, 1000, 0.0}});
    calibrate(measured, kCpu, 100, 0.5);
    for (int i = 0; i < PerformanceModel::kMinSamples; ++i) {
        const Grant g = measured.request({kDomain, 100, {0, 10}}, 0);
        ASSERT_TRUE(measured.start(g.ticket, 0));
        measured.finish(g.ticket, 0.1, 0.6);
    }
    EXPECT_NEAR(measured.predict(kDomain, 100, kGpu), 0.7, 1e-12);
    EXPECT_EQ(measured.request({kDomain, 100, {1, 10}}, 0).device, kCpu);
}

TEST(ResourceManager, LearnsFromFinishedTasks) {
    ResourceManager manager({cpu(2), gpu(0, 1000)});
    // Nothing known: the uncalibrated guess, the same everywhere, and the
    // tie goes to the device listed first.
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 10, kGpu), ResourceManager::kUncalibratedSeconds);
    calibrate(manager, kCpu, 10, 2.0);
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 10, kCpu), 2.0);
    // The GPU, not calibrated, is assumed faster than the fastest device
    // known, so that it is tried next and learns.
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 10, kGpu), 2.0 / ResourceManager::kUncalibratedSpeedup);
    const Grant tried = manager.request({kDomain, 10, {1, 100}}, 0);
    EXPECT_EQ(tried.device, kGpu);
    manager.cancel(tried.ticket);
    calibrate(manager, kGpu, 10, 0.25);
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 10, kGpu), 0.25);
    // A kind of its own has a model of its own.
    EXPECT_DOUBLE_EQ(manager.predict(1, 10, kCpu), ResourceManager::kUncalibratedSeconds);
    ASSERT_NE(manager.model(kDomain, kGpu), nullptr);
    EXPECT_EQ(manager.model(kDomain, kGpu)->samples(), PerformanceModel::kMinSamples);
}

// The first tasks on the CPU still running while the GPU has finished three:
// the CPU, uncalibrated, must not be guessed faster than the GPU (its guess
// derives from the GPU's times) when its tasks have already run longer.
TEST(ResourceManager, RunningTasksBoundAnUncalibratedGuess) {
    ResourceManager manager({cpu(4), gpu(0, 1)});
    std::vector<int> running;
    for (int i = 0; i < 4; ++i) {
        const Grant g = manager.request({kDomain, 10, {1, 0}}, 0);
        ASSERT_TRUE(manager.start(g.ticket, 0));
        running.push_back(g.ticket);
    }
    for (int i = 0; i < PerformanceModel::kMinSamples; ++i) {
        const Grant g = manager.request({kDomain, 10, {0, 1}}, 0.1 * i);
        ASSERT_TRUE(manager.start(g.ticket, 0.1 * i));
        manager.finish(g.ticket, 0.1);
    }
    // The guess alone would be 0.05 s: the CPU's four tasks have run 0.9 s.
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 10, kCpu), 0.1 / ResourceManager::kUncalibratedSpeedup);
    const Grant next = manager.request({kDomain, 10, {1, 1}}, 0.9);
    EXPECT_EQ(next.device, kGpu);
    EXPECT_NEAR(next.predicted_seconds, 0.1, 1e-12);
    // Once calibrated, the CPU's model alone counts, however long a task
    // there has been running.
    manager.cancel(next.ticket);
    for (const int ticket : running) manager.finish(ticket, 2.0);
    const Grant slow = manager.request({kDomain, 10, {1, 0}}, 5);
    ASSERT_TRUE(manager.start(slow.ticket, 5));
    EXPECT_DOUBLE_EQ(manager.request({kDomain, 10, {1, 0}}, 100).predicted_seconds, 2.0);
}

// A prior stands for a device until its first sample; its own first
// samples, too few to trust, stand for it before any other device's guess.
TEST(ResourceManager, APriorStandsUntilTheDevicesOwnSamples) {
    ResourceManager manager({cpu(2), gpu(0, 1)});
    EXPECT_THROW(manager.set_prior(kDomain, kCpu, 0), Error);
    manager.set_prior(kDomain, kCpu, 0.01);
    EXPECT_TRUE(manager.has_prior(kDomain, kCpu));
    EXPECT_FALSE(manager.has_prior(kDomain, kGpu));
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 100, kCpu), 1.0);
    // The GPU, with nothing of its own, is guessed faster than the CPU's prior.
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 100, kGpu), 1.0 / ResourceManager::kUncalibratedSpeedup);
    // One sample on the GPU: its time, not the guess.
    calibrate(manager, kGpu, 100, 0.05, 1);
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 100, kGpu), 0.05);
    const Grant g = manager.request({kDomain, 100, {1, 1}}, 10);
    EXPECT_EQ(g.device, kGpu);
    manager.cancel(g.ticket);
    // One sample on the CPU replaces its prior.
    calibrate(manager, kCpu, 100, 3.0, 1);
    EXPECT_DOUBLE_EQ(manager.predict(kDomain, 100, kCpu), 3.0);
}

TEST(ResourceManager, UsesSeveralGpus) {
    ResourceManager manager({cpu(8), gpu(0, 100), gpu(1, 100)});
    calibrate(manager, kCpu, 10, 1.0);
    calibrate(manager, 1, 10, 0.1);
    calibrate(manager, 2, 10, 0.1);
    const ResourceRequest r{kDomain, 10, {1, 100, 100}};
    const Grant a = manager.request(r, 0);
    const Grant b = manager.request(r, 0);
    EXPECT_EQ(a.device, 1);
    EXPECT_EQ(b.device, 2); // the other GPU is free now; the first only at 0.1
    EXPECT_DOUBLE_EQ(b.start, 0.0);
    const Grant c = manager.request(r, 0);
    EXPECT_NEAR(c.start, 0.1, 1e-12); // both busy: the next on whichever frees first
    EXPECT_NE(c.device, kCpu);
}

// Batches: a GPU may take up to 32 tasks of size 10 in one grant; it takes
// as many as end no later than the task would alone on the CPU.
TEST(ResourceManager, ABatchEndsNoLaterThanTheTaskAloneOnTheCpu) {
    ResourceManager manager({cpu(1), gpu(0, 1)});
    calibrate(manager, kCpu, 10, 1.04);
    // The GPU has run batches of two sizes: 0.1 s a task.
    calibrate(manager, kGpu, 10, 0.1);
    calibrate(manager, kGpu, 20, 0.2);
    const ResourceRequest r{kDomain, 10, {1, 1}, {1, 32}};
    const Grant a = manager.request(r, 0);
    EXPECT_EQ(a.device, kGpu);
    EXPECT_EQ(a.count, 10);
    EXPECT_NEAR(a.predicted_seconds, 1.0, 1e-9);
    // The GPU is booked until 1.0: the CPU ends the next task first.
    const Grant b = manager.request(r, 0);
    EXPECT_EQ(b.device, kCpu);
    EXPECT_EQ(b.count, 1);
    // Both booked: the GPU's batch may end as late as the CPU's next task.
    const Grant c = manager.request(r, 0);
    EXPECT_EQ(c.device, kGpu);
    EXPECT_EQ(c.count, 10);
    EXPECT_NEAR(c.start, 1.0, 1e-9);
    // The GPU's model learns the batch, at its size.
    ASSERT_TRUE(manager.start(a.ticket, 0));
    manager.finish(a.ticket, 0.5);
    EXPECT_EQ(manager.model(kDomain, kGpu)->sizes(), 3u);
    EXPECT_EQ(manager.model(kDomain, kGpu)->samples(), 7);
}

// A GPU whose batches have a fixed cost: a batch of 32 tasks of size 10
// takes 1.1 s, one task alone 0.12 s (the fit: 0.12 c^0.64 s for c tasks).
// While the GPU is busy, a batch cut short by where the task would end on
// the CPU (a remainder) is granted only where its tasks take at most
// kRemainderWaste times a full batch's share; otherwise the task goes to
// the CPU. An idle GPU takes any remainder.
TEST(ResourceManager, ARemainderThatWouldWaitAndWasteTheGpuGoesToTheCpu) {
    const auto manager_with_cpu = [](double cpu_seconds) {
        ResourceManager manager({cpu(1), gpu(0, 1)});
        calibrate(manager, kCpu, 10, cpu_seconds);
        calibrate(manager, kGpu, 10, 0.12);
        calibrate(manager, kGpu, 320, 1.1);
        return manager;
    };
    const ResourceRequest r{kDomain, 10, {1, 1}, {1, 32}};
    const auto wasteful = [](const Grant& g) { return g.predicted_seconds * 32 > ResourceManager::kRemainderWaste * 1.1 * g.count; };
    {
        ResourceManager manager = manager_with_cpu(1.3);
        const Grant a = manager.request(r, 0);
        EXPECT_EQ(a.device, kGpu);
        EXPECT_EQ(a.count, 32);
        // The GPU would end the task alone at 1.22 s, the CPU at 1.3 s; only
        // two tasks fit on the GPU by then, at 0.09 s each: the CPU takes it.
        const Grant b = manager.request(r, 0);
        EXPECT_EQ(b.device, kCpu);
        // The CPU booked until 1.3 s: a full batch on the GPU ends first.
        const Grant c = manager.request(r, 0);
        EXPECT_EQ(c.device, kGpu);
        EXPECT_EQ(c.count, 32);
        EXPECT_NEAR(c.start, 1.1, 1e-9);
        // The GPU busy until 2.2 s, the CPU's next end 2.6 s: six tasks
        // would fit, at 0.063 s each.
        const Grant d = manager.request(r, 0);
        EXPECT_EQ(d.device, kCpu);
        EXPECT_NEAR(d.start, 1.3, 1e-9);
    }
    {
        // The CPU would end the task at 2 s: the remainder that fits after
        // the GPU's first batch is 23 tasks, within the waste allowed.
        ResourceManager manager = manager_with_cpu(2.0);
        EXPECT_EQ(manager.request(r, 0).count, 32);
        const Grant b = manager.request(r, 0);
        EXPECT_EQ(b.device, kGpu);
        EXPECT_NEAR(b.start, 1.1, 1e-9);
        EXPECT_GT(b.count, 1);
        EXPECT_LT(b.count, 32);
        EXPECT_FALSE(wasteful(b)) << b.count << " tasks in " << b.predicted_seconds << " s";
    }
    {
        // An idle GPU takes the four tasks that end before the CPU's 0.3 s.
        ResourceManager manager = manager_with_cpu(0.3);
        const Grant a = manager.request(r, 0);
        EXPECT_EQ(a.device, kGpu);
        EXPECT_EQ(a.count, 4);
        EXPECT_TRUE(wasteful(a));
    }
}

// Grants on a device are served in order, but a device that ends its work
// early starts what was queued behind it early, and takes a new grant at
// once after that, not at the start the queue was once booked for.
TEST(ResourceManager, ADeviceThatEndsEarlyTakesTheNextGrantAtOnce) {
    ResourceManager manager({cpu(1), gpu(0, 1)});
    calibrate(manager, kGpu, 10, 1.0);
    const ResourceRequest r{kDomain, 10, {0, 1}};
    const Grant a = manager.request(r, 0);
    const Grant b = manager.request(r, 0);
    EXPECT_NEAR(b.start, 1.0, 1e-9);
    ASSERT_TRUE(manager.start(a.ticket, 0));
    manager.finish(a.ticket, 0.1);
    ASSERT_TRUE(manager.start(b.ticket, 0.1));
    manager.finish(b.ticket, 0.1);
    const Grant c = manager.request(r, 0.3);
    EXPECT_NEAR(c.start, 0.3, 1e-9);
}

// A grant not yet started moves to a device where it would end earlier:
// the driver of an idle GPU takes it from the queue of a busy one.
TEST(ResourceManager, AWaitingGrantMovesWhereItWouldEndEarlier) {
    ResourceManager manager({cpu(1), gpu(0, 1), gpu(1, 1)});
    calibrate(manager, 1, 10, 1.0);
    calibrate(manager, 2, 10, 2.0); // GPU 1 is predicted slower
    const ResourceRequest either{kDomain, 10, {0, 1, 1}};
    // GPU 0 runs one task and has two queued, at 1 s and 2 s; GPU 1 runs one
    // until 2 s.
    const Grant running = manager.request(either, 0);
    const Grant other = manager.request({kDomain, 10, {0, 0, 1}}, 0);
    const Grant first = manager.request(either, 0);
    const Grant second = manager.request(either, 0);
    ASSERT_TRUE(manager.start(running.ticket, 0));
    ASSERT_TRUE(manager.start(other.ticket, 0));
    ASSERT_EQ(running.device, 1);
    ASSERT_EQ(first.device, 1);
    ASSERT_EQ(second.device, 1);
    EXPECT_NEAR(first.start, 1.0, 1e-9);
    EXPECT_NEAR(second.start, 2.0, 1e-9);
    // Neither a started grant nor one onto a device that cannot hold it
    // moves; nor one to GPU 1 while it is busy (no earlier end).
    EXPECT_FALSE(manager.move(running.ticket, 2, 0.1).has_value());
    EXPECT_FALSE(manager.move(first.ticket, kCpu, 0.1).has_value());
    EXPECT_FALSE(manager.move(second.ticket, 2, 0.1).has_value());
    // GPU 1 ends early: the grant queued last on GPU 0 moves there, and
    // starts at once.
    manager.finish(other.ticket, 0.2);
    const std::optional<Grant> moved = manager.move(second.ticket, 2, 0.3);
    ASSERT_TRUE(moved.has_value());
    EXPECT_EQ(moved->device, 2);
    EXPECT_NEAR(moved->start, 0.3, 1e-9);
    EXPECT_TRUE(manager.start(moved->ticket, 0.3));
    EXPECT_THROW(manager.start(second.ticket, 0.3), Error) << "the old ticket is closed";
    // The grant queued first ends at 2 s on GPU 0, later on GPU 1, busy
    // again: it stays.
    EXPECT_FALSE(manager.move(first.ticket, 2, 0.3).has_value());
}

TEST(ResourceManager, UntilTwoBatchSizesAreSeenABatchTakesItsTasksInTurn) {
    ResourceManager manager({cpu(1), gpu(0, 1)});
    calibrate(manager, kCpu, 10, 1.04);
    calibrate(manager, kGpu, 10, 0.1); // one size: no fit over sizes
    // Ten tasks one after another would end with the CPU's one; the batch
    // stops at kLearningBatch, which teaches the GPU a second size.
    const Grant a = manager.request({kDomain, 10, {1, 1}, {1, 32}}, 0);
    EXPECT_EQ(a.device, kGpu);
    EXPECT_EQ(a.count, ResourceManager::kLearningBatch);
    EXPECT_NEAR(a.predicted_seconds, 0.1 * ResourceManager::kLearningBatch, 1e-9);
    ASSERT_TRUE(manager.start(a.ticket, 0));
    manager.finish(a.ticket, 0.2);
    // Two sizes: the fit says a batch of ten ends long before the CPU's task.
    const Grant b = manager.request({kDomain, 10, {1, 1}, {1, 32}}, 1);
    EXPECT_EQ(b.device, kGpu);
    EXPECT_GT(b.count, 10);
    // Nothing known of the GPU: it takes one task at a time, to learn,
    // while the CPU could take the task.
    ResourceManager fresh({cpu(1), gpu(0, 1)});
    const Grant first = fresh.request({kDomain, 10, {1, 1}, {1, 32}}, 0);
    EXPECT_EQ(first.device, kCpu);
    const Grant second = fresh.request({kDomain, 10, {1, 1}, {1, 32}}, 0);
    EXPECT_EQ(second.device, kGpu);
    EXPECT_EQ(second.count, 1);
}

TEST(ResourceManager, WhereNoDeviceTakesTheTaskAloneABatchTakesAllItMay) {
    ResourceManager manager({gpu(0, 1), gpu(1, 1)});
    const ResourceRequest r{kDomain, 10, {1, 1}, {5, 5}};
    const Grant a = manager.request(r, 0);
    const Grant b = manager.request(r, 0);
    EXPECT_EQ(a.count, 5);
    EXPECT_EQ(b.count, 5);
    EXPECT_NE(a.device, b.device);
}

TEST(ResourceManager, ServesWaitingClientsInOrder) {
    ResourceManager manager({gpu(0, 100)});
    calibrate(manager, 0, 10, 1.0);
    const Grant a = manager.request({kDomain, 10, {100}}, 0);
    const Grant b = manager.request({kDomain, 10, {60}}, 0);
    const Grant c = manager.request({kDomain, 10, {30}}, 0);
    ASSERT_TRUE(manager.start(a.ticket, 0));
    // c would fit beside b, but is not placed before it.
    EXPECT_GE(c.start, b.start);
    EXPECT_FALSE(manager.start(b.ticket, 0.5)); // a still holds the memory
    EXPECT_FALSE(manager.start(c.ticket, 0.5)); // b waits before it
    manager.finish(a.ticket, 0.5);
    EXPECT_FALSE(manager.start(c.ticket, 0.5)); // still b's turn
    EXPECT_TRUE(manager.start(b.ticket, 0.5));
    EXPECT_TRUE(manager.start(c.ticket, 0.5)); // 60 + 30 <= 100
}

TEST(ResourceManager, NeverOversubscribes) {
    // Clients ask at random times for random amounts; their tasks take
    // anything from a tenth to three times the prediction. At every step of
    // the simulated clock the units in use stay within each capacity.
    ResourceManager manager({cpu(3), gpu(0, 1000), gpu(1, 500)});
    std::mt19937 random(34);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    struct Running {
        int ticket;
        double end;
    };
    std::vector<Grant> waiting;
    std::vector<Running> running;
    int refused = 0, finished = 0;
    for (int step = 0; step < 4000; ++step) {
        const double now = step * 0.01;
        for (auto it = running.begin(); it != running.end();) {
            if (it->end <= now) {
                manager.finish(it->ticket, 0.05 + unit(random));
                it = running.erase(it);
                ++finished;
            } else {
                ++it;
            }
        }
        if (unit(random) < 0.3) {
            const double size = 1 + std::floor(unit(random) * 4);
            waiting.push_back(manager.request({kDomain, size, {1, 100 + 800 * unit(random), 100 + 400 * unit(random)}}, now));
        }
        for (auto it = waiting.begin(); it != waiting.end();) {
            if (manager.start(it->ticket, now)) {
                running.push_back({it->ticket, now + it->predicted_seconds * (0.1 + 2.9 * unit(random))});
                it = waiting.erase(it);
            } else {
                ++refused;
                ++it;
            }
        }
        for (int d = 0; d < 3; ++d)
            ASSERT_LE(manager.in_use(d), manager.devices()[static_cast<std::size_t>(d)].capacity + 1e-9) << "step " << step;
    }
    EXPECT_GT(finished, 200);
    EXPECT_GT(refused, 0); // the capacities were reached, and held
}

TEST(ResourceManager, RefusesATaskNoDeviceCanHold) {
    ResourceManager manager({cpu(1), gpu(0, 100)});
    EXPECT_THROW(manager.request({kDomain, 10, {0, 200}}, 0), Error);
    EXPECT_THROW(ResourceManager({}), Error);
}

// A node's devices and a job's requests (placement.hpp): the CPU holds the
// node's CPU workers; each GPU one task at a time, and only a domain its
// memory holds after the context; a domain task may go anywhere (under
// --device gpu only to a GPU), a seam only to the CPU.
TEST(NodePlacement, DevicesAndRequestsOfAJob) {
    JobConfig config;
    config.lattice = 21;
    config.domains = 8;
    const Job job(config);
    const NodePlacement cpu_only(job, 3, {}, 0.0);
    ASSERT_EQ(cpu_only.manager.devices().size(), 1u);
    EXPECT_DOUBLE_EQ(cpu_only.manager.devices()[0].capacity, 3.0);

    const NodePlacement two_gpus(job, 3, {0, 1}, 16000.0);
    ASSERT_EQ(two_gpus.manager.devices().size(), 3u);
    EXPECT_EQ(two_gpus.gpu_of(0), -1);
    EXPECT_EQ(two_gpus.gpu_of(2), 1);
    EXPECT_DOUBLE_EQ(two_gpus.manager.devices()[1].capacity, 1.0);

    const int domain_task = job.task_count() - 1; // leaves come last (task_tree)
    ASSERT_EQ(job.kind(domain_task), TaskKind::domain);
    const ResourceRequest domain = two_gpus.request(domain_task, nullptr, nullptr);
    EXPECT_EQ(domain.units, (std::vector<double>{1, 1, 1}));
    EXPECT_DOUBLE_EQ(domain.size, static_cast<double>(job.partition().tet_count()) / 8);

    ASSERT_EQ(job.kind(0), TaskKind::seam);
    Piece left, right;
    left.triangles = {0, 1, 2};
    right.triangles = {0, 1, 2, 0, 2, 3};
    const ResourceRequest seam = two_gpus.request(0, &left, &right);
    EXPECT_EQ(seam.units, (std::vector<double>{1, 0, 0}));
    EXPECT_DOUBLE_EQ(seam.size, 3.0);

    // A GPU whose memory, less the context, cannot hold the domain's
    // estimate: the domain stays on the CPU, or under --device gpu is refused.
    const double small = (kGpuContextMiB + kGpuTaskMarginMiB) / kGpuUsableShare;
    EXPECT_EQ(NodePlacement(job, 3, {0}, small).request(domain_task, nullptr, nullptr).units,
              (std::vector<double>{1, 0}));
    const NodePlacement gpu_only(job, 3, {0}, 16000.0, false);
    EXPECT_EQ(gpu_only.request(domain_task, nullptr, nullptr).units, (std::vector<double>{0, 1}));
    EXPECT_EQ(gpu_only.request(0, &left, &right).units, (std::vector<double>{1, 0}));
    // A seam on a GPU only when the caller allows it, and only where its
    // region fits.
    EXPECT_EQ(gpu_only.request(0, &left, &right, 1, true).units, (std::vector<double>{1, 1}));
    EXPECT_EQ(NodePlacement(job, 3, {0}, small).request(0, &left, &right, 1, true).units,
              (std::vector<double>{1, 0}));
    EXPECT_THROW(NodePlacement(job, 3, {0}, small, false).request(domain_task, nullptr, nullptr), Error);

    // Batches: a GPU may take up to --gpu-batch domain tasks, and no more
    // than its memory holds by the estimate or the caller allows; the CPU one.
    const int default_batch = kGpuBatchPerStream * JobConfig{}.gpu_streams;
    EXPECT_EQ(two_gpus.batch_limit(), default_batch);
    EXPECT_EQ(two_gpus.request(domain_task, nullptr, nullptr, 3).batch, (std::vector<int>{1, 3, 3}));
    EXPECT_EQ(two_gpus.request(domain_task, nullptr, nullptr, 1000).batch,
              (std::vector<int>{1, default_batch, default_batch}));
    EXPECT_TRUE(two_gpus.request(0, &left, &right, 3).batch.empty());
    config.gpu_batch = 4;
    const Job capped(config);
    EXPECT_EQ(NodePlacement(capped, 3, {0}, 16000.0).batch_limit(), 4);
    const double task_mib = static_cast<double>(job.partition().tet_count()) / 8 * kGpuBytesPerTet / (1 << 20) +
                            kGpuTaskMarginMiB;
    const double two_tasks = (kGpuContextMiB + 2.5 * task_mib) / kGpuUsableShare;
    EXPECT_EQ(NodePlacement(job, 3, {0}, two_tasks).batch_limit(), 2);
}
