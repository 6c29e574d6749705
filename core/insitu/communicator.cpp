// The in-situ call's collectives (communicator.hpp).
#include "communicator.hpp"

#include <cstdint>
#include <limits>

#include "tetiso/error.hpp"

namespace tetiso::insitu {

std::vector<std::string> all_gather(MPI_Comm comm, const std::string& mine) {
    int size = 0;
    MPI_Comm_size(comm, &size);
    const std::uint64_t length = mine.size();
    std::vector<std::uint64_t> lengths(static_cast<std::size_t>(size));
    MPI_Allgather(&length, 1, MPI_UINT64_T, lengths.data(), 1, MPI_UINT64_T, comm);
    std::vector<int> counts(static_cast<std::size_t>(size)), displacements(static_cast<std::size_t>(size));
    std::uint64_t total = 0;
    for (int r = 0; r < size; ++r) {
        const std::uint64_t n = lengths[static_cast<std::size_t>(r)];
        if (n >= static_cast<std::uint64_t>(std::numeric_limits<int>::max()) ||
            total + n >= static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
            throw Error("rank " + std::to_string(r) + ": its share of an exchange between ranks is 2 GB or more");
        counts[static_cast<std::size_t>(r)] = static_cast<int>(n);
        displacements[static_cast<std::size_t>(r)] = static_cast<int>(total);
        total += n;
    }
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_CHAR, all.data(), counts.data(), displacements.data(),
                   MPI_CHAR, comm);
    std::vector<std::string> shares;
    for (int r = 0; r < size; ++r)
        shares.push_back(all.substr(static_cast<std::size_t>(displacements[static_cast<std::size_t>(r)]),
                                    static_cast<std::size_t>(counts[static_cast<std::size_t>(r)])));
    return shares;
}

void agree(MPI_Comm comm, const std::string& problem) {
    int failed = problem.empty() ? 0 : 1, any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    if (!any) return;
    const std::vector<std::string> problems = all_gather(comm, problem);
    for (std::size_t r = 0; r < problems.size(); ++r)
        if (!problems[r].empty()) throw Error("rank " + std::to_string(r) + ": " + problems[r]);
}

} // namespace tetiso::insitu
