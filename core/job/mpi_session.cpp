// MPI for the lifetime of a job's process (schedule.hpp's MpiSession).
#include "tetiso/schedule.hpp"

#include <cstdlib>

#ifdef TETISO_HAVE_MPI

#include <mpi.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <thread>

#include "tetiso/error.hpp"

namespace tetiso {

MpiSession::MpiSession() {
    if (!launched_with_mpi()) return;
    int provided = 0;
    // Tasks may use OpenMP threads, but only the main thread calls MPI.
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    active_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    // MPI_Init returns on a rank whose transport failed (Open MPI warns that
    // an mmap of its shared memory failed, and goes on); its messages then
    // never arrive and every rank waits in the first collective. A barrier
    // right after start-up, before any rank does work of its own, completes
    // within moments when all is well; one that does not is that failure.
    MPI_Request started;
    MPI_Ibarrier(MPI_COMM_WORLD, &started);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kMpiStartSeconds);
    for (int done = 0;;) {
        MPI_Test(&started, &done, MPI_STATUS_IGNORE);
        if (done) break;
        if (std::chrono::steady_clock::now() > deadline) {
            if (rank_ == 0)
                std::fprintf(stderr,
                             "tetiso: the %d MPI ranks could not all reach each other within %d s of start-up "
                             "(a rank's MPI transport failed to start: see the launcher's messages); the job is "
                             "stopped\n",
                             size_, kMpiStartSeconds);
            MPI_Abort(MPI_COMM_WORLD, 2);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

MpiSession::~MpiSession() {
    if (active_) MPI_Finalize();
}

bool MpiSession::broadcast(bool value) const {
    if (!active_) return value;
    int flag = value ? 1 : 0;
    MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return flag != 0;
}

bool MpiSession::all(bool value) const {
    if (!active_) return value;
    int flag = value ? 1 : 0, every = 0;
    MPI_Allreduce(&flag, &every, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    return every != 0;
}

std::vector<std::string> MpiSession::all_gather(const std::string& mine) const {
    if (!active_ || size_ == 1) return {mine};
    // Sizes first, -1 for a share too large for MPI's int counts: every rank
    // then refuses together instead of some waiting for the rest.
    const long long size = mine.size() < static_cast<std::size_t>(std::numeric_limits<int>::max()) ? static_cast<long long>(mine.size()) : -1;
    std::vector<long long> sizes(static_cast<std::size_t>(size_));
    MPI_Allgather(&size, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    long long total = 0;
    for (const long long s : sizes) {
        if (s < 0 || total + s >= std::numeric_limits<int>::max())
            throw Error("the ranks' shares of a .pvtu's scan exceed 2 GB: use fewer pieces per job or split it once with `tetiso split`");
        total += s;
    }
    std::vector<int> counts(sizes.begin(), sizes.end()), offsets(static_cast<std::size_t>(size_), 0);
    for (int r = 1; r < size_; ++r) offsets[static_cast<std::size_t>(r)] = offsets[static_cast<std::size_t>(r - 1)] + counts[static_cast<std::size_t>(r - 1)];
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_CHAR, all.data(), counts.data(), offsets.data(), MPI_CHAR,
                   MPI_COMM_WORLD);
    std::vector<std::string> shares;
    for (int r = 0; r < size_; ++r)
        shares.emplace_back(all, static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                            static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]));
    return shares;
}

RankGroup MpiSession::group() const {
    RankGroup group;
    group.rank = rank_;
    group.size = size_;
    if (active_ && size_ > 1) group.all_gather = [this](const std::string& mine) { return all_gather(mine); };
    return group;
}

} // namespace tetiso

#else

namespace tetiso {
MpiSession::MpiSession() = default;
MpiSession::~MpiSession() = default;
bool MpiSession::broadcast(bool value) const { return value; }
bool MpiSession::all(bool value) const { return value; }
std::vector<std::string> MpiSession::all_gather(const std::string& mine) const { return {mine}; }
RankGroup MpiSession::group() const { return {}; }
} // namespace tetiso

#endif

namespace tetiso {

bool launched_with_mpi() {
#ifdef TETISO_HAVE_MPI
    for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
        if (std::getenv(variable)) return true;
#endif
    return false;
}

} // namespace tetiso
