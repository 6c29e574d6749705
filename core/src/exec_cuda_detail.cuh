// What CudaExec's members (exec_cuda.cuh) launch and keep besides CUB: the
// operators they hand CUB, the kernels of their own loops (the tests' loop
// held to the tests' registers, the cooperative loop of steps), and the
// profile of TETISO_GPU_PROFILE.
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <cooperative_groups.h>

#include "cuda_support.cuh"

namespace tetiso {

namespace cuda_exec {

// CUB calls a select operator with the element, here an index.
template <class Keep>
struct IndexPredicate {
    Keep keep;
    __host__ __device__ bool operator()(std::int64_t i) const { return keep(i); }
};

// An index's count, 1 or 0, for a sum.
template <class Counted>
struct IndexCount {
    Counted counted;
    __host__ __device__ std::int64_t operator()(std::int64_t i) const { return counted(i) ? 1 : 0; }
};

// for_each_of_kernel for the legality tests: the registers of
// for_each_heavy_kernel.
template <class Function>
__global__ void __launch_bounds__(cuda::kBlock, 3)
    for_each_of_heavy_kernel(const std::int64_t* n, std::int64_t min_n, Function function) {
    const std::int64_t count = *n > min_n ? *n : min_n;
    for (std::int64_t i = blockIdx.x * static_cast<std::int64_t>(blockDim.x) + threadIdx.x; i < count;
         i += static_cast<std::int64_t>(gridDim.x) * blockDim.x)
        function(i);
}

// A tile of a warp's threads that runs one task together (tile.hpp): what
// CudaExec::for_each_of_tiled hands its function. Its members are the host's
// too, for the host's compilation of code that names it, and run only on
// the device.
template <int Size>
struct DeviceTile {
    static constexpr int kSize = Size;
    __host__ __device__ static constexpr int size() { return Size; }
#ifdef __CUDA_ARCH__
    __device__ int rank() const { return static_cast<int>(threadIdx.x % Size); }
    __device__ unsigned ballot(bool b) const {
        return cooperative_groups::tiled_partition<Size>(cooperative_groups::this_thread_block()).ballot(b);
    }
    __device__ int sum(int x) const {
        const auto tile = cooperative_groups::tiled_partition<Size>(cooperative_groups::this_thread_block());
        for (int offset = Size / 2; offset > 0; offset /= 2) x += tile.shfl_xor(x, offset);
        return x;
    }
    template <class T>
    __device__ T shfl(const T& value, int rank) const {
        return cooperative_groups::tiled_partition<Size>(cooperative_groups::this_thread_block()).shfl(value, rank);
    }
    __device__ static int lowest(unsigned mask) { return __ffs(mask) - 1; }
    __device__ static int count(unsigned mask) { return __popc(mask); }
    __device__ void sync() const {
        cooperative_groups::tiled_partition<Size>(cooperative_groups::this_thread_block()).sync();
    }
#else
    int rank() const { return 0; }
    unsigned ballot(bool b) const { return b; }
    int sum(int x) const { return x; }
    template <class T>
    T shfl(const T& value, int) const {
        return value;
    }
    static int lowest(unsigned) { return 0; }
    static int count(unsigned mask) { return mask ? 1 : 0; }
    void sync() const {}
#endif
};

// CudaExec::for_each_of_tiled's loop: tiles of Size threads striding over
// the tasks, each tile's scratch in shared memory (raw bytes: a __shared__
// variable is not constructed).
template <int Size, int Block, int MinBlocks, class Scratch, class Function>
__global__ void __launch_bounds__(Block, MinBlocks) for_each_of_tiled_kernel(const std::int64_t* n, Function function) {
    constexpr int kTiles = Block / Size;
    struct alignas(Scratch) Raw {
        unsigned char bytes[sizeof(Scratch)];
    };
    __shared__ Raw scratch[kTiles];
    const DeviceTile<Size> tile;
    const int own = static_cast<int>(threadIdx.x / Size);
    Scratch& mine = *reinterpret_cast<Scratch*>(&scratch[own]);
    const std::int64_t count = *n;
    for (std::int64_t i = blockIdx.x * static_cast<std::int64_t>(kTiles) + own; i < count;
         i += static_cast<std::int64_t>(gridDim.x) * kTiles) {
        function(i, tile, mine);
        tile.sync(); // the next task overwrites the scratch
    }
}

// A device-side loop of steps, each two passes over a list whose size the
// previous step left in device memory (CudaExec::run_steps): one cooperative
// grid, every block resident, a grid-wide barrier between the passes and
// after each step, until a step finds the list empty. The size is read by
// every thread after the barrier, so all leave the loop together.
template <class First, class Second>
__global__ void __launch_bounds__(cuda::kBlock)
    steps_kernel(std::int64_t* sizes, int current, std::uint32_t step, First first, Second second, std::int64_t* steps_run) {
    cooperative_groups::grid_group grid = cooperative_groups::this_grid();
    const std::int64_t stride = static_cast<std::int64_t>(gridDim.x) * blockDim.x;
    const std::int64_t start = blockIdx.x * static_cast<std::int64_t>(blockDim.x) + threadIdx.x;
    std::int64_t steps = 0;
    for (;; current = 1 - current) {
        const std::int64_t n = *static_cast<volatile std::int64_t*>(sizes + current);
        if (n == 0) break;
        ++step;
        ++steps;
        for (std::int64_t i = start; i < n; i += stride) first(i, step, current);
        grid.sync();
        for (std::int64_t i = start; i < n; i += stride) second(i, step, current);
        grid.sync();
    }
    if (start == 0) *steps_run = steps;
}

// An index's count for a scan of n + 1 entries: count(i), 0 at n.
template <class Count>
struct IndexSum {
    Count count;
    std::int64_t n;
    __host__ __device__ std::uint32_t operator()(std::int64_t i) const { return i < n ? count(i) : 0u; }
};

// With TETISO_GPU_PROFILE set, every primitive waits for the device before
// and after it and adds its seconds to its call site's line of a table,
// printed to stderr when the backend goes: where a driver's time goes on
// the device, by line of the driver. Off, it costs a branch.
class Profile {
public:
    Profile() : on_(std::getenv("TETISO_GPU_PROFILE") != nullptr) {}
    ~Profile() {
        if (!on_ || sites_.empty()) return;
        std::vector<std::pair<std::string, Site>> rows(sites_.begin(), sites_.end());
        std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.second.seconds > b.second.seconds; });
        double total = 0;
        for (const auto& row : rows) total += row.second.seconds;
        std::fprintf(stderr, "tetiso GPU profile: %.3f s in primitives\n", total);
        for (const auto& [where, site] : rows)
            std::fprintf(stderr, "  %9.3f ms %8ld calls  %s\n", site.seconds * 1e3, site.calls, where.c_str());
    }
    bool on() const { return on_; }
    void add(const char* what, const char* file, int line, double seconds) {
        const char* base = std::strrchr(file, '/');
        Site& site = sites_[std::string(what) + " " + (base ? base + 1 : file) + ":" + std::to_string(line)];
        site.seconds += seconds;
        ++site.calls;
    }

private:
    struct Site {
        double seconds = 0;
        long calls = 0;
    };
    bool on_;
    std::map<std::string, Site> sites_;
};

} // namespace cuda_exec

} // namespace tetiso
