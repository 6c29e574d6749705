// Internal: what the in-situ call needs of MPI on the session's own
// communicator: every rank's bytes on every rank, and one failure agreed by
// all, so that a rank with bad input or a failed task never leaves the
// others waiting and every rank throws the same message.
#pragma once

#include <mpi.h>

#include <string>
#include <vector>

namespace tetiso::insitu {

// Every rank's `mine`, in rank order, on every rank. Throws tetiso::Error
// on every rank where a share is 2 GB or more (MPI's int counts).
std::vector<std::string> all_gather(MPI_Comm comm, const std::string& mine);

// Collective: where any rank's `problem` is not empty, throws tetiso::Error
// on every rank with the lowest such rank's, prefixed "rank R: ".
void agree(MPI_Comm comm, const std::string& problem);

} // namespace tetiso::insitu
