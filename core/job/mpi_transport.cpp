// Messages over MPI and rank 0's transport (mpi_transport.hpp).
#include "mpi_transport.hpp"

#ifdef TETISO_HAVE_MPI

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <thread>

#include "affinity.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

void Backoff::pause() {
    std::this_thread::sleep_for(pause_);
    const auto longest = Clock::now() - start_ < kPatient ? std::chrono::microseconds(kShortPause)
                                                         : std::chrono::microseconds(kLongPause);
    pause_ = std::min(2 * pause_, longest);
}

MessageBytes receive_probed(const MPI_Status& status) {
    int size = 0;
    MPI_Get_count(&status, MPI_BYTE, &size);
    MessageBytes bytes(static_cast<std::size_t>(size));
    MPI_Recv(bytes.data(), size, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return bytes;
}

Clock::time_point deadline_in(double seconds) {
    if (!std::isfinite(seconds) || seconds > 1e9) return Clock::time_point::max();
    return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, seconds)));
}

Sends::~Sends() {
    // A job that ends on an error may leave sends to a rank that stopped
    // answering: their bytes must outlive MPI's use of them, which ends only
    // at MPI_Abort or MPI_Finalize, so those are kept to the end.
    if (wait(deadline_in(1.0))) return;
    static auto* kept = new std::deque<MessageBytes>;
    for (InFlight& s : in_flight_) {
        MPI_Request_free(&s.request);
        kept->push_back(std::move(s.bytes));
    }
}

