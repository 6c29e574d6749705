// The messages between the job's controller and its workers, one struct
// each, and their codec on ByteWriter/ByteReader (byte_buffer.hpp): every
// message is encoded by one function and decoded by one, so that the two
// sides cannot disagree on a field's place. The transports carry the bytes
// (mpi_transport.hpp) or the structs themselves (local_transport.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tetiso/schedule.hpp"

namespace tetiso {

using MessageBytes = std::vector<std::byte>;

// Worker -> controller, once, before its first task: the cores the
// launcher bound it to (a cpu_set_t's bytes, affinity.hpp), which the
// controller lends to other workers' tasks; empty where they are not known.
struct ReadyMessage {
    MessageBytes cores;
};

// Controller -> worker: run `task`, a domain task on GPU `gpu` of the
// worker's node (-1: the CPU), or a seam of the two pieces.
struct TaskMessage {
    std::int32_t task = 0;
    std::int32_t gpu = -1;
    std::optional<Piece> left, right;
};

// Worker -> controller: a finished task, what it measured and its piece.
struct ResultMessage {
    double seconds = 0; // the task's time on the worker
    // What the worker measured: the task, its threads, sizes, stages and
    // field range (the controller adds where and when it ran).
    TaskRecord record;
    Piece piece;
};

// Controller -> worker: run these domain tasks together on GPU `gpu` of the
// worker's node (a GPU grant's batch, Job::execute_batch).
struct BatchMessage {
    std::int32_t gpu = -1;
    std::vector<std::int32_t> tasks;
};

// Worker -> controller: a finished batch, one result per task in the
// batch's order, each with its share of the batch's seconds.
struct BatchResultMessage {
    std::vector<ResultMessage> results;
};

// Worker -> controller: a task that threw (of a batch: the one that fails).
struct FailureMessage {
    std::int32_t task = 0;
    std::string what;
};

// Controller -> worker: lent cores for the task it runs (a cpu_set_t's bytes).
struct LendMessage {
    MessageBytes cores;
};

// Controller -> worker: the job is over; `failed` when it ended on an error.
struct StopMessage {
    bool failed = false;
};

// Controller -> worker: the controller is alive; the next message from it
// comes within `seconds`, or it has stopped answering.
struct HeartbeatMessage {
    double seconds = 0;
};

MessageBytes encode(const ReadyMessage& message);
MessageBytes encode(const TaskMessage& message);
MessageBytes encode(const ResultMessage& message);
MessageBytes encode(const BatchMessage& message);
MessageBytes encode(const BatchResultMessage& message);
MessageBytes encode(const FailureMessage& message);
MessageBytes encode(const LendMessage& message);
MessageBytes encode(const StopMessage& message);
MessageBytes encode(const HeartbeatMessage& message);

// Each throws tetiso::Error on bytes that end early.
ReadyMessage decode_ready(const MessageBytes& bytes);
TaskMessage decode_task(const MessageBytes& bytes);
ResultMessage decode_result(const MessageBytes& bytes);
BatchMessage decode_batch(const MessageBytes& bytes);
BatchResultMessage decode_batch_result(const MessageBytes& bytes);
FailureMessage decode_failure(const MessageBytes& bytes);
LendMessage decode_lend(const MessageBytes& bytes);
StopMessage decode_stop(const MessageBytes& bytes);
HeartbeatMessage decode_heartbeat(const MessageBytes& bytes);

} // namespace tetiso
