// In situ: a running solver's ranks hand their pieces of a tetrahedral mesh
// to tetiso in memory, collectively over the solver's own communicator, and
// one rank gets the reduced isosurface back (or writes it), with no file in
// between.
//
// Each rank's piece is one domain, exactly as each piece of a .pvtu is
// (pvtu.hpp): rank r's piece is piece r of the .pvtu the same pieces would
// be written as. The pieces are seamed by global node ids, never by
// coordinates; a shared node takes the smallest position and value its
// pieces give, and copies farther apart than the .pvtu reader's tolerance
// are refused. The domains, their merge tree, the edge keys, the spacing the
// error bound is measured in and the order of the seams are those of the
// file route, computed by the same code, so the surface is byte for byte
// what `tetiso run --mesh PIECES.pvtu --array FIELD --level L` writes for
// those pieces, for any number of ranks and any device. Only where each task
// runs differs: a rank extracts and reduces its own piece (no node is sent),
// and a seam runs on the rank that holds its left child's piece, the right
// one sent to it.
//
// Cost: every rank scans the boundary of its piece and the ranks pool those
// scans (one all-gather of boundary nodes and edges), then each reduces its
// piece; the seams follow the fixed tree, one point-to-point message of a
// reduced piece per seam. The reduced surface ends on the root alone.
//
// Errors are collective: bad input on one rank, or a task that fails on one
// rank, makes the call throw tetiso::Error on every rank with the same
// message, which names the rank and what is wrong. No rank is left waiting.
#pragma once

#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "tetiso/device.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

// The element type of a solver's array.
enum class ScalarType : std::uint8_t { float32, float64, int32, int64, uint8 };

// A solver's array as it lies in memory: not copied, read during the call
// only. `size` counts elements (not bytes, not nodes).
struct ArrayView {
    const void* data = nullptr;
    std::size_t size = 0;
    ScalarType type = ScalarType::float64;

    ArrayView() = default;
    ArrayView(const float* values, std::size_t count) : data(values), size(count), type(ScalarType::float32) {}
    ArrayView(const double* values, std::size_t count) : data(values), size(count), type(ScalarType::float64) {}
    ArrayView(const std::int32_t* values, std::size_t count) : data(values), size(count), type(ScalarType::int32) {}
    ArrayView(const std::int64_t* values, std::size_t count) : data(values), size(count), type(ScalarType::int64) {}
    ArrayView(const std::uint8_t* values, std::size_t count) : data(values), size(count), type(ScalarType::uint8) {}
    bool empty() const { return size == 0; }
};

// One rank's piece, as the solver holds it. Layouts read in place (no copy
// of the solver's arrays is made for them):
//   coordinates  3 per node, interleaved x0 y0 z0 x1 ... (float32 or float64;
//                DOLFINx's mesh.geometry.x, a NumPy (n, 3) C-order array)
//   global_ids   one per node (int32 or int64), each in [0, 2^32), unique
//                within the piece; a node several pieces hold has the same
//                id in each
//   field        one value per node (float32 or float64)
//   tetrahedra   4 local node indices per tetrahedron (int32), in either
//                orientation
//   ghost_cells  empty, or one uint8 per tetrahedron: nonzero marks a cell
//                another rank owns, which is skipped here (VTK's
//                vtkGhostType, DUPLICATECELL). Only with a mask are the kept
//                tetrahedra copied (4 int32 each).
// Nodes that no kept tetrahedron uses are ignored. Coordinates and values
// are taken as float, as the .pvtu reader takes them. A message about a
// node or tetrahedron names its index in the arrays as given, except that
// a tetrahedron found wrong only once the domain is built (zero volume) is
// numbered among the kept ones (the same where the ghosts come last).
struct InSituPiece {
    ArrayView coordinates;
    ArrayView global_ids;
    ArrayView field;
    ArrayView tetrahedra;
    ArrayView ghost_cells;
};

// Where each rank's extraction and reduction run (the seams run on the
// host): the CPU; the GPU of this rank (the node's GPUs dealt out to its
// ranks by their rank within the node, gpu = local rank mod GPU count; an
// error where the node has none); or automatic, that GPU where the node has
// one, else the CPU. The surface is the same bytes on either.
enum class InSituDevice { cpu, gpu, automatic };

