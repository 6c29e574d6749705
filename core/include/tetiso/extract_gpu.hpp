// Marching tetrahedra on a CUDA GPU: the same surface as tetiso::extract, bit
// for bit (positions, keys, flags, vertex and triangle order), so that pieces
// from the CPU and the GPU seam with each other and a job's output does not
// depend on where its domains ran.
//
// The passes are extract.cpp's, written as data-parallel steps over the
// domain's flat arrays (classify nodes, count and emit crossings per
// tetrahedron, sort and unique the crossing edges, place, connect, order by
// key). A GpuExtractor keeps its device buffers from one domain to the next,
// as a worker's CPU keeps its freed memory, so a run of domains allocates
// once.
//
// Built only where CMake finds nvcc (TETISO_CUDA); elsewhere gpu_available()
// is false and a GpuExtractor cannot be made.
#pragma once

#include <memory>
#include <string>

#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

struct GpuInfo {
    bool available = false;
    std::string description; // the device's name and memory, or why there is none
};

// Whether this build has the CUDA backend and the machine a CUDA device.
GpuInfo gpu_info();

// Seconds of the last extraction, by stage (device work is waited for at
// each boundary, so the three add up to the call).
struct GpuExtractTimings {
    double upload = 0.0;   // domain arrays to the device
    double compute = 0.0;  // every pass on the device
    double download = 0.0; // the piece back to the host
};

class GpuExtractor {
public:
    // Throws tetiso::Error when there is no CUDA device or this build has no
    // CUDA backend.
    explicit GpuExtractor(int device = 0);
    ~GpuExtractor();
    GpuExtractor(const GpuExtractor&) = delete;
    GpuExtractor& operator=(const GpuExtractor&) = delete;

    // The same as tetiso::extract(domain, level), errors included (the same
    // tetiso::Error messages for a non-finite value, a tetrahedron naming a
    // node that does not exist, a surface too large). A CUDA failure (out of
    // device memory, say) is a tetiso::Error naming the call.
    Piece extract(const Domain& domain, float level);

    // A domain of the lattice test problem from its field values alone
    // (Decomposition::field_values): the device builds its positions, node
    // ids, interface masks and tetrahedra as make_domain does, so the surface
    // is extract(decomposition.make_domain(domain, field), level)'s while
    // 4 bytes per node cross the bus instead of some 125.
    Piece extract(const Decomposition& decomposition, int domain, const std::vector<float>& values, float level);

    const GpuExtractTimings& last_timings() const { return timings_; }

private:
    struct Buffers;
    std::unique_ptr<Buffers> buffers_;
    GpuExtractTimings timings_;
};

} // namespace tetiso
