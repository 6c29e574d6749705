// What the CUDA units share: error checks that throw tetiso::Error naming the
// call, device arrays that only grow (a process's buffers serve task after
// task without allocating, the pool the GPU path needs), and the one kernel
// every data-parallel loop launches.
#pragma once

#include <cuda_runtime.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tetiso/error.hpp"

namespace tetiso::cuda {

inline void check(cudaError_t status, const char* what) {
    if (status != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(status));
}

inline void check_launch(const char* kernel) { check(cudaGetLastError(), kernel); }

// Device memory held by this process's DeviceArrays, all devices together.
inline std::atomic<std::size_t> bytes_held{0};

// The stream of the CUDA Device whose call this thread runs, set as the call
// starts (Device::State::use_device). An array belongs to one Device and is
// used on its stream alone, so it grows in that stream's order, and the
// other Devices of the GPU, driven by other threads, go on meanwhile.
// Unset, growing waits for the whole device.
inline thread_local cudaStream_t growth_stream = nullptr;

// A device array that only grows, keeping its contents when it does: a run
// of tasks allocates a few times at first and then never (no managed
// memory: plain device allocations).
template <class T>
class DeviceArray {
public:
    DeviceArray() = default;
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    ~DeviceArray() {
        cudaFree(data_);
        bytes_held -= capacity_ * sizeof(T);
    }

    T* data() const { return data_; }
    std::size_t size() const { return size_; }

    void resize(std::size_t n) {
        if (n > capacity_) {
            const std::size_t grown = n + n / 4; // the next task is often a little larger
            T* fresh = nullptr;
            if (const cudaStream_t stream = growth_stream) {
                // Work queued on the stream may still read or write the old
                // buffer: it goes once that work is done.
                check(cudaMallocAsync(reinterpret_cast<void**>(&fresh), grown * sizeof(T), stream),
                      "cudaMallocAsync (out of device memory?)");
                if (size_ > 0)
                    check(cudaMemcpyAsync(fresh, data_, size_ * sizeof(T), cudaMemcpyDeviceToDevice, stream),
                          "cudaMemcpyAsync");
                if (data_ && !stream_ordered_) check(cudaStreamSynchronize(stream), "growing a device array");
                if (data_) check(stream_ordered_ ? cudaFreeAsync(data_, stream) : cudaFree(data_), "freeing");
                stream_ordered_ = true;
            } else {
                // Work queued on any stream may still read or write the old
                // buffer; wait for it all.
                check(cudaDeviceSynchronize(), "growing a device array");
                check(cudaMalloc(reinterpret_cast<void**>(&fresh), grown * sizeof(T)),
                      "cudaMalloc (out of device memory?)");
                if (size_ > 0)
                    check(cudaMemcpy(fresh, data_, size_ * sizeof(T), cudaMemcpyDeviceToDevice), "cudaMemcpy");
                check(cudaFree(data_), "cudaFree");
                stream_ordered_ = false;
            }
            bytes_held += (grown - capacity_) * sizeof(T);
            data_ = fresh;
            capacity_ = grown;
        }
        size_ = n;
    }

    void swap(DeviceArray& other) noexcept {
        std::swap(data_, other.data_);
        std::swap(size_, other.size_);
        std::swap(capacity_, other.capacity_);
        std::swap(stream_ordered_, other.stream_ordered_);
    }

    std::size_t capacity_bytes() const { return capacity_ * sizeof(T); }

private:
    T* data_ = nullptr;
    std::size_t size_ = 0;
    std::size_t capacity_ = 0;
    bool stream_ordered_ = false; // data_ from cudaMallocAsync, freed in a stream's order
};

constexpr int kBlock = 256;

inline unsigned blocks_for(std::int64_t n) {
    const std::int64_t blocks = (n + kBlock - 1) / kBlock;
    return static_cast<unsigned>(blocks < 65535 * 64 ? blocks : 65535 * 64);
}

// A grid-stride loop over [0, n): any element count fits any grid.
template <class Function>
__global__ void for_each_kernel(std::int64_t n, Function function) {
    for (std::int64_t i = blockIdx.x * static_cast<std::int64_t>(blockDim.x) + threadIdx.x; i < n;
         i += static_cast<std::int64_t>(gridDim.x) * blockDim.x)
        function(i);
}

// The same for loops of heavy elements (Grain::kTests: a legality test each,
// some 200 registers' worth of state uncapped): the compiler is held to the
// registers that let three blocks share a multiprocessor (80), so that more
// warps hide the latency of each test's long chains of loads: faster than
// two blocks (128 registers) or uncapped, and four blocks (64) gain nothing
// more (TETISO_GPU_TEST_BLOCKS_PER_SM overrides it, for measuring).
template <class Function>
__global__ void __launch_bounds__(kBlock, 3) for_each_heavy_kernel(std::int64_t n, Function function) {
    for (std::int64_t i = blockIdx.x * static_cast<std::int64_t>(blockDim.x) + threadIdx.x; i < n;
         i += static_cast<std::int64_t>(gridDim.x) * blockDim.x)
        function(i);
}

// The same over [0, max(*n, min_n)), n read on the device.
template <class Function>
__global__ void for_each_of_kernel(const std::int64_t* n, std::int64_t min_n, Function function) {
    const std::int64_t count = *n > min_n ? *n : min_n;
    for (std::int64_t i = blockIdx.x * static_cast<std::int64_t>(blockDim.x) + threadIdx.x; i < count;
         i += static_cast<std::int64_t>(gridDim.x) * blockDim.x)
        function(i);
}

template <class Function>
void for_each(cudaStream_t stream, std::int64_t n, const Function& function, const char* what = "for_each") {
    if (n <= 0) return;
    for_each_kernel<<<blocks_for(n), kBlock, 0, stream>>>(n, function);
    check_launch(what);
}

} // namespace tetiso::cuda
