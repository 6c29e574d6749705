// Messages between ranks over MPI (messages.hpp gives their bytes), and the
// controller's transport on rank 0. Every send is non-blocking and every wait
// polls with a growing pause, so that no rank holds a core while it waits
// (Open MPI's blocking calls poll at full speed) and none blocks for ever on
// a rank that stopped answering: rank 0 gives each task a deadline
// (scheduler.hpp), and sends the workers waiting on it a heartbeat, by which
// they notice when it stops.
#pragma once

#ifdef TETISO_HAVE_MPI

#include <mpi.h>
#include <sched.h>

#include <chrono>
#include <deque>
#include <limits>
#include <thread>
#include <vector>

#include "transport.hpp"

namespace tetiso {

// kStopped: a worker's answer to kStop, an empty message.
enum MessageTag : int {
    kReady = 1,
    kTask = 2,
    kResult = 3,
    kFailure = 4,
    kStop = 5,
    kLend = 6,
    kHeartbeat = 7,
    kStopped = 8,
    kBatch = 9,
    kBatchResult = 10,
};

// A wait's pause between polls: short at first, so that a message arriving
// soon costs at most kShortPause of latency (tasks take 10^-2 to 1 s), and
// long once the wait has lasted kPatient, when nothing is coming soon.
class Backoff {
public:
    void pause();
    // Between polls while this rank's sends are moving (Sends::moving): no
    // pause, the core only yielded; otherwise pause().
    void pause_unless_moving(bool moving) {
        if (moving)
            std::this_thread::yield();
        else
            pause();
    }

private:
    static constexpr auto kShortPause = std::chrono::microseconds(500);
    static constexpr auto kLongPause = std::chrono::milliseconds(20);
    static constexpr auto kPatient = std::chrono::seconds(1);
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    std::chrono::microseconds pause_{5};
};

using Clock = std::chrono::steady_clock;

// Waits for the next message from `from` (or MPI_ANY_SOURCE) until
// `deadline`; false when it passed first. `meanwhile` runs between polls and
// says whether sends of this rank are moving (Sends::moving): then it polls
// again at once, only yielding its core.
template <class Meanwhile>
bool wait_for_message(int from, MPI_Status& status, Clock::time_point deadline, Meanwhile meanwhile) {
    Backoff backoff;
    for (;;) {
        int arrived = 0;
        MPI_Iprobe(from, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status);
        if (arrived) return true;
        if (Clock::now() >= deadline) return false;
        backoff.pause_unless_moving(meanwhile());
    }
}

// Receives the message a probe found, whatever its size.
MessageBytes receive_probed(const MPI_Status& status);

// Sends in flight, each with its bytes, kept until MPI is done with them.
class Sends {
public:
    ~Sends();
    void send(MessageBytes bytes, int to, int tag);
    // Frees the bytes of the sends that completed; true when none is left.
    bool progress();
    // Whether a send in flight was posted less than kMoving ago. A large
    // message moves only while its sender calls MPI (where the ranks cannot
    // read each other's memory, Open MPI's shared memory copies it through
    // fragments that the sender's progress pushes): polled every half
    // millisecond, the pieces of a GPU's grant, 30 MB, took a tenth of a
    // second to reach rank 0. So a rank with such a send polls at once; past
    // kMoving the receiver is taken to be busy, or stopped, and polling it
    // so often would only take the core from ranks that share it.
    bool moving() const;
    // Waits until every send completed or `deadline` passed; true if all did.
    bool wait(Clock::time_point deadline);

private:
    static constexpr auto kMoving = std::chrono::milliseconds(100);
    struct InFlight {
        MessageBytes bytes;
        MPI_Request request;
        Clock::time_point posted;
    };
    std::deque<InFlight> in_flight_;
};

// Seconds from now as a deadline (infinity: never).
Clock::time_point deadline_in(double seconds);

// Rank 0's transport: tasks, lends and the stop to the workers, heartbeats
// to them while rank 0 waits, their reports back.
class MpiTransport : public Transport {
public:
    // task_timeout: the deadlines' floor (0: none, and no heartbeat).
    MpiTransport(int ranks, double task_timeout);
    void send_task(int worker, TaskMessage message) override;
    void send_batch(int worker, BatchMessage message) override;
    void lend_cores(int borrower, int lender) override;
    std::optional<WorkerEvent> receive(double deadline) override;
    void busy_for(double seconds) override;
    double clock() const override;
    int stop(bool failed) override;

    // The union of rank 0's cores and every ready worker's; false where rank
    // 0's are not known.
    bool job_cores(cpu_set_t& cores) const;

    // A heartbeat if one is due, from a task rank 0 runs (between its
    // reduction rounds): the workers keep the patience busy_for() asked.
    void keep_alive() { heartbeat_if_due(); }

private:
    void heartbeat(double seconds);
    void heartbeat_if_due();
    // What rank 0 does between polls for a message: heartbeats, its sends
    // progressed; whether they are moving (wait_for_message).
    bool between_polls();

    int ranks_;
    double task_timeout_;
    double patience_; // what the heartbeats ask of the workers now
    Clock::time_point start_;
    Clock::time_point last_heartbeat_;
    Sends sends_;
    std::vector<bool> greeted_;
    std::vector<MessageBytes> worker_cores_; // by rank, from its ready message
    bool stopped_ = false;
};

} // namespace tetiso

#endif
