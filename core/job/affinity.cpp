// Cores and the threads on them (affinity.hpp).
#include "affinity.hpp"

#include <cstring>

namespace tetiso {

bool current_cores(cpu_set_t& cores) {
    CPU_ZERO(&cores);
    return sched_getaffinity(0, sizeof cores, &cores) == 0;
}

MessageBytes cores_bytes() {
    cpu_set_t cores;
    if (!current_cores(cores)) return {};
    MessageBytes bytes(sizeof cores);
    std::memcpy(bytes.data(), &cores, sizeof cores);
    return bytes;
}

bool cores_from_bytes(const MessageBytes& bytes, cpu_set_t& cores) {
    if (bytes.size() != sizeof cores) return false;
    std::memcpy(&cores, bytes.data(), sizeof cores);
    return true;
}

void run_on(const cpu_set_t& cores, int threads) {
    sched_setaffinity(0, sizeof cores, &cores);
#ifdef _OPENMP
#pragma omp parallel num_threads(threads)
    sched_setaffinity(0, sizeof cores, &cores);
#else
    (void)threads;
#endif
}

} // namespace tetiso
