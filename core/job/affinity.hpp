// The cores a process runs on (the launcher's binding), and moving a
// process's threads onto others: how idle workers lend their cores to a
// running task, and how the controller runs the last seams on every rank's
// cores (scheduler.hpp).
#pragma once

#include <sched.h>

#include "messages.hpp"

namespace tetiso {

// The cores the calling thread may run on; false where that is not known.
bool current_cores(cpu_set_t& cores);

// current_cores() as message bytes, empty where not known.
MessageBytes cores_bytes();

// Bytes from cores_bytes() back into a set; false unless they are one.
bool cores_from_bytes(const MessageBytes& bytes, cpu_set_t& cores);

// Moves this process's calling thread and the first `threads` OpenMP threads
// onto `cores`: a thread OpenMP made earlier keeps the cores it was made on.
void run_on(const cpu_set_t& cores, int threads);

} // namespace tetiso
