// The job's scheduling policy as a pure state machine (paper, section "Load
// balancing and job scheduling"): events in — a worker is ready, a task
// ended or failed, time passed — and actions out — send a task to a worker,
// lend an idle worker's cores to a running task, run a seam here. The
// placement of tasks on each node's devices (placement.hpp) is decided
// inside, by the node's ResourceManager. Like the manager it holds no clock
// and sends nothing: the caller says what time it is (seconds since the job
// started) and carries out the actions over a Transport (transport.hpp), so
// that the policy is the same for a single process and an MPI job, and is
// unit-tested on a simulated clock (validation/tests/test_scheduler.cpp).
//
// The policy: tasks in TaskQueue order. Under --device cpu a task goes to
// whichever idle worker has its cores (an idle worker that lent them out
// only when there is no other); under auto or gpu a node is asked for a
// task once one of its processes is idle and not promised, and the task
// waits for its grant. A grant on a GPU takes the next domain tasks of the
// queue with it as one batch (placement.hpp says how many), sent to the
// GPU's driver in one message and answered with one result per task. A controller that is not a worker runs a seam itself
// when it is the only task left to run (the root, and in practice every
// seam after the last domain). Once no task is ready, idle workers lend
// their cores to running tasks. Once every domain task is placed, a seam
// may go to a GPU's driver, where its region is reduced on the GPU. A task
// that fails stops the handing out; the job ends when nothing runs. A task that has not ended by its deadline
// — max(floor, kDeadlineFactor x its predicted seconds) after it was sent —
// names its rank as stopped answering; the prediction is the latest, so a
// task sent before any had ended gets its deadline once one has.
#pragma once

#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "messages.hpp"
#include "node_layout.hpp"
#include "tetiso/placement.hpp"
#include "tetiso/resources.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso {

struct SchedulerAction {
    enum class Kind {
        send_task,  // message.task to `worker`, with the pieces it needs
        send_batch, // batch: several domain tasks to `worker`, a GPU's driver (or a lone worker)
        lend_cores, // `lender`'s cores to `worker`, whose task takes them between reduction rounds
        run_here,   // the controller runs `task` itself (inputs()), then reports on_result or on_failure as rank 0
    };
    Kind kind = Kind::send_task;
    int worker = -1;
    int lender = -1;
    int task = -1;
    TaskMessage message;
    BatchMessage batch;
};

struct SchedulerSetup {
    int ranks = 1; // ranks are 0 .. ranks - 1; a worker is idle once it reported ready
    // Whether rank 0 controls without being a worker, and runs the last
    // seams itself.
    bool seams_here = false;
    // With --device auto (or gpu under MPI): the nodes, their GPUs and
    // drivers, each node's tasks placed by its resource manager.
    std::optional<NodeLayout> nodes;
    // The shortest deadline a task gets, in seconds; 0: no deadline.
    double task_timeout = 0;
    // With nodes: the CPU's speed as Job::probe_cpu measured it, seconds per
    // raw triangle on one core; 0: not measured (NodePlacement says how it
    // is used).
    double cpu_seconds_per_triangle = 0;
};

// Why the job failed: a task that threw, or a rank that stopped answering.
struct SchedulerFailure {
    int task = -1; // -1: the rank held no task
    int rank = 0;
    std::string what;
    bool unresponsive = false; // the rank holds the task still: it cannot be stopped in order
    double allowed_seconds = 0; // unresponsive: the deadline it missed
};

// A finished task's record as a result message: what a worker sends back,
// or the controller reports of a task it ran.
ResultMessage result_message(const TaskRecord& record, double seconds, int threads, Piece piece);
// A finished batch's results: `seconds`, the batch's time on the worker,
// shared out among its tasks in proportion to their stages' seconds.
BatchResultMessage batch_result_message(const std::vector<TaskRecord>& records, double seconds, int threads,
                                        std::vector<Piece> pieces);

class Scheduler {
public:
    // A task's deadline is at least this many times its predicted seconds.
    static constexpr double kDeadlineFactor = 10;

    Scheduler(const Job& job, SchedulerSetup setup);

    // What to do now. A run_here action comes alone: carry it out and report
    // before asking again.
    std::vector<SchedulerAction> decide(double now);

    // Events. Each one from a worker also makes it idle (a worker reports
    // only when it has nothing to do).
    void on_ready(int worker, bool cores_known, double now);
    void on_result(int rank, ResultMessage result, double now);
    // A batch's results, in the batch's order.
    void on_batch_result(int rank, std::vector<ResultMessage> results, double now);
    void on_failure(int rank, int task, const std::string& what, double now);
    // Time passed: a task past its deadline fails the job as unresponsive.
    void on_time(double now);
    // A worker that did not answer the end of the job (it held no task)
    // fails it as unresponsive.
    void on_silent(int worker);

