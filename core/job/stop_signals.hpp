// What rank 0 says when the job is stopped from outside. A worker killed by
// SIGKILL (by hand, or by the kernel out of memory) says nothing, and the
// launcher names only its rank and the signal before it sends SIGTERM to
// every other rank: rank 0, which knows which task each rank held, says so
// on its way out. The line is rebuilt whenever a task starts or ends and
// written from the signal handler with write(2), which is all a handler may
// use: two buffers, the one in use switched atomically.
#pragma once

#include <signal.h>

#include <atomic>
#include <cstddef>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "tetiso/schedule.hpp"

namespace tetiso {

class TasksInFlight {
public:
    TasksInFlight();
    ~TasksInFlight() { disarm(); }
    TasksInFlight(const TasksInFlight&) = delete;
    TasksInFlight& operator=(const TasksInFlight&) = delete;

    // running: rank -> the task it holds, of `ranks` ranks; batches: rank
    // -> the batch it runs, where it runs one (its first task is running's).
    void update(const Job& job, const std::map<int, int>& running, int ranks,
                const std::map<int, std::vector<int>>& batches = {});
    // The signals' previous handlers back: for a job that ends itself by
    // other means (MPI_Abort, having said why).
    void disarm();

private:
    static constexpr int kSignals[] = {SIGTERM, SIGINT, SIGHUP};
    static constexpr std::size_t kLength = 4096;
    static std::size_t index_of(int signal);
    void set(const std::string& held);
    static void on_signal(int signal);

    static inline char lines_[2][kLength];
    static inline std::size_t lengths_[2];
    static inline std::atomic<int> current_{0};
    struct sigaction previous_[std::size(kSignals)];
    bool armed_ = false;
};

} // namespace tetiso
