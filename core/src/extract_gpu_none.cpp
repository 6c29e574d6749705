// The GPU extraction of a build without CUDA (no nvcc at configure time, or
// TETISO_CUDA=OFF): there is never a device, and asking for one is an error
// that says why.
#include "tetiso/error.hpp"
#include "tetiso/extract_gpu.hpp"

namespace tetiso {

struct GpuExtractor::Buffers {};

GpuInfo gpu_info() { return {false, "this tetiso was built without CUDA (no nvcc found, or TETISO_CUDA=OFF)"}; }

GpuExtractor::GpuExtractor(int) { throw Error("GPU extraction: " + gpu_info().description); }

GpuExtractor::~GpuExtractor() = default;

Piece GpuExtractor::extract(const Domain&, float) { throw Error("GPU extraction: " + gpu_info().description); }

Piece GpuExtractor::extract(const Decomposition&, int, const std::vector<float>&, float) {
    throw Error("GPU extraction: " + gpu_info().description);
}

} // namespace tetiso
