// Rank 0's last word on a job stopped from outside (stop_signals.hpp).
#include "stop_signals.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstring>

namespace tetiso {

TasksInFlight::TasksInFlight() {
    set("no task had started");
    struct sigaction action {};
    action.sa_handler = &TasksInFlight::on_signal;
    sigemptyset(&action.sa_mask);
    for (const int signal : kSignals) sigaction(signal, &action, &previous_[index_of(signal)]);
    armed_ = true;
}

void TasksInFlight::disarm() {
    if (!armed_) return;
    for (const int signal : kSignals) sigaction(signal, &previous_[index_of(signal)], nullptr);
    armed_ = false;
}

std::size_t TasksInFlight::index_of(int signal) {
    return static_cast<std::size_t>(std::find(std::begin(kSignals), std::end(kSignals), signal) - std::begin(kSignals));
}

void TasksInFlight::update(const Job& job, const std::map<int, int>& running, int ranks,
                           const std::map<int, std::vector<int>>& batches) {
    std::string held;
    for (int rank = 0; rank < ranks; ++rank) {
        const auto it = running.find(rank);
        if (rank == 0 && it == running.end()) continue; // rank 0 is the one speaking
        const auto batch = batches.find(rank);
        const std::string more = batch == batches.end() || batch->second.size() < 2 ? std::string()
                                 : " and " + std::to_string(batch->second.size() - 1) + " more of its batch";
        held += std::string(held.empty() ? "" : ", ") + "rank " + std::to_string(rank) +
                (it == running.end() ? " held no task" : " held task '" + job.describe(it->second) + "'" + more);
    }
    set(held);
}

void TasksInFlight::set(const std::string& held) {
    const std::string line = "tetiso: the job was stopped from outside (a rank was killed or ran out of memory, "
                             "or the launcher was interrupted) while " + held + "\n";
    const int next = 1 - current_.load();
    const std::size_t n = std::min(line.size(), kLength);
    std::memcpy(lines_[next], line.data(), n);
    if (n == kLength) lines_[next][kLength - 1] = '\n';
    lengths_[next] = n;
    current_.store(next);
}

void TasksInFlight::on_signal(int signal) {
    const int at = current_.load();
    const ssize_t written = ::write(STDERR_FILENO, lines_[at], lengths_[at]);
    (void)written;
    ::signal(signal, SIG_DFL);
    ::raise(signal);
}

} // namespace tetiso