void Sends::send(MessageBytes bytes, int to, int tag) {
    if (bytes.size() > static_cast<std::size_t>(INT32_MAX)) throw Error("message over 2 GiB between MPI ranks");
    in_flight_.push_back(InFlight{std::move(bytes), MPI_REQUEST_NULL, Clock::now()});
    InFlight& s = in_flight_.back();
    MPI_Isend(s.bytes.data(), static_cast<int>(s.bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD, &s.request);
}

bool Sends::progress() {
    for (auto it = in_flight_.begin(); it != in_flight_.end();) {
        int done = 0;
        MPI_Test(&it->request, &done, MPI_STATUS_IGNORE);
        it = done ? in_flight_.erase(it) : std::next(it);
    }
    return in_flight_.empty();
}

bool Sends::moving() const {
    const Clock::time_point now = Clock::now();
    return std::any_of(in_flight_.begin(), in_flight_.end(), [&](const InFlight& s) { return now - s.posted < kMoving; });
}

bool Sends::wait(Clock::time_point deadline) {
    Backoff backoff;
    while (!progress()) {
        if (Clock::now() >= deadline) return false;
        backoff.pause_unless_moving(moving());
    }
    return true;
}

MpiTransport::MpiTransport(int ranks, double task_timeout)
    : ranks_(ranks), task_timeout_(task_timeout), patience_(task_timeout), start_(Clock::now()), last_heartbeat_(start_),
      greeted_(static_cast<std::size_t>(ranks), false), worker_cores_(static_cast<std::size_t>(ranks)) {}

double MpiTransport::clock() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

void MpiTransport::send_task(int worker, TaskMessage message) {
    MessageBytes bytes = encode(message);
    message = TaskMessage{}; // the pieces are in the bytes now
    sends_.send(std::move(bytes), worker, kTask);
}

void MpiTransport::send_batch(int worker, BatchMessage message) { sends_.send(encode(message), worker, kBatch); }

void MpiTransport::lend_cores(int borrower, int lender) {
    sends_.send(encode(LendMessage{worker_cores_[static_cast<std::size_t>(lender)]}), borrower, kLend);
}

bool MpiTransport::job_cores(cpu_set_t& cores) const {
    if (!current_cores(cores)) return false;
    for (const MessageBytes& bytes : worker_cores_) {
        cpu_set_t theirs;
        if (cores_from_bytes(bytes, theirs)) CPU_OR(&cores, &cores, &theirs);
    }
    return true;
}

// Each worker waiting on rank 0 expects a message within `seconds`.
void MpiTransport::heartbeat(double seconds) {
    if (task_timeout_ <= 0 || stopped_) return;
    for (int worker = 1; worker < ranks_; ++worker) sends_.send(encode(HeartbeatMessage{seconds}), worker, kHeartbeat);
    last_heartbeat_ = Clock::now();
}

// Four heartbeats in each worker's patience: a late one is not yet silence.
void MpiTransport::heartbeat_if_due() {
    if (task_timeout_ > 0 && Clock::now() - last_heartbeat_ > std::chrono::duration<double>(task_timeout_ / 4))
        heartbeat(patience_);
}

bool MpiTransport::between_polls() {
    heartbeat_if_due();
    sends_.progress();
    return sends_.moving();
}

void MpiTransport::busy_for(double seconds) {
    patience_ = seconds + task_timeout_;
    heartbeat(patience_);
}

std::optional<WorkerEvent> MpiTransport::receive(double deadline) {
    patience_ = task_timeout_; // listening again
    heartbeat_if_due();         // also when reports keep coming and the wait never pauses
    MPI_Status status;
    const bool arrived =
        wait_for_message(MPI_ANY_SOURCE, status, deadline_in(deadline - clock()), [this] { return between_polls(); });
    if (!arrived) return std::nullopt;
    const MessageBytes message = receive_probed(status);
    WorkerEvent event;
    event.worker = status.MPI_SOURCE;
    greeted_[static_cast<std::size_t>(event.worker)] = true;
    switch (status.MPI_TAG) {
    case kResult:
        event.kind = WorkerEvent::Kind::result;
        event.result = decode_result(message);
        break;
    case kBatchResult:
        event.kind = WorkerEvent::Kind::batch_result;
        event.batch = decode_batch_result(message);
        break;
    case kFailure:
        event.kind = WorkerEvent::Kind::failure;
        event.failure = decode_failure(message);
        break;
    default: {
        event.kind = WorkerEvent::Kind::ready;
        ReadyMessage ready = decode_ready(message);
        cpu_set_t cores;
        event.cores_known = cores_from_bytes(ready.cores, cores);
        if (event.cores_known) worker_cores_[static_cast<std::size_t>(event.worker)] = std::move(ready.cores);
    }
    }
    return event;
}

// Every worker's first "ready" is received before it is told to stop, so no
// message is left unmatched at MPI_Finalize; heartbeats stop before the stop
// goes out, which the workers read after them. Each worker answers the stop:
// one that does not, within the deadlines' floor, stopped answering while it
// held no task, and MPI_Finalize would wait for it for ever.
int MpiTransport::stop(bool failed) {
    // A worker not ready yet may still be preparing its GPU: it gets ten
    // floors.
    const Clock::time_point ready_by = task_timeout_ > 0 ? deadline_in(10 * task_timeout_) : Clock::time_point::max();
    for (int worker = 1; worker < ranks_; ++worker)
        if (!greeted_[static_cast<std::size_t>(worker)]) {
            MPI_Status status;
            const bool ready = wait_for_message(worker, status, ready_by, [this] { return between_polls(); });
            if (!ready) return worker;
            receive_probed(status);
        }
    stopped_ = true;
    for (int worker = 1; worker < ranks_; ++worker) sends_.send(encode(StopMessage{failed}), worker, kStop);
    const Clock::time_point deadline = task_timeout_ > 0 ? deadline_in(task_timeout_) : Clock::time_point::max();
    for (int worker = 1; worker < ranks_; ++worker) {
        MPI_Status status;
        Backoff backoff;
        for (int arrived = 0;;) {
            MPI_Iprobe(worker, kStopped, MPI_COMM_WORLD, &arrived, &status);
            if (arrived) break;
            sends_.progress();
            if (Clock::now() >= deadline) return worker;
            backoff.pause();
        }
        receive_probed(status);
    }
    sends_.wait(Clock::time_point::max());
    return -1;
}

} // namespace tetiso

#endif
