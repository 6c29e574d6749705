// The job's scheduling policy (scheduler.hpp).
#include "scheduler.hpp"

#include <algorithm>
#include <cmath>

#include "tetiso/error.hpp"

namespace tetiso {

ResultMessage result_message(const TaskRecord& record, double seconds, int threads, Piece piece) {
    ResultMessage result;
    result.seconds = seconds;
    result.record = record;
    result.record.threads = threads;
    result.piece = std::move(piece);
    return result;
}

BatchResultMessage batch_result_message(const std::vector<TaskRecord>& records, double seconds, int threads,
                                        std::vector<Piece> pieces) {
    const auto staged = [](const TaskRecord& r) {
        return r.stages.generate + r.stages.upload + r.stages.extract + r.stages.reduce + r.stages.download;
    };
    double sum = 0;
    for (const TaskRecord& r : records) sum += staged(r);
    BatchResultMessage batch;
    for (std::size_t i = 0; i < records.size(); ++i) {
        const double share = sum > 0 ? staged(records[i]) / sum : 1.0 / static_cast<double>(records.size());
        batch.results.push_back(result_message(records[i], seconds * share, threads, std::move(pieces[i])));
    }
    return batch;
}

Scheduler::Scheduler(const Job& job, SchedulerSetup setup)
    : job_(job), setup_(std::move(setup)), queue_(job), pieces_(static_cast<std::size_t>(job.task_count())),
      cores_known_(static_cast<std::size_t>(setup_.ranks), false), lent_to_(static_cast<std::size_t>(setup_.ranks), -1),
      size_sent_(static_cast<std::size_t>(job.task_count()), 1.0), domains_to_place_(job.partition().domain_count()) {
    result_.ranks = setup_.ranks;
    result_.cpu_seconds_per_triangle = setup_.cpu_seconds_per_triangle;
    if (!setup_.nodes) return;
    const NodeLayout& nodes = *setup_.nodes;
    node_of_ = nodes.node_of;
    driving_ = nodes.driving;
    const bool domains_on_cpu = job.config().device == JobConfig::Device::automatic;
    std::vector<int> drivers(nodes.gpus.size(), 0); // by node
    for (int r = 0; r < static_cast<int>(driving_.size()); ++r) {
        const int node = node_of_[at(r)], gpu = driving_[at(r)];
        if (gpu < 0) continue;
        ++drivers[static_cast<std::size_t>(node)];
        driver_of_gpu_[{node, gpu}] = r;
    }
    for (std::size_t node = 0; node < nodes.gpus.size(); ++node) {
        placements_.emplace_back(job, nodes.workers[node] - drivers[node], nodes.gpus[node], nodes.gpu_mib[node],
                                 domains_on_cpu, setup_.cpu_seconds_per_triangle);
        gpu_slots_ += static_cast<int>(nodes.gpus[node].size());
    }
}

std::vector<SchedulerAction> Scheduler::decide(double now) {
    std::vector<SchedulerAction> actions;
    if (here_ >= 0) throw Error("the scheduler was asked what to do before the task it runs here ended");
    if (should_run_here()) {
        const int task = queue_.pop();
        const TaskNode& n = job_.node(task);
        size_sent_[static_cast<std::size_t>(task)] =
            static_cast<double>(piece(n.left)->triangle_count() + piece(n.right)->triangle_count());
        here_ = task;
        SchedulerAction run;
        run.kind = SchedulerAction::Kind::run_here;
        run.task = task;
        actions.push_back(std::move(run));
        return actions;
    }
    if (placements_.empty()) {
        while (!failure_ && !idle_.empty() && queue_.has_ready()) send_task(actions, take_idle(), queue_.pop(), -1, now);
    } else {
        while (!failure_ && queue_.has_ready()) {
            const int node = node_with_room();
            if (node < 0) break;
            place(node, now);
        }
    }
    if (!failure_) {
        rebalance(now);
        start_granted(actions, now);
    } else {
        cancel_waiting();
    }
    if (!failure_ && !queue_.has_ready()) lend_idle_cores(actions);
    return actions;
}

bool Scheduler::done() const { return running_.empty() && here_ < 0 && (failure_ || queue_.finished()); }

void Scheduler::fail(int task, int rank, const std::string& what) {
    if (!failure_) failure_ = SchedulerFailure{task, rank, what, false, 0};
}

// A seam the controller runs itself when no task is in flight and it is the
// only one ready. Then every unfinished task is one of its ancestors (any
// other would have a ready or running task below it), so nothing could start
// before it ends, and no worker loses work while the controller computes and
// answers nobody. That is always so for the root, and, because the queue
// finishes subtrees early, in practice for every seam after the last domain
// task. Run there, such a seam skips packing both pieces, the worker's
// unpacking, and the same again for its result; and the root seam, which
// holds the whole surface several times, takes no worker's memory. A looser
// rule, with seams of other subtrees still in flight, could keep a finished
// worker's result and the parent it readies waiting for the controller.
bool Scheduler::should_run_here() const {
    return setup_.seams_here && !failure_ && running_.empty() && waiting_.empty() && queue_.ready_count() == 1 &&
           job_.kind(queue_.peek()) == TaskKind::seam;
}

const Piece* Scheduler::input(int task, bool right) const {
    const TaskNode& n = job_.node(task);
    const int child = right ? n.right : n.left;
    if (child < 0) return nullptr;
    const std::optional<Piece>& p = pieces_[static_cast<std::size_t>(child)];
    return p ? &*p : nullptr;
}

void Scheduler::on_ready(int worker, bool cores_known, double) {
    if (cores_known) cores_known_[at(worker)] = true;
    idle_.push_back(worker);
}

// A finished task's record: what its worker measured, and where and when
// (on this clock) it ran.
TaskRecord Scheduler::completed(const ResultMessage& result, int rank, double start, double end) const {
    const TaskNode& n = job_.node(result.record.task);
    TaskRecord record = result.record;
    record.kind = job_.kind(result.record.task);
    record.first_domain = n.first;
    record.domain_count = n.count;
    record.rank = rank;
    record.start = start;
    record.end = end;
    return record;
}

// A finished task's piece kept for its parent, its time learnt, its parent
// readied.
void Scheduler::keep_result(int task, Piece made, double seconds, TaskRecord record) {
    learn(task, size_sent_[static_cast<std::size_t>(task)], seconds);
    if (record.kind == TaskKind::domain)
        for (NodePlacement& placement : placements_) placement.learn_domain_triangles(static_cast<double>(record.triangles_in));
    piece(task) = std::move(made);
    result_.tasks.push_back(record);
    queue_.complete(task);
    ++done_;
}

void Scheduler::on_result(int rank, ResultMessage result, double now) {
    const int task = result.record.task;
    const TaskNode& n = job_.node(task);
    TaskRecord record = completed(result, rank, std::max(0.0, now - result.seconds), now);
    const bool here = rank == 0 && task == here_;
    if (here) {
        here_ = -1;
        piece(n.left).reset();
        piece(n.right).reset();
    } else {
        if (const auto it = placed_.find(rank); it != placed_.end()) {
            const Placed& p = it->second;
            placements_[static_cast<std::size_t>(p.node)].finish(p.grant, result.seconds, record);
            record.wait_seconds = p.sent_at - p.asked_at;
            placed_.erase(it);
        }
        running_.erase(rank);
        batches_.erase(rank);
        end_lends_to(rank);
    }
    keep_result(task, std::move(result.piece), result.seconds, record);
    if (!here) idle_.push_back(rank);
}

// The batch's records lie end to end within its span, each as long as its
// share of the batch's seconds: a device's busy time is the batch's, and no
// rank seems to hold two tasks at once.
void Scheduler::on_batch_result(int rank, std::vector<ResultMessage> results, double now) {
    const auto held = batches_.find(rank);
    const std::vector<int> batch = held != batches_.end() ? held->second : std::vector<int>{};
    bool matches = batch.size() == results.size();
    for (std::size_t i = 0; matches && i < batch.size(); ++i) matches = results[i].record.task == batch[i];
    if (!matches) {
        const auto held_task = running_.find(rank);
        on_failure(rank, !batch.empty() ? batch.front() : held_task != running_.end() ? held_task->second : -1,
                   "answered a batch of " + std::to_string(batch.size()) + " tasks with other results", now);
        return;
    }
    double total = 0;
    for (const ResultMessage& r : results) total += r.seconds;
    std::vector<TaskRecord> records;
    double start = std::max(0.0, now - total);
    for (const ResultMessage& r : results) {
        records.push_back(completed(r, rank, start, std::min(now, start + r.seconds)));
        start = records.back().end;
    }
    if (const auto it = placed_.find(rank); it != placed_.end()) {
        const Placed& p = it->second;
        std::vector<TaskRecord*> shares;
        for (TaskRecord& r : records) {
            r.wait_seconds = p.sent_at - p.asked_at;
            shares.push_back(&r);
        }
        placements_[static_cast<std::size_t>(p.node)].finish(p.grant, total, shares);
        placed_.erase(it);
    }
    running_.erase(rank);
    batches_.erase(rank);
    end_lends_to(rank);
    for (std::size_t i = 0; i < results.size(); ++i)
        keep_result(batch[i], std::move(results[i].piece), results[i].seconds, records[i]);
    idle_.push_back(rank);
}

void Scheduler::on_failure(int rank, int task, const std::string& what, double) {
    fail(task, rank, what);
    if (rank == 0 && task == here_) {
        here_ = -1;
        return;
    }
    if (const auto it = placed_.find(rank); it != placed_.end()) {
        placements_[static_cast<std::size_t>(it->second.node)].manager.cancel(it->second.grant.ticket);
        placed_.erase(it);
    }
    running_.erase(rank);
    batches_.erase(rank);
    end_lends_to(rank);
    idle_.push_back(rank);
}

void Scheduler::on_time(double now) {
    if (failure_ && failure_->unresponsive) return;
    for (const auto& [worker, task] : running_) {
        const double allowed = allowance_of(worker);
        if (now < dispatched_at_[worker] + allowed) continue;
        failure_ = SchedulerFailure{task, worker, "no answer within its deadline", true, allowed};
        return;
    }
}

void Scheduler::on_silent(int worker) {
    failure_ = SchedulerFailure{-1, worker, "no answer to the end of the job", true, setup_.task_timeout};
}

double Scheduler::next_deadline() const {
    double next = std::numeric_limits<double>::infinity();
    for (const auto& [worker, task] : running_) next = std::min(next, dispatched_at_.at(worker) + allowance_of(worker));
    return next;
}

double Scheduler::task_size(int task) const { return size_sent_[static_cast<std::size_t>(task)]; }

void Scheduler::learn(int task, double size, double seconds) {
    const int kind = static_cast<int>(job_.kind(task));
    models_[kind].add(size, seconds);
    longest_[kind] = std::max(longest_[kind], seconds);
}

// The model's prediction for the task's size; while it has too few samples,
// the longest task of the kind so far, or of any kind; 0 before any ended.
double Scheduler::predicted_seconds(int task) const {
    const int kind = static_cast<int>(job_.kind(task));
    if (const auto it = models_.find(kind); it != models_.end())
        if (const auto seconds = it->second.predict(task_size(task))) return std::max(*seconds, 0.0);
    if (const auto it = longest_.find(kind); it != longest_.end()) return it->second;
    double longest = 0;
    for (const auto& [k, seconds] : longest_) longest = std::max(longest, seconds);
    return longest;
}

double Scheduler::allowance(int task) const {
    const double predicted = predicted_seconds(task);
    if (setup_.task_timeout <= 0 || predicted <= 0) return std::numeric_limits<double>::infinity();
    return std::max(setup_.task_timeout, kDeadlineFactor * predicted);
}

double Scheduler::allowance_of(int worker) const {
    const auto batch = batches_.find(worker);
    if (batch == batches_.end()) return allowance(running_.at(worker));
    double predicted = 0;
    for (const int task : batch->second) predicted += predicted_seconds(task);
    if (setup_.task_timeout <= 0 || predicted <= 0) return std::numeric_limits<double>::infinity();
    return std::max(setup_.task_timeout, kDeadlineFactor * predicted);
}

// Lending. Once no task is ready, a worker without work lends its cores to a
// running task (the one with the fewest lends, the latest started among
// equals), which takes them at its next reduction round. The domain tasks'
// times vary with the machine's noise, not with the domain, so the phase's
// end is uneven whatever the order. A lent core comes back when its
// borrower's task ends; a lender given a seam meanwhile shares it for that
// seam's time. A GPU's driver does not lend (a task for its GPU may come at
// any moment), nor borrow for a domain task (it runs on the GPU); a seam it
// runs borrows like any, its passes over the whole pieces run on the host.
void Scheduler::lend_idle_cores(std::vector<SchedulerAction>& actions) {
    for (const int lender : idle_) {
        if (lent_to_[at(lender)] >= 0 || !cores_known_[at(lender)] || drives_gpu(lender)) continue;
        int borrower = -1;
        for (const auto& [worker, task] : running_) {
            if (!cores_known_[at(worker)] || (runs_on_gpu(worker) && job_.kind(task) == TaskKind::domain)) continue;
            if (borrower < 0 || lends_[worker] < lends_[borrower] ||
                (lends_[worker] == lends_[borrower] && dispatched_at_[worker] > dispatched_at_[borrower]))
                borrower = worker;
        }
        if (borrower < 0) return;
        SchedulerAction lend;
        lend.kind = SchedulerAction::Kind::lend_cores;
        lend.worker = borrower;
        lend.lender = lender;
        actions.push_back(std::move(lend));
        lent_to_[at(lender)] = borrower;
        ++lends_[borrower];
    }
}

void Scheduler::end_lends_to(int borrower) {
    for (int& to : lent_to_)
        if (to == borrower) to = -1;
    lends_.erase(borrower);
}

// An idle worker whose cores are not lent out, where there is one.
int Scheduler::take_idle() {
    auto it = std::find_if(idle_.begin(), idle_.end(), [&](int worker) { return lent_to_[at(worker)] < 0; });
    if (it == idle_.end()) it = idle_.begin();
    const int worker = *it;
    idle_.erase(it);
    return worker;
}

// Whether `worker`'s task runs on a GPU (its grant is for one).
bool Scheduler::runs_on_gpu(int worker) const {
    const auto it = placed_.find(worker);
    return it != placed_.end() && placements_[static_cast<std::size_t>(it->second.node)].gpu_of(it->second.grant.device) >= 0;
}

bool Scheduler::drives_gpu(int worker) const { return !driving_.empty() && driving_[at(worker)] >= 0; }

// The rank that drives the GPU of a node's manager device, -1 where none does
// (the CPU, or the GPUs of a node with a lone worker).
int Scheduler::driver_of(int node, int device) const {
    const int gpu = placements_[static_cast<std::size_t>(node)].gpu_of(device);
    const auto it = driver_of_gpu_.find({node, gpu});
    return gpu < 0 || it == driver_of_gpu_.end() ? -1 : it->second;
}

// A node that can take another task: one of its processes is idle and not
// already promised to a grant that waits (a driver to one for its GPU; the
// other workers to those for the CPU). Placing a task only then, not as soon
// as it is ready, keeps each device's queue as short as the predictions make
// it worth, and lets a task's place be decided with the latest models. Nodes
// are served in the order their processes became idle.
int Scheduler::node_with_room() const {
    std::map<int, int> free_workers; // node -> idle workers that drive no GPU, less the grants waiting for one
    std::map<int, int> waiting_for;  // driver -> grants waiting for it
    // An idle worker of a node whose CPU may not take the next task (it waits
    // for its prior) is no room: placing would only queue the task on a GPU
    // whose model is still the guess of its first tasks. Unless a GPU of the
    // node has no driver: the worker runs its grants (a single process).
    const TaskKind next = job_.kind(queue_.peek());
    const auto room_for_next = [&](int node) {
        const NodePlacement& placement = placements_[static_cast<std::size_t>(node)];
        if (placement.cpu_takes(next)) return true;
        for (int d = 1; d < static_cast<int>(placement.manager.devices().size()); ++d)
            if (driver_of(node, d) < 0) return true;
        return false;
    };
    for (const int worker : idle_)
        if (!drives_gpu(worker) && room_for_next(node_of_[at(worker)])) ++free_workers[node_of_[at(worker)]];
    for (const Placed& p : waiting_) {
        if (const int driver = driver_of(p.node, p.grant.device); driver >= 0)
            ++waiting_for[driver];
        else
            --free_workers[p.node];
    }
    for (const int worker : idle_) {
        const bool room = drives_gpu(worker) ? waiting_for[worker] == 0 : free_workers[node_of_[at(worker)]] > 0;
        if (room) return node_of_[at(worker)];
    }
    return -1;
}

// Asks `node`'s manager where and when the next task runs; it waits for that
// grant in waiting_.
void Scheduler::place(int node, double now) {
    const int task = queue_.pop();
    const TaskNode& n = job_.node(task);
    NodePlacement& placement = placements_[static_cast<std::size_t>(node)];
    const Piece* left = n.left >= 0 ? &*piece(n.left) : nullptr;
    const Piece* right = n.right >= 0 ? &*piece(n.right) : nullptr;
    // Seams may go to a GPU's driver once every domain task is placed: until
    // then the GPUs have domains to reduce, which only they and the cores
    // can, and the cores are enough for the seams.
    const bool seams_on_gpus = job_.kind(task) == TaskKind::seam && domains_to_place_ == 0 && !driver_of_gpu_.empty();
    Placed p;
    p.task = task;
    p.node = node;
    // A GPU's batch takes no more than half the GPUs' share of the domains
    // waiting (this one and those ready behind it: after a domain the queue
    // holds only domains): each GPU gets some to the end, and pieces keep
    // coming back for the seams, the batches halving as the queue empties.
    int most_in_batch = 1;
    if (job_.kind(task) == TaskKind::domain && gpu_slots_ > 0) {
        const auto waiting = static_cast<int>(1 + queue_.ready_count());
        most_in_batch = (waiting + 2 * gpu_slots_ - 1) / (2 * gpu_slots_);
    }
    try {
        p.grant = placement.manager.request(placement.request(task, left, right, most_in_batch, seams_on_gpus), now);
    } catch (const Error& e) {
        fail(task, 0, e.what());
        return;
    }
    p.tasks = {task};
    while (static_cast<int>(p.tasks.size()) < p.grant.count && queue_.has_ready()) p.tasks.push_back(queue_.pop());
    for (const int t : p.tasks) domains_to_place_ -= job_.kind(t) == TaskKind::domain;
    p.asked_at = now;
    waiting_.push_back(p);
}

// A GPU's driver idle, no grant waiting for it, takes the grant waiting
// longest ahead on another device of its node, where it would end it
// earlier. The grants were split among the devices by predictions, which
// early in a job can run long for one GPU: its driver then stood idle while
// another GPU worked through a queue of grants (the N = 500, 125-domain job
// on two H200s: one idle for 2.1 s of 5.4 while the other ran eight grants
// booked a second into the job).
void Scheduler::rebalance(double now) {
    for (const int worker : idle_) {
        if (!drives_gpu(worker)) continue;
        const int node = node_of_[at(worker)];
        NodePlacement& placement = placements_[static_cast<std::size_t>(node)];
        int device = -1;
        for (int d = 1; d < static_cast<int>(placement.manager.devices().size()); ++d)
            if (driver_of(node, d) == worker) device = d;
        if (device < 0) continue;
        std::vector<Placed*> others; // the node's grants waiting for another device
        bool has_own = false;
        for (Placed& p : waiting_) {
            if (p.node != node) continue;
            if (p.grant.device == device) has_own = true;
            else others.push_back(&p);
        }
        if (has_own) continue;
        const auto end = [](const Placed* p) { return p->grant.start + p->grant.predicted_seconds; };
        std::stable_sort(others.begin(), others.end(), [&](const Placed* a, const Placed* b) { return end(a) > end(b); });
        for (Placed* p : others)
            if (const std::optional<Grant> moved = placement.manager.move(p->grant.ticket, device, now)) {
                p->grant = *moved;
                break;
            }
    }
}

// The idle rank that runs a grant now: its GPU's driver, or an idle worker of
// its node that drives none (one whose cores are not lent out where there is
// one); -1 while none is idle.
int Scheduler::executor_of(const Placed& p) const {
    if (const int driver = driver_of(p.node, p.grant.device); driver >= 0)
        return std::find(idle_.begin(), idle_.end(), driver) != idle_.end() ? driver : -1;
    int lent = -1;
    for (const int worker : idle_) {
        if (drives_gpu(worker) || node_of_[at(worker)] != p.node) continue;
        if (lent_to_[at(worker)] < 0) return worker;
        if (lent < 0) lent = worker;
    }
    return lent;
}

// Sends the tasks whose grants their devices admit now, in the order they
// were asked for (the manager keeps each device's order).
void Scheduler::start_granted(std::vector<SchedulerAction>& actions, double now) {
    for (auto it = waiting_.begin(); it != waiting_.end();) {
        Placed& p = *it;
        NodePlacement& placement = placements_[static_cast<std::size_t>(p.node)];
        const int worker = executor_of(p);
        if (worker < 0 || !placement.manager.start(p.grant.ticket, now)) {
            ++it;
            continue;
        }
        p.sent_at = now;
        idle_.erase(std::find(idle_.begin(), idle_.end(), worker));
        placed_[worker] = p;
        if (p.tasks.size() > 1)
            send_batch(actions, worker, p.tasks, placement.gpu_of(p.grant.device), now);
        else
            send_task(actions, worker, p.task, placement.gpu_of(p.grant.device), now);
        it = waiting_.erase(it);
    }
}

// After a failure no task is sent: those waiting for a grant give it up.
void Scheduler::cancel_waiting() {
    for (const Placed& p : waiting_) placements_[static_cast<std::size_t>(p.node)].manager.cancel(p.grant.ticket);
    waiting_.clear();
}

// gpu: where a domain task runs, GPU `gpu` of the worker's node or (-1) the
// CPU. The pieces leave with the message: the controller keeps no copy.
void Scheduler::send_task(std::vector<SchedulerAction>& actions, int worker, int task, int gpu, double now) {
    const TaskNode& n = job_.node(task);
    SchedulerAction send;
    send.kind = SchedulerAction::Kind::send_task;
    send.worker = worker;
    send.task = task;
    send.message.task = task;
    send.message.gpu = gpu;
    if (n.left >= 0) {
        size_sent_[static_cast<std::size_t>(task)] =
            static_cast<double>(piece(n.left)->triangle_count() + piece(n.right)->triangle_count());
        send.message.left = std::move(piece(n.left));
        send.message.right = std::move(piece(n.right));
        piece(n.left).reset();
        piece(n.right).reset();
    }
    running_[worker] = task;
    dispatched_at_[worker] = now;
    actions.push_back(std::move(send));
}

void Scheduler::send_batch(std::vector<SchedulerAction>& actions, int worker, const std::vector<int>& tasks, int gpu,
                           double now) {
    SchedulerAction send;
    send.kind = SchedulerAction::Kind::send_batch;
    send.worker = worker;
    send.task = tasks.front();
    send.batch.gpu = gpu;
    send.batch.tasks.assign(tasks.begin(), tasks.end());
    running_[worker] = tasks.front();
    batches_[worker] = tasks;
    dispatched_at_[worker] = now;
    actions.push_back(std::move(send));
}

JobResult Scheduler::take_result(double now) {
    result_.surface = std::move(*pieces_[0]);
    result_.seconds = now;
    return std::move(result_);
}

} // namespace tetiso
