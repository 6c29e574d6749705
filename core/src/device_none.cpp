// The devices of a build without CUDA (no nvcc at configure time, or
// TETISO_CUDA=OFF): the host alone. Asking for a GPU is an error that says
// why, so no Device ever reaches the entry points below.
#include "device_entry.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

struct Device::State {};

namespace {
const char* kNoCuda = "this tetiso was built without CUDA (no nvcc found, or TETISO_CUDA=OFF)";
[[noreturn]] void no_gpu() { throw Error(std::string("GPU: ") + kNoCuda); }
} // namespace

GpuInfo gpu_info(int) { return {false, kNoCuda}; }
int gpu_count() { return 0; }

Device Device::cuda(int) { no_gpu(); }
int Device::gpu() const { return -1; }
std::string Device::description() const { return "cpu"; }
std::size_t Device::gpu_bytes_held() { return 0; }

namespace on_gpu {
Piece extract(Device::State&, const Domain&, float, const ReduceOptions*, ReduceReport*, StageSeconds*) { no_gpu(); }
Piece extract(Device::State&, const Decomposition&, int, const Field&, float, const ReduceOptions*, ReduceReport*,
              StageSeconds*) {
    no_gpu();
}
Piece reduce(Device::State&, const Piece&, const ReduceOptions&, ReduceReport*, StageSeconds*) { no_gpu(); }
std::vector<Piece> reduce_batch(Device::State&, const std::vector<Piece>&, const ReduceOptions&, ReduceReport*,
                                StageSeconds*) {
    no_gpu();
}
std::vector<BatchTask> extract_batch(Device::State&, const Decomposition&, const std::vector<int>&, const Field&,
                                            float, const ReduceOptions&, std::size_t) {
    no_gpu();
}
std::vector<BatchTask> extract_batch(Device::State&, std::size_t, const std::function<Domain(std::size_t)>&,
                                            float, const ReduceOptions&, std::size_t) {
    no_gpu();
}
} // namespace on_gpu

} // namespace tetiso