// What a session keeps from one call to the next.
struct InSituSessionOptions {
    InSituDevice device = InSituDevice::cpu;
    // Host threads of this rank's tasks (0: OpenMP's default); the surface
    // does not depend on it.
    int threads = 1;
    // The rank that gets the surface (and writes it).
    int root = 0;
};

// One call's level and reduction, with the defaults of `tetiso run`.
struct InSituOptions {
    double level = 0;
    // Off: extract and seam only (`--no-reduce`).
    bool reduce = true;
    // Φ* and the rest of the reduction; its threads, more_threads, device and
    // max_error are the session's and the call's own, whatever is set here.
    ReduceOptions reduce_options;
    // The error bound in units of the whole mesh's mean edge length
    // (`--max-error`); 0: none.
    double max_error_spacings = 0.25;
    int seam_rings = 1;   // `--seam-rings`
    int sample_rings = 1; // `--sample-rings`
    // Where set, the root writes the surface there (.ply or .vtp, atomically)
    // and every rank learns whether that worked.
    std::filesystem::path output;
};

// What one call cost, on this rank, and how large things were.
struct InSituCost {
    struct Seconds {
        double check = 0;  // the piece's arrays checked, the ranks agreeing on them
        double scan = 0;   // this piece's boundary scanned
        double pool = 0;   // the scans pooled (all-gather) and the tables built
        double domain = 0; // this piece's domain built, extracted and reduced
        double seams = 0;  // the seams run here, waits for pieces included
        double write = 0;  // the surface written (root, with an output)
        double total = 0;  // the whole call, from entry to return
    } seconds;
    StageSeconds domain_stages; // the domain task's stages (generate: built from the arrays)
    // This rank's piece: nodes used, tetrahedra kept, triangles extracted
    // and left after its reduction.
    std::int64_t nodes = 0, tetrahedra = 0;
    std::int64_t triangles_extracted = 0, triangles_reduced = 0;
    int seams = 0; // seams this rank ran
    std::int64_t bytes_sent = 0, bytes_received = 0; // pieces sent and received
};

struct InSituResult {
    // The reduced surface on the root; none on the other ranks.
    std::optional<Piece> surface;
    InSituCost cost;
    // The whole mesh, as every rank knows it after the pool.
    std::int64_t mesh_nodes = 0, mesh_tetrahedra = 0;
    double spacing = 0;   // its mean edge length, the error bound's unit
    double max_error = 0; // the bound the reduction kept (0: none)
    int domain = 0;       // this rank's piece's domain id (the file route's)
};

// A session on a solver's communicator: the communicator duplicated once,
// the device made once (a GPU's context, stream and buffers kept), so that a
// time loop calls isosurface() every few steps without setting either up
// again. Every rank of the communicator makes the session and every call
// together. Destroy it before MPI_Finalize.
class InSituSession {
public:
    // Collective. Throws tetiso::Error on every rank where the options are
    // out of range on any rank, or disagree between ranks, or the device
    // policy asks for a GPU a rank has not.
    explicit InSituSession(MPI_Comm comm, const InSituSessionOptions& options = {});
    ~InSituSession();
    InSituSession(const InSituSession&) = delete;
    InSituSession& operator=(const InSituSession&) = delete;

    // Collective: every rank passes its piece, the same options on each.
    // Throws tetiso::Error on every rank, with one message naming the first
    // rank at fault and what is wrong, where any rank's piece is unusable
    // (an array of the wrong type or size, an index out of range, a
    // coordinate or value that is not finite in float range, a node id
    // outside [0, 2^32) or twice in one piece, a tetrahedron of zero volume,
    // a piece with no tetrahedra besides ghosts, tetrahedra that overlap in
    // one piece (one listed twice, one inverted) or across pieces, pieces
    // that overlap or disagree on a shared node: the .pvtu reader's checks,
    // in its words), where the options differ between ranks,
    // or where a task fails on any rank; then nothing is written.
    InSituResult isosurface(const InSituPiece& piece, const InSituOptions& options);

    int rank() const;
    int size() const;
    // This rank's device for its domain task.
    const Device& device() const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

} // namespace tetiso
