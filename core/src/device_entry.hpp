// A CUDA Device's side of extract, reduce and a domain's task: what those
// entry points call where the Device in their options is a GPU
// (device_cuda.cu; device_none.cpp in a build without CUDA, where no such
// Device can be made). Each adds its seconds by stage to *seconds where set.
#pragma once

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

} // namespace tetiso::on_gpu