    // When on_time next has something to check (infinity: never).
    double next_deadline() const;
    // The seconds a task is given from when it is sent, under the
    // predictions now: infinity before any task has ended (nothing says yet
    // how long tasks take) or without a floor.
    double allowance(int task) const;
    // The same for what `worker` holds: its task, or its batch's tasks together.
    double allowance_of(int worker) const;

    // Nothing runs, and the job either finished or failed.
    bool done() const;
    const std::optional<SchedulerFailure>& failure() const { return failure_; }
    int tasks_done() const { return done_; }
    bool places_tasks() const { return !placements_.empty(); }
    // rank -> task it holds, the first of its batch (a task the controller
    // runs is not among them).
    const std::map<int, int>& running() const { return running_; }
    // rank -> the batch it runs, where it runs one.
    const std::map<int, std::vector<int>>& batches() const { return batches_; }
    // The pieces a task run here takes (null for a domain task).
    const Piece* input(int task, bool right) const;
    // The finished job (done(), no failure): the surface and the records.
    JobResult take_result(double now);

private:
    // A task's grant, from its request to its result; a GPU's grant may
    // carry a batch, `tasks` (the first is `task`).
    struct Placed {
        int task = 0, node = 0;
        std::vector<int> tasks;
        Grant grant;
        double asked_at = 0, sent_at = 0;
    };

    std::optional<Piece>& piece(int task) { return pieces_[static_cast<std::size_t>(task)]; }
    std::size_t at(int rank) const { return static_cast<std::size_t>(rank); }
    void fail(int task, int rank, const std::string& what);
    bool should_run_here() const;
    void lend_idle_cores(std::vector<SchedulerAction>& actions);
    void end_lends_to(int borrower);
    int take_idle();
    bool runs_on_gpu(int worker) const;
    bool drives_gpu(int worker) const;
    int driver_of(int node, int device) const;
    int node_with_room() const;
    void place(int node, double now);
    void rebalance(double now);
    int executor_of(const Placed& p) const;
    void start_granted(std::vector<SchedulerAction>& actions, double now);
    void cancel_waiting();
    void send_task(std::vector<SchedulerAction>& actions, int worker, int task, int gpu, double now);
    void send_batch(std::vector<SchedulerAction>& actions, int worker, const std::vector<int>& tasks, int gpu,
                    double now);
    TaskRecord completed(const ResultMessage& result, int rank, double start, double end) const;
    void keep_result(int task, Piece piece, double seconds, TaskRecord record);
    double predicted_seconds(int task) const;
    double task_size(int task) const;
    void learn(int task, double size, double seconds);

    const Job& job_;
    const SchedulerSetup setup_;
    TaskQueue queue_;
    std::vector<std::optional<Piece>> pieces_; // by task, while its parent has not taken it
    std::deque<int> idle_;
    std::map<int, int> running_; // worker -> task
    std::map<int, std::vector<int>> batches_; // worker -> the batch it runs, where it runs one
    JobResult result_;
    std::optional<SchedulerFailure> failure_;
    int done_ = 0;
    int here_ = -1; // the task run here, while it runs
    std::vector<bool> cores_known_;
    std::vector<int> lent_to_;            // lender -> borrower
    std::map<int, int> lends_;            // borrower -> lends it has
    std::map<int, double> dispatched_at_; // worker -> when its task was sent
    std::vector<double> size_sent_;       // by task: its size when sent (task_size)
    // How long each kind of task took here, for the deadlines: a model over
    // the task's size (PerformanceModel) and the longest seen.
    std::map<int, PerformanceModel> models_;
    std::map<int, double> longest_;
    // --device auto or gpu: a manager per node, the ranks that drive its
    // GPUs, and each task's grant from the request to its result.
    std::vector<int> node_of_;                          // by rank
    std::vector<int> driving_;                          // by rank: the GPU it drives, -1 for none
    std::map<std::pair<int, int>, int> driver_of_gpu_;  // (node, CUDA index) -> rank
    std::deque<NodePlacement> placements_;              // by node
    std::map<int, Placed> placed_;                      // worker -> the grant of the task it runs
    int domains_to_place_ = 0;                          // domain tasks not yet placed
    std::deque<Placed> waiting_;                        // grants not started yet, in the order asked
    int gpu_slots_ = 0;                                 // GPUs the job places tasks on, on every node
};

} // namespace tetiso
