// A worker rank of the MPI job: says it is ready, runs the tasks rank 0
// sends, with the cores idle workers lend it, and returns each piece, until
// rank 0 says stop. It watches rank 0 meanwhile: when no message comes from
// it within the patience its last heartbeat asked for (mpi_transport.hpp),
// rank 0 stopped answering, and the worker ends the job.
#pragma once

#include "tetiso/schedule.hpp"

namespace tetiso {

// driven_gpu: the GPU this worker drives (-1 for none), made ready before it
// says it is ready: its first task there then takes what its next ones take.
// Throws JobStopped when the job ended on a failure.
void work(const Job& job, int driven_gpu);

} // namespace tetiso
