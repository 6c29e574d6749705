// The controller's loop: the scheduler's actions carried out over a
// transport, and the workers' reports fed back to it (transport.hpp).
#include <new>

#include "transport.hpp"

namespace tetiso {

std::optional<JobResult> drive(const Job& job, Scheduler& scheduler, Transport& transport, const DriveHooks& hooks) {
    const auto report_running = [&](const std::map<int, int>& running) {
        if (hooks.on_running) hooks.on_running(running);
    };
    const auto report_progress = [&] {
        if (hooks.progress) hooks.progress(scheduler.tasks_done(), job.task_count(), transport.clock());
    };
    for (;;) {
        bool ran_here = false, sent = false;
        for (SchedulerAction& action : scheduler.decide(transport.clock())) {
            switch (action.kind) {
            case SchedulerAction::Kind::send_task:
                transport.send_task(action.worker, std::move(action.message));
                sent = true;
                break;
            case SchedulerAction::Kind::send_batch:
                transport.send_batch(action.worker, std::move(action.batch));
                sent = true;
                break;
            case SchedulerAction::Kind::lend_cores:
                transport.lend_cores(action.worker, action.lender);
                break;
            case SchedulerAction::Kind::run_here: {
                ran_here = true;
                report_running({{0, action.task}});
                transport.busy_for(scheduler.allowance(action.task));
                try {
                    ResultMessage result = hooks.run_here(action.task, scheduler.input(action.task, false),
                                                          scheduler.input(action.task, true));
                    scheduler.on_result(0, std::move(result), transport.clock());
                    report_progress();
                } catch (const std::exception& e) {
                    const std::string what = dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what();
                    scheduler.on_failure(0, action.task, what, transport.clock());
                }
                report_running(scheduler.running());
                break;
            }
            }
        }
        if (sent) report_running(scheduler.running());
        if (ran_here) continue;
        if (scheduler.done()) break;
        std::optional<WorkerEvent> event;
        while (!(event = transport.receive(scheduler.next_deadline()))) {
            scheduler.on_time(transport.clock());
            if (scheduler.failure() && scheduler.failure()->unresponsive) return std::nullopt;
        }
        switch (event->kind) {
        case WorkerEvent::Kind::ready:
            scheduler.on_ready(event->worker, event->cores_known, transport.clock());
            break;
        case WorkerEvent::Kind::result:
            scheduler.on_result(event->worker, std::move(event->result), transport.clock());
            report_running(scheduler.running());
            report_progress();
            break;
        case WorkerEvent::Kind::batch_result:
            scheduler.on_batch_result(event->worker, std::move(event->batch.results), transport.clock());
            report_running(scheduler.running());
            report_progress();
            break;
        case WorkerEvent::Kind::failure:
            scheduler.on_failure(event->worker, event->failure.task, event->failure.what, transport.clock());
            report_running(scheduler.running());
            break;
        }
    }
    if (const int silent = transport.stop(scheduler.failure().has_value()); silent >= 0)
        scheduler.on_silent(silent);
    if (scheduler.failure()) return std::nullopt;
    return scheduler.take_result(transport.clock());
}

} // namespace tetiso
