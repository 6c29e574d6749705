// The single-process run: the scheduler over the in-process transport
// (local_transport.hpp).
#include "local_transport.hpp"

#include <new>

#include "tetiso/error.hpp"
#include "tetiso/device.hpp"

namespace tetiso {

LocalTransport::LocalTransport(const Job& job, bool placed)
    : job_(job), placed_(placed), start_(std::chrono::steady_clock::now()) {
    WorkerEvent ready;
    ready.kind = WorkerEvent::Kind::ready;
    ready.worker = 0;
    events_.push_back(std::move(ready));
}

double LocalTransport::clock() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void LocalTransport::send_task(int worker, TaskMessage message) {
    WorkerEvent event;
    event.worker = worker;
    TaskRecord record;
    TaskThreads threads{job_.config().threads, {}, {}};
    if (placed_) threads.gpu = message.gpu;
    const double started = clock();
    try {
        Piece piece = job_.execute(message.task, message.left ? &*message.left : nullptr,
                                   message.right ? &*message.right : nullptr, record, threads);
        message.left.reset();
        message.right.reset();
        event.kind = WorkerEvent::Kind::result;
        event.result = result_message(record, clock() - started, record.threads, std::move(piece));
    } catch (const Error& e) {
        event.kind = WorkerEvent::Kind::failure;
        event.failure = FailureMessage{message.task, e.what()};
    } catch (const std::bad_alloc&) {
        event.kind = WorkerEvent::Kind::failure;
        event.failure = FailureMessage{message.task, "out of memory"};
    }
    events_.push_back(std::move(event));
}

void LocalTransport::send_batch(int worker, BatchMessage message) {
    WorkerEvent event;
    event.worker = worker;
    TaskThreads threads{job_.config().threads, {}, message.gpu};
    const double started = clock();
    try {
        std::vector<TaskRecord> records;
        std::vector<Piece> pieces =
            job_.execute_batch(std::vector<int>(message.tasks.begin(), message.tasks.end()), records, threads);
        event.kind = WorkerEvent::Kind::batch_result;
        event.batch = batch_result_message(records, clock() - started, threads.count, std::move(pieces));
    } catch (const BatchTaskError& e) {
        event.kind = WorkerEvent::Kind::failure;
        event.failure = FailureMessage{e.task, e.what()};
    } catch (const std::bad_alloc&) {
        event.kind = WorkerEvent::Kind::failure;
        event.failure = FailureMessage{message.tasks.empty() ? -1 : message.tasks.front(), "out of memory"};
    }
    events_.push_back(std::move(event));
}

std::optional<WorkerEvent> LocalTransport::receive(double) {
    if (events_.empty()) throw Error("the single-process job waits for a report that cannot come");
    WorkerEvent event = std::move(events_.front());
    events_.pop_front();
    return event;
}

JobResult run_local(const Job& job, const Progress& progress) {
    SchedulerSetup setup;
    if (job.config().device != JobConfig::Device::cpu) {
        const std::vector<int> gpus = NodePlacement::usable_gpus(job.config(), gpu_count());
        setup.nodes = single_process_layout(gpus, gpus.empty() ? 0.0 : gpu_memory_mib(gpus.front()));
        if (job.config().device == JobConfig::Device::automatic && !gpus.empty())
            setup.cpu_seconds_per_triangle = job.probe_cpu();
    }
    Scheduler scheduler(job, setup);
    LocalTransport transport(job, scheduler.places_tasks());
    DriveHooks hooks;
    hooks.progress = progress;
    std::optional<JobResult> result = drive(job, scheduler, transport, hooks);
    if (!result) {
        const SchedulerFailure& failure = *scheduler.failure();
        throw Error("task '" + job.describe(failure.task) + "' failed: " + failure.what);
    }
    return std::move(*result);
}

} // namespace tetiso
