// A CUDA Device (tetiso/device.hpp): finding the device, its context,
// stream and buffers, and the entry points that extract and reduce call for
// it (device_entry.hpp), each one domain's or piece's passes on the stream
// with the device waited for at every stage boundary.
#include <cuda_runtime.h>

#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "device_cuda.cuh"
#include "device_entry.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Each GPU thread's stack: the largest frame of the reduction's kernels (the
// legality test) with room to spare. The device reserves it for every
// thread it can hold.
constexpr std::size_t kStackBytes = 8 * 1024;

// How a host thread waits for its stream (TETISO_GPU_WAIT=spin|yield|blocking,
// read when the process first opens the device). CUDA's default spins while
// the process has no more contexts than the machine has cores. A process
// whose Devices are driven by more threads than it has cores (a job's GPU
// driver is bound to one core and runs a thread per stream,
// domain_task.hpp) must not: a spinning thread holds the core that another
// needs to launch its kernels. Yielding costs a wait little and gives the
// core to whichever thread has work.
unsigned host_wait_flag() {
    const char* text = std::getenv("TETISO_GPU_WAIT");
    const std::string wait = text ? text : "yield";
    if (wait == "spin") return cudaDeviceScheduleSpin;
    if (wait == "blocking") return cudaDeviceScheduleBlockingSync;
    if (wait == "auto") return cudaDeviceScheduleAuto;
    return cudaDeviceScheduleYield;
}

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
    if (cudaInitDevice(device_index, cudaDeviceLmemResizeToMax | host_wait_flag(), cudaInitDeviceFlagsAreValid) !=
        cudaSuccess)
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

std::vector<Piece> reduce_batch(Device::State& g, const std::vector<Piece>& pieces, const ReduceOptions& options,
                                ReduceReport* report, StageSeconds* seconds) {
    g.timings = {};
    std::vector<Piece> out = g.reduce_batch(pieces, options, report);
    add(seconds, g.timings);
    return out;
}

namespace {

// extract_surface(i): domain i's surface on the device, its extraction's
// seconds in g.timings.
template <class ExtractSurface>
std::vector<BatchTask> extract_batch_then(Device::State& g, std::size_t count, ExtractSurface extract_surface,
                                                 const ReduceOptions& reduce, std::size_t batch_triangles) {
    std::vector<BatchTask> results(count);
    std::size_t first = 0; // the batch's first domain
    const auto reduce_batch = [&](std::size_t end) {
        g.timings = {};
        std::vector<Piece> pieces = g.reduce_batch(reduce, nullptr);
        // The batch's reduction and download, shared out by raw triangles.
        std::size_t total = 0;
        for (std::size_t i = first; i < end; ++i) total += results[i].triangles_extracted;
        for (std::size_t i = first; i < end; ++i) {
            BatchTask& r = results[i];
            const double share = total > 0 ? static_cast<double>(r.triangles_extracted) / static_cast<double>(total)
                                            : 1.0 / static_cast<double>(end - first);
            r.seconds.reduce += share * g.timings.reduce;
            r.seconds.download += share * g.timings.download;
            r.piece = std::move(pieces[i - first]);
        }
        first = end;
        g.begin_batch();
    };
    g.begin_batch();
    for (std::size_t i = 0; i < count; ++i) {
        g.timings = {};
        const DeviceSurface surface = extract_surface(i);
        results[i].seconds += g.timings;
        results[i].triangles_extracted = static_cast<std::size_t>(surface.triangle_count);
        // The surface stays in the extraction's buffers while the batch
        // before it is reduced.
        const auto held = static_cast<std::size_t>(g.reduction.s.nt);
        if (batch_triangles > 0 && i > first && held + results[i].triangles_extracted > batch_triangles)
            reduce_batch(i);
        g.append_to_batch(surface);
    }
    if (first < count) reduce_batch(count);
    return results;
}

} // namespace

std::vector<BatchTask> extract_batch(Device::State& g, const Decomposition& decomposition,
                                            const std::vector<int>& domains, const Field& field, float level,
                                            const ReduceOptions& reduce, std::size_t batch_triangles) {
    return extract_batch_then(
        g, domains.size(), [&](std::size_t i) { return g.extract(decomposition, domains[i], field, level); }, reduce,
        batch_triangles);
}

std::vector<BatchTask> extract_batch(Device::State& g, std::size_t count,
                                            const std::function<Domain(std::size_t)>& make, float level,
                                            const ReduceOptions& reduce, std::size_t batch_triangles) {
    std::vector<double> generate(count, 0.0);
    std::vector<BatchTask> results = extract_batch_then(
        g, count,
        [&](std::size_t i) {
            const auto start = std::chrono::steady_clock::now();
            const Domain domain = make(i);
            generate[i] = seconds_since(start);
            return g.extract(domain, level);
        },
        reduce, batch_triangles);
    for (std::size_t i = 0; i < count; ++i) results[i].seconds.generate += generate[i];
    return results;
}

} // namespace on_gpu
} // namespace tetiso
