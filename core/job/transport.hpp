// What carries the scheduler's actions to the workers and their reports
// back: a Transport. The MPI one (mpi_transport.hpp) sends messages between
// ranks; the in-process one (local_transport.hpp) runs each task where it
// is sent, so that a single process is the same scheduler with one worker.
// drive() is the controller's loop over either.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>

#include "messages.hpp"
#include "scheduler.hpp"

namespace tetiso {

// A worker's report.
struct WorkerEvent {
    enum class Kind { ready, result, batch_result, failure } kind = Kind::ready;
    int worker = -1;
    bool cores_known = false; // ready: the worker named its cores
    ResultMessage result;
    BatchResultMessage batch;
    FailureMessage failure;
};

class Transport {
public:
    virtual ~Transport() = default;
    virtual void send_task(int worker, TaskMessage message) = 0;
    virtual void send_batch(int worker, BatchMessage message) = 0;
    virtual void lend_cores(int borrower, int lender) = 0;
    // The next report, waiting at most until `deadline` (seconds on the
    // controller's clock, clock()); none when it passed first.
    virtual std::optional<WorkerEvent> receive(double deadline) = 0;
    // The controller is about to be busy for up to `seconds` (a task it runs
    // itself): workers waiting on it should not give up sooner.
    virtual void busy_for(double seconds) { (void)seconds; }
    // Seconds since the job started.
    virtual double clock() const = 0;
    // Every worker told that the job ended (`failed`: on an error), and
    // each one's answer awaited; returns a rank that did not answer within
    // its deadline (it stopped answering while it held no task), or -1.
    virtual int stop(bool failed) = 0;
};

// What the controller does around a task it runs itself, and a task's
// progress: called by drive().
struct DriveHooks {
    // Runs `task` on the controller and returns its result (the
    // controller's threads and cores are the hook's business); throws what
    // the task throws.
    std::function<ResultMessage(int task, const Piece* left, const Piece* right)> run_here;
    // After each event: the tasks each rank holds now (rank -> task).
    std::function<void(const std::map<int, int>& running)> on_running;
    Progress progress;
};

// Runs the scheduler to its end over the transport. Returns the job's
// result; a failure comes back in scheduler.failure(), with the workers
// stopped unless it is a rank that stopped answering, which cannot be.
std::optional<JobResult> drive(const Job& job, Scheduler& scheduler, Transport& transport, const DriveHooks& hooks);

} // namespace tetiso
