// What a CUDA Device (tetiso/device.hpp) holds: its device and stream, the
// buffers of its extraction and of its reduction, kept from task to task.
// Made here (device_cuda.cu); shared by the CUDA units of extraction
// (extract_gpu.cu) and reduction (reduce/reduce_gpu.cu), so that a domain's
// surface passes from one to the other on the device.
#pragma once

#include <cuda_runtime.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cuda_support.cuh"
#include "exec_cuda.cuh"
#include "marching_tets.hpp"
#include "reduce/rounds.hpp"
#include "tetiso/device.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

// An extracted surface left on the device: what a piece holds, in the
// extraction's buffers (valid until the next extraction).
struct DeviceSurface {
    const float *x, *y, *z;
    const EdgeKey* key;
    const std::uint8_t* flags;
    const std::int32_t* triangles;
    std::int32_t vertices, triangle_count;
    int domain;
};

// What extraction keeps on the device (extract_gpu.cu): the domain, and the
// arrays of the passes of marching tetrahedra (marching_tets.hpp).
struct ExtractionBuffers {
    template <class T>
    using Array = cuda::DeviceArray<T>;
    Array<float> x, y, z, f;
    Array<GlobalId> gid;
    Array<std::uint8_t> interface;
    Array<EdgeKey> shared;
    Array<std::int32_t> tets;
    marching::Arrays<CudaExec> passes;
};

struct Device::State {
    explicit State(int device);
    ~State();

    int device = 0;
    std::string description;
    cudaStream_t stream = nullptr;
    ExtractionBuffers extraction;
    std::unique_ptr<CudaExec> exec;
    reduction::ReductionState<CudaExec> reduction;
    StageSeconds timings; // of the current call, added to the caller's at its end

    // Extraction up to a surface on the device; fills timings.upload and
    // .extract (extract_gpu.cu).
    DeviceSurface extract(const Domain& domain, float level);
    DeviceSurface extract(const Decomposition& decomposition, int domain, const Field& field, float level);
    // The surface as a piece; fills timings.download.
    Piece download(const DeviceSurface& surface);

    // tetiso::reduce of a host piece, and of a surface extracted here, which
    // never leaves the device (reduce/reduce_gpu.cu); fill timings.upload,
    // .reduce and .download.
    Piece reduce(const Piece& piece, const ReduceOptions& options, ReduceReport* report);
    Piece reduce(const DeviceSurface& surface, const ReduceOptions& options, ReduceReport* report);
    // tetiso::reduce_batch of host pieces; and a batch of surfaces extracted
    // here: begin_batch, then append_to_batch after each extraction (the
    // surface copied beside the others, checked as reduce() checks it),
    // then reduce_batch (reduce/reduce_gpu.cu).
    std::vector<Piece> reduce_batch(const std::vector<Piece>& pieces, const ReduceOptions& options, ReduceReport* report);
    void begin_batch();
    void append_to_batch(const DeviceSurface& surface);
    std::vector<Piece> reduce_batch(const ReduceOptions& options, ReduceReport* report);
    std::vector<int> batch_domains; // the domain of each surface appended

    // Each call's first step on its thread: this device current, and this
    // Device's arrays growing on its stream (cuda::growth_stream).
    void use_device() const {
        cuda::check(cudaSetDevice(device), "cudaSetDevice");
        cuda::growth_stream = stream;
    }
};

inline double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace tetiso
