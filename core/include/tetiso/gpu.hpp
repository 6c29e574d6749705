// One CUDA GPU doing a domain's work: marching tetrahedra and reduction, the
// same bytes as tetiso::extract and tetiso::reduce (positions, keys, flags,
// vertex and triangle order, error bounds, samples), so that pieces from the
// CPU and the GPU seam with each other and a job's surface does not depend on
// where its tasks ran.
//
// Both stages run the CPU's algorithms as data-parallel passes over flat
// arrays, calling the same per-element functions (compiled for host and
// device, with the same rounding: no fused multiply-adds, IEEE division and
// square roots, the transcendental functions computed by tetiso itself). A
// domain task stays on the device from its field values to its reduced
// piece; only that piece comes back. A Gpu keeps its buffers from one task
// to the next (they only grow), so a run of domains allocates at its start
// and then not again; it uses no managed memory.
//
// Built only where CMake finds nvcc (TETISO_CUDA); elsewhere gpu_info() says
// so and a Gpu cannot be made.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

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

// Seconds of the last call, by stage (device work is waited for at each
// boundary, so the three add up to the call).
struct GpuTimings {
    double upload = 0.0;   // input to the device
    double compute = 0.0;  // every pass on the device: extract + reduce
    double download = 0.0; // the result back to the host
    double extract = 0.0, reduce = 0.0;
};

class Gpu {
public:
    // Throws tetiso::Error when the device does not exist or this build has
    // no CUDA backend.
    explicit Gpu(int device = 0);
    ~Gpu();
    Gpu(const Gpu&) = delete;
    Gpu& operator=(const Gpu&) = delete;

    int device() const;
    // The device's name, memory and compute capability.
    const std::string& description() const;

    // tetiso::extract(domain, level), errors included (the same tetiso::Error
    // messages for a non-finite value, a tetrahedron naming a node that does
    // not exist, a surface too large).
    Piece extract(const Domain& domain, float level);

    // A domain of the lattice test problem: the device builds its nodes,
    // node ids, interface masks and tetrahedra as make_domain does, and
    // evaluates a built-in field (Field::builtin) itself, so nothing but the
    // piece crosses the bus; another field's values are computed on the host
    // and uploaded (4 bytes per node).
    Piece extract(const Decomposition& decomposition, int domain, const Field& field, float level);

    // tetiso::reduce(piece, options, report), byte for byte; options.threads
    // and options.more_threads do not apply. The report's stage seconds
    // wait for the device at each stage.
    Piece reduce(const Piece& piece, const ReduceOptions& options, ReduceReport* report = nullptr);

    // A domain's task: extract(...) then reduce(...) of its piece, without
    // the piece leaving the device in between.
    Piece extract_and_reduce(const Domain& domain, float level, const ReduceOptions& options,
                             ReduceReport* report = nullptr);
    Piece extract_and_reduce(const Decomposition& decomposition, int domain, const Field& field, float level,
                             const ReduceOptions& options, ReduceReport* report = nullptr);

    const GpuTimings& last_timings() const;

    // Device memory the buffers of every Gpu of this process hold (they are
    // kept between calls and only grow).
    std::size_t bytes_held() const;

    struct State;

private:
    std::unique_ptr<State> state_;
};

} // namespace tetiso
