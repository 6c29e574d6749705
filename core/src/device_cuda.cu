// A CUDA Device (tetiso/device.hpp): finding the device, its context,
// stream and buffers, and the entry points that extract and reduce call for
// it (device_entry.hpp), each one domain's or piece's passes on the stream
// with the device waited for at every stage boundary.
#include <cuda_runtime.h>

#include <string>

#include "device_cuda.cuh"
#include "device_entry.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Each GPU thread's stack: the largest frame of the reduction's kernels (the
// legality test) with room to spare. The device reserves it for every
// thread it can hold.
constexpr std::size_t kStackBytes = 8 * 1024;

void add(StageSeconds* to, const StageSeconds& s) {
    if (to) *to += s;
}

} // namespace

GpuInfo gpu_info(int device) {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) return {false, std::string("no usable CUDA device (") + cudaGetErrorString(status) + ")"};
    if (count == 0) return {false, "no CUDA device"};
    if (device < 0 || device >= count)
        return {false, "no CUDA device " + std::to_string(device) + " (this machine has " + std::to_string(count) + ")"};
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, device) != cudaSuccess)
        return {false, "CUDA device " + std::to_string(device) + " cannot be queried"};
    return {true,
            std::string(prop.name) + ", " + std::to_string(prop.totalGlobalMem >> 20) + " MiB, compute capability " +
                std::to_string(prop.major) + "." + std::to_string(prop.minor),
            prop.totalGlobalMem};
}

int gpu_count() {
    int count = 0;
    return cudaGetDeviceCount(&count) == cudaSuccess ? count : 0;
}

Device::State::State(int device_index) : device(device_index) {
    const GpuInfo info = gpu_info(device_index);
    if (!info.available) throw Error("GPU: " + info.description);
    description = info.description;
    // The reduction's legality tests keep a collapse's new faces on the
    // stack (several KB a thread). By default the driver grows local memory
    // for such a launch and shrinks it after, which cost every launch of
    // them about half a millisecond, whatever its size; keep it grown. Too
    // late where this process already uses the device (another Device of
    // it): then the stack limit alone, set below, spares the resizing.
    if (cudaInitDevice(device_index, cudaDeviceLmemResizeToMax, cudaInitDeviceFlagsAreValid) != cudaSuccess)
        cudaGetLastError();
    use_device();
    cuda::check(cudaDeviceSetLimit(cudaLimitStackSize, kStackBytes), "setting the GPU threads' stack size");
    cuda::check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
    exec = std::make_unique<CudaExec>(stream);
}

Device::State::~State() {
    exec.reset();
    if (cuda::growth_stream == stream) cuda::growth_stream = nullptr;
    if (stream) cudaStreamDestroy(stream);
}

Device Device::cuda(int index) {
    Device device;
    device.state_ = std::make_shared<State>(index);
    return device;
}

int Device::gpu() const { return state_ ? state_->device : -1; }

std::string Device::description() const { return state_ ? state_->description : "cpu"; }

std::size_t Device::gpu_bytes_held() { return cuda::bytes_held.load(); }

namespace on_gpu {
namespace {

template <class ExtractSurface>
Piece extract_then(Device::State& g, ExtractSurface extract_surface, const ReduceOptions* then_reduce,
                   ReduceReport* report, StageSeconds* seconds) {
    g.timings = {};
    const DeviceSurface surface = extract_surface();
    Piece piece = then_reduce ? g.reduce(surface, *then_reduce, report) : g.download(surface);
    add(seconds, g.timings);
    return piece;
}

} // namespace

Piece extract(Device::State& g, const Domain& domain, float level, const ReduceOptions* then_reduce,
              ReduceReport* report, StageSeconds* seconds) {
    return extract_then(g, [&] { return g.extract(domain, level); }, then_reduce, report, seconds);
}

Piece extract(Device::State& g, const Decomposition& decomposition, int domain, const Field& field, float level,
              const ReduceOptions* then_reduce, ReduceReport* report, StageSeconds* seconds) {
    return extract_then(g, [&] { return g.extract(decomposition, domain, field, level); }, then_reduce, report,
                        seconds);
}

Piece reduce(Device::State& g, const Piece& piece, const ReduceOptions& options, ReduceReport* report,
             StageSeconds* seconds) {
    g.timings = {};
    Piece out = g.reduce(piece, options, report);
    add(seconds, g.timings);
    return out;
}

} // namespace on_gpu
} // namespace tetiso
