// A CUDA Device's side of extract, reduce and a domain's task: what those
// entry points call where the Device in their options is a GPU
// (device_cuda.cu; device_none.cpp in a build without CUDA, where no such
// Device can be made). Each adds its seconds by stage to *seconds where set.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "tetiso/device.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::on_gpu {

// Marching tetrahedra, then, where then_reduce is set, the reduction of the
// surface without it leaving the device.
Piece extract(Device::State& gpu, const Domain& domain, float level, const ReduceOptions* then_reduce,
              ReduceReport* report, StageSeconds* seconds);
// A lattice domain, built on the device (a built-in field evaluated there
// too), so that nothing but the piece crosses the bus.
Piece extract(Device::State& gpu, const Decomposition& decomposition, int domain, const Field& field, float level,
              const ReduceOptions* then_reduce, ReduceReport* report, StageSeconds* seconds);
Piece reduce(Device::State& gpu, const Piece& piece, const ReduceOptions& options, ReduceReport* report,
             StageSeconds* seconds);
std::vector<Piece> reduce_batch(Device::State& gpu, const std::vector<Piece>& pieces, const ReduceOptions& options,
                                ReduceReport* report, StageSeconds* seconds);

// Domains extracted on the device one after the other, their surfaces
// reduced side by side in batches (Device::State::reduce_batch) of at most
// batch_triangles raw triangles (0: one batch). Lattice domains are built on
// the device; other domains are made on the host by make(i), one at a time,
// and released once extracted. Each result's seconds: its domain's
// generation and extraction, and its batch's reduction and download shared
// out by raw triangles.
// A domain's task in a batch: its piece, seconds and raw triangles.
struct BatchTask {
    Piece piece;
    StageSeconds seconds;
    std::size_t triangles_extracted = 0;
};
std::vector<BatchTask> extract_batch(Device::State& gpu, const Decomposition& decomposition,
                                            const std::vector<int>& domains, const Field& field, float level,
                                            const ReduceOptions& reduce, std::size_t batch_triangles);
std::vector<BatchTask> extract_batch(Device::State& gpu, std::size_t count,
                                            const std::function<Domain(std::size_t)>& make, float level,
                                            const ReduceOptions& reduce, std::size_t batch_triangles);

} // namespace tetiso::on_gpu
