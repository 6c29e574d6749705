// Where extraction and reduction run: the host, or one CUDA GPU. A Device is
// a value passed in the options of extract (ExtractOptions), reduce
// (ReduceOptions) and a domain's task (domain_task.hpp); no algorithm is
// written for one device or the other, and the output is the same bytes on
// every device (positions, keys, flags, vertex and triangle order, error
// bounds, samples), so that pieces from the CPU and the GPU seam with each
// other and a job's surface does not depend on where its tasks ran.
//
// On a GPU, both stages run the host's algorithms as data-parallel passes
// over flat arrays, calling the same per-element functions (compiled for
// host and device, with the same rounding: no fused multiply-adds, IEEE
// division and square roots, the transcendental functions computed by tetiso
// itself). A CUDA Device owns its stream and buffers, kept from one call to
// the next (they only grow), so a run of domains allocates at its start and
// then not again; it uses no managed memory. Copies of a Device share them:
// one thread at a time may use a CUDA Device. Several Devices of one GPU may
// be used by as many threads at once (several domains in flight): each waits
// for its own stream alone, its buffers growing in that stream's order, and
// yields its core while it waits (TETISO_GPU_WAIT=spin|yield|blocking|auto,
// read when the process first opens the device), so that threads that share
// a core do not hold it from each other.
//
// The host's thread count is the options' own (ExtractOptions::threads,
// ReduceOptions::threads), since a reduction may be offered more threads as
// it runs. The GPU exists only where CMake found nvcc (TETISO_CUDA);
// elsewhere gpu_info() says so and Device::cuda throws.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace tetiso {

struct GpuInfo {
    bool available = false;
    std::string description; // the device's name and memory, or why there is none
    std::size_t memory_bytes = 0; // the device's global memory (0 where none)
};

// Whether this build has the CUDA backend and the machine CUDA device
// `device` (0-based, as CUDA numbers them after CUDA_VISIBLE_DEVICES).
GpuInfo gpu_info(int device = 0);

// CUDA devices this process can use (0 in a build without CUDA).
int gpu_count();

// Seconds of a domain's stages. extract, reduce and run_domain_task add
// theirs; device work is waited for at each boundary, so on a GPU upload,
// extract, reduce and download add up to the calls.
struct StageSeconds {
    double generate = 0; // the domain built on the host
    double upload = 0;   // input to the device
    double extract = 0, reduce = 0;
    double download = 0; // the result back to the host

    StageSeconds& operator+=(const StageSeconds& s) {
        generate += s.generate;
        upload += s.upload;
        extract += s.extract;
        reduce += s.reduce;
        download += s.download;
        return *this;
    }
};

class Device {
public:
    // The host.
    Device() = default;
    static Device host() { return Device(); }
    // CUDA device `index`, its stream and buffers made now. Throws
    // tetiso::Error ("GPU: why not") where it does not exist or this build
    // has no CUDA backend.
    static Device cuda(int index = 0);

    bool is_gpu() const { return state_ != nullptr; }
    // The CUDA device's index, -1 for the host.
    int gpu() const;
    // "cpu", or the GPU's name, memory and compute capability.
    std::string description() const;

    // Device memory the buffers of every CUDA Device of this process hold.
    static std::size_t gpu_bytes_held();

    // What a CUDA Device keeps between calls (device_cuda.cuh).
    struct State;
    State& state() const { return *state_; }

private:
    std::shared_ptr<State> state_;
};

} // namespace tetiso
