// The in-process transport: one worker, this process (rank 0), which runs
// each task where it is sent and reports it at the next receive(). With it
// the single-process run is the scheduler of the MPI job with one worker and
// no controller of its own: tasks in TaskQueue order, one at a time, placed
// by the resource manager under --device auto and gpu.
#pragma once

#include <chrono>
#include <deque>

#include "transport.hpp"

namespace tetiso {

class LocalTransport : public Transport {
public:
    // placed: the scheduler places tasks (a task's GPU then comes with it;
    // otherwise it runs where the job's --device says).
    LocalTransport(const Job& job, bool placed);
    void send_task(int worker, TaskMessage message) override;
    void send_batch(int worker, BatchMessage message) override;
    void lend_cores(int, int) override {}
    std::optional<WorkerEvent> receive(double deadline) override;
    double clock() const override;
    int stop(bool) override { return -1; }

private:
    const Job& job_;
    bool placed_;
    std::chrono::steady_clock::time_point start_;
    std::deque<WorkerEvent> events_;
};

} // namespace tetiso
