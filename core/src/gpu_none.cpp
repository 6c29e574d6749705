// The GPU of a build without CUDA (no nvcc at configure time, or
// TETISO_CUDA=OFF): there is never a device, and asking for one is an error
// that says why.
#include "tetiso/error.hpp"
#include "tetiso/gpu.hpp"

namespace tetiso {

struct Gpu::State {};

namespace {
const char* kNoCuda = "this tetiso was built without CUDA (no nvcc found, or TETISO_CUDA=OFF)";
[[noreturn]] void no_gpu() { throw Error(std::string("GPU: ") + kNoCuda); }
} // namespace

GpuInfo gpu_info(int) { return {false, kNoCuda}; }
int gpu_count() { return 0; }

Gpu::Gpu(int) { no_gpu(); }
Gpu::~Gpu() = default;
int Gpu::device() const { no_gpu(); }
const std::string& Gpu::description() const { no_gpu(); }
Piece Gpu::extract(const Domain&, float) { no_gpu(); }
Piece Gpu::extract(const Decomposition&, int, const Field&, float) { no_gpu(); }
Piece Gpu::reduce(const Piece&, const ReduceOptions&, ReduceReport*) { no_gpu(); }
Piece Gpu::extract_and_reduce(const Domain&, float, const ReduceOptions&, ReduceReport*) { no_gpu(); }
Piece Gpu::extract_and_reduce(const Decomposition&, int, const Field&, float, const ReduceOptions&, ReduceReport*) {
    no_gpu();
}
const GpuTimings& Gpu::last_timings() const { no_gpu(); }
std::size_t Gpu::bytes_held() const { return 0; }

} // namespace tetiso
