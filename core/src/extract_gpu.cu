// Marching tetrahedra on a CUDA GPU (extract_gpu.hpp). The CPU version
// (extract.cpp) numbers crossings through per-node buckets filled by atomics;
// here every cut tetrahedron writes its crossing edges as 64-bit codes
// (local lo << 32 | local hi), and one radix sort and unique give the vertices
// in (lo, hi) order — the CPU's order, with no bucket to overflow. Triangles
// find their corners by binary search in that sorted list. Each pass is one
// kernel or one CUB primitive on the extractor's stream, and every scalar the
// host needs (a count, the first bad element) is read once, at a boundary.
//
// Bit-identical to the CPU: placement and the quad's split are the shared
// functions of extract_rules.hpp, compiled with --fmad=false (no fused
// multiply-add, as the host is built with -ffp-contract=off), and IEEE
// division (nvcc's default -prec-div=true).
#include "tetiso/extract_gpu.hpp"

#include <cuda_runtime.h>

#include <chrono>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>

#include "extract_rules.hpp"
#include "tetiso/error.hpp"
#include "tetiso/lattice.hpp"

namespace tetiso {
namespace {

using u8 = std::uint8_t;
using u32 = std::uint32_t;
using u64 = std::uint64_t;
using i32 = std::int32_t;

void check_cuda(cudaError_t status, const char* what) {
    if (status != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(status));
}

// The case table as the kernels read it: per pattern, the crossing count and
// the two tet-corner numbers of each crossing's edge, in case order.
struct CaseTable {
    int crossings[16];
    int corner[16][4][2];
};

__constant__ CaseTable c_cases;

CaseTable make_case_table() {
    CaseTable table{};
    for (int p = 0; p < 16; ++p) {
        const auto& c = extract_rules::kCases[static_cast<std::size_t>(p)];
        table.crossings[p] = c.crossings;
        for (int k = 0; k < 4; ++k)
            for (int end = 0; end < 2; ++end)
                table.corner[p][k][end] = extract_rules::kEdgesOfTet[c.edge[static_cast<std::size_t>(k)]][end];
    }
    return table;
}

// A device array that only grows: a run of domains allocates once.
template <class T>
class DeviceArray {
public:
    DeviceArray() = default;
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    ~DeviceArray() { cudaFree(data_); }

    T* data() const { return data_; }
    std::size_t size() const { return size_; }

    void resize(std::size_t n, const char* what) {
        if (n > capacity_) {
            check_cuda(cudaFree(data_), "cudaFree");
            data_ = nullptr;
            capacity_ = 0;
            const std::size_t grown = n + n / 4; // the next domain is often a little larger
            check_cuda(cudaMalloc(reinterpret_cast<void**>(&data_), grown * sizeof(T)), what);
            capacity_ = grown;
        }
        size_ = n;
    }

    void upload(const std::vector<T>& host, cudaStream_t stream, const char* what) {
        resize(host.size(), what);
        if (!host.empty())
            check_cuda(cudaMemcpyAsync(data_, host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice, stream), what);
    }

private:
    T* data_ = nullptr;
    std::size_t capacity_ = 0;
    std::size_t size_ = 0;
};

constexpr int kBlock = 256;

unsigned blocks_for(std::size_t n) {
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    return static_cast<unsigned>(blocks < 65535u * 32u ? blocks : 65535u * 32u);
}

// Grid-stride loops: any element count fits any grid.
#define TETISO_FOR_EACH(i, n) \
    for (std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; i < (n); \
         i += static_cast<std::size_t>(gridDim.x) * blockDim.x)

// The nodes of a lattice domain, as Decomposition::make_domain makes them.
struct LatticeNodes {
    std::int64_t n;               // lattice nodes per axis
    std::int64_t lo[3], px, py;   // the box's first node and its nodes per axis (x, y)
    std::int64_t nx, ny, nz;      // cells per axis
    unsigned open_faces;          // the box's faces that are interfaces
};

__global__ void make_lattice_nodes(std::size_t count, LatticeNodes box, float* x, float* y, float* z, GlobalId* gid,
                                   u8* interface) {
    TETISO_FOR_EACH(v, count) {
        const auto node = static_cast<std::int64_t>(v);
        const std::int64_t i = node % box.px, j = (node / box.px) % box.py, k = node / (box.px * box.py);
        const std::int64_t gi = box.lo[0] + i, gj = box.lo[1] + j, gk = box.lo[2] + k;
        // Lattice::coordinate: the same double operations, then one rounding.
        const double last = static_cast<double>(box.n - 1);
        x[v] = static_cast<float>(kLatticeExtent * static_cast<double>(gi) / last);
        y[v] = static_cast<float>(kLatticeExtent * static_cast<double>(gj) / last);
        z[v] = static_cast<float>(kLatticeExtent * static_cast<double>(gk) / last);
        gid[v] = gi + box.n * (gj + box.n * gk);
        const unsigned faces = (i == 0 ? 1u : 0u) | (i == box.nx ? 2u : 0u) | (j == 0 ? 4u : 0u) |
                               (j == box.ny ? 8u : 0u) | (k == 0 ? 16u : 0u) | (k == box.nz ? 32u : 0u);
        interface[v] = static_cast<u8>(faces & box.open_faces);
    }
}

// 1. classify. bad_node: one more than the largest node whose value is not
// finite (0: none), the node the CPU names.
__global__ void classify_nodes(std::size_t n, const float* f, float level, u8* above,
                               unsigned long long* bad_node) {
    TETISO_FOR_EACH(v, n) {
        const float value = f[v];
        if (!isfinite(value)) atomicMax(bad_node, static_cast<unsigned long long>(v) + 1);
        above[v] = value >= level ? 1 : 0;
    }
}

// 2a. count. bad_tet: the smallest tetrahedron naming a node that does not
// exist (ULLONG_MAX: none), the one the CPU names.
template <class Tets>
__global__ void count_crossings(std::size_t tets, Tets corners, u32 nodes, const u8* above, u8* pattern,
                                u32* crossings, u32* triangles, unsigned long long* bad_tet) {
    TETISO_FOR_EACH(t, tets) {
        const int4 v = corners(t);
        unsigned p = 0;
        if (static_cast<u32>(v.x) >= nodes || static_cast<u32>(v.y) >= nodes || static_cast<u32>(v.z) >= nodes ||
            static_cast<u32>(v.w) >= nodes)
            atomicMin(bad_tet, static_cast<unsigned long long>(t));
        else
            p = above[v.x] | (above[v.y] << 1) | (above[v.z] << 2) | (above[v.w] << 3);
        const int count = c_cases.crossings[p];
        pattern[t] = static_cast<u8>(p);
        crossings[t] = static_cast<u32>(count);
        triangles[t] = count == 4 ? 2u : (count == 3 ? 1u : 0u);
    }
}

// Where the per-tetrahedron kernels read a tetrahedron: an uploaded array, or
// the lattice's Freudenthal split computed from the tetrahedron's index, in
// make_domain's order (cells x fastest, six per cell).
struct TetArray {
    const int4* corners;
    __device__ int4 operator()(std::size_t t) const { return corners[t]; }
};

__constant__ int c_cell_orders[6][3];

struct LatticeTets {
    std::int64_t nx, ny, px, py; // cells and nodes per axis (x, y)
    __device__ int4 operator()(std::size_t t) const {
        const auto cell = static_cast<std::int64_t>(t / 6);
        const int which = static_cast<int>(t % 6);
        const std::int64_t i = cell % nx, j = (cell / nx) % ny, k = cell / (nx * ny);
        const std::int64_t stride[3] = {1, px, px * py};
        const std::int64_t origin = i + px * (j + py * k);
        const std::int64_t v1 = origin + stride[c_cell_orders[which][0]];
        const std::int64_t v2 = v1 + stride[c_cell_orders[which][1]];
        const bool odd = which >= 3;
        return make_int4(static_cast<int>(origin), static_cast<int>(odd ? v2 : v1), static_cast<int>(odd ? v1 : v2),
                         static_cast<int>(origin + 1 + px + px * py));
    }
};

__device__ inline int corner_of(const int4& v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : (k == 2 ? v.z : v.w)); }

__device__ inline u64 edge_code(const int4& v, unsigned p, int k) {
    const i32 a = corner_of(v, c_cases.corner[p][k][0]), b = corner_of(v, c_cases.corner[p][k][1]);
    const i32 lo = a < b ? a : b, hi = a < b ? b : a;
    return (static_cast<u64>(lo) << 32) | static_cast<u32>(hi);
}

// 2b. emit: each cut tetrahedron writes its crossing edges' codes.
template <class Tets>
__global__ void emit_crossings(std::size_t tets, Tets corners, const u8* pattern, const u32* first,
                               u64* codes) {
    TETISO_FOR_EACH(t, tets) {
        const unsigned p = pattern[t];
        const int count = c_cases.crossings[p];
        if (count == 0) continue;
        const int4 v = corners(t);
        u64* out = codes + first[t];
        for (int k = 0; k < count; ++k) out[k] = edge_code(v, p, k);
    }
}

// The first position in sorted[0, n) not below key.
__device__ inline std::size_t lower_bound(const u64* sorted, std::size_t n, u64 key) {
    std::size_t lo = 0, hi = n;
    while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (sorted[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

__device__ inline bool contains(const u64* sorted, std::size_t n, u64 key) {
    const std::size_t at = lower_bound(sorted, n, key);
    return at < n && sorted[at] == key;
}

struct NodeArrays {
    const float *x, *y, *z, *f;
    const GlobalId* gid;
    const u8* interface;
};

struct VertexArrays {
    float *x, *y, *z;
    EdgeKey* key;
    u8* flags;
};

// 4. place: extract.cpp's place_vertex, through the same functions.
__global__ void place_vertices(std::size_t count, const u64* edges, NodeArrays node, const EdgeKey* shared,
                               std::size_t shared_count, float level, VertexArrays out) {
    TETISO_FOR_EACH(i, count) {
        const auto lo = static_cast<std::size_t>(edges[i] >> 32), hi = static_cast<std::size_t>(edges[i] & 0xffffffffu);
        const bool lo_first = node.gid[lo] < node.gid[hi];
        const std::size_t a = lo_first ? lo : hi, b = lo_first ? hi : lo;
        const float t = extract_rules::crossing_parameter(node.f[a], node.f[b], level);
        out.x[i] = extract_rules::interpolate(node.x[a], node.x[b], t);
        out.y[i] = extract_rules::interpolate(node.y[a], node.y[b], t);
        out.z[i] = extract_rules::interpolate(node.z[a], node.z[b], t);
        const EdgeKey key = edge_key(node.gid[a], node.gid[b]);
        out.key[i] = key;
        const bool on_interface = (node.interface[a] & node.interface[b]) != 0 &&
                                  (shared_count == 0 || contains(shared, shared_count, key));
        out.flags[i] = on_interface ? static_cast<u8>(kLocked) : u8{0};
    }
}

__device__ inline i32 vertex_of(const u64* edges, std::size_t n, u64 code) {
    return static_cast<i32>(lower_bound(edges, n, code));
}

// 5. connect: a cut tetrahedron's one or two triangles, in tetrahedron order.
template <class Tets>
__global__ void connect(std::size_t tets, Tets corners, const u8* pattern, const u32* first_triangle,
                        const u64* edges, std::size_t vertex_count, const GlobalId* gid, i32* triangles) {
    TETISO_FOR_EACH(t, tets) {
        const unsigned p = pattern[t];
        const int count = c_cases.crossings[p];
        if (count == 0) continue;
        const int4 v = corners(t);
        i32 vertex[4];
        EdgeKey order[4];
        for (int k = 0; k < count; ++k) {
            const u64 code = edge_code(v, p, k);
            vertex[k] = vertex_of(edges, vertex_count, code);
            order[k] = edge_key(gid[code >> 32], gid[code & 0xffffffffu]);
        }
        i32* out = triangles + 3 * static_cast<std::size_t>(first_triangle[t]);
        if (count == 3) {
            out[0] = vertex[0], out[1] = vertex[1], out[2] = vertex[2];
        } else if (extract_rules::split_through_first(order)) {
            out[0] = vertex[0], out[1] = vertex[1], out[2] = vertex[2];
            out[3] = vertex[0], out[4] = vertex[2], out[5] = vertex[3];
        } else {
            out[0] = vertex[1], out[1] = vertex[2], out[2] = vertex[3];
            out[3] = vertex[1], out[4] = vertex[3], out[5] = vertex[0];
        }
    }
}

// Whether keys are out of order anywhere (lattice domains number nodes in
// global order and never are).
__global__ void find_unsorted(std::size_t n, const EdgeKey* key, unsigned long long* unsorted) {
    TETISO_FOR_EACH(i, n) {
        if (i + 1 < n && key[i] > key[i + 1]) *unsorted = 1;
    }
}

__global__ void number_in_order(std::size_t n, i32* values) {
    TETISO_FOR_EACH(i, n) values[i] = static_cast<i32>(i);
}

// order_by_key on the device: a stable radix sort by key gives the CPU's
// stable_sort order; positions and flags follow, corners are renamed.
__global__ void gather_vertices(std::size_t n, const i32* order, const float* x, const float* y, const float* z,
                                const u8* flags, VertexArrays out, i32* rank) {
    TETISO_FOR_EACH(i, n) {
        const auto from = static_cast<std::size_t>(order[i]);
        out.x[i] = x[from];
        out.y[i] = y[from];
        out.z[i] = z[from];
        out.flags[i] = flags[from];
        rank[from] = static_cast<i32>(i);
    }
}

__global__ void rename_corners(std::size_t n, const i32* rank, i32* corners) {
    TETISO_FOR_EACH(i, n) corners[i] = rank[corners[i]];
}

void check_launch(const char* kernel) { check_cuda(cudaGetLastError(), kernel); }

int bits_for(std::size_t n) {
    int bits = 1;
    while (bits < 32 && (std::size_t{1} << bits) < n) ++bits;
    return bits;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

struct GpuExtractor::Buffers {
    int device = 0;
    cudaStream_t stream = nullptr;
    // The domain.
    DeviceArray<float> x, y, z, f;
    DeviceArray<GlobalId> gid;
    DeviceArray<u8> interface;
    DeviceArray<EdgeKey> shared;
    DeviceArray<i32> tets;
    // Per node and per tetrahedron.
    DeviceArray<u8> above, pattern;
    DeviceArray<u32> crossings, first_crossing, triangles_per_tet, first_triangle;
    // Crossings, then vertices.
    DeviceArray<u64> codes, sorted_codes, edges;
    DeviceArray<float> vx, vy, vz, sx, sy, sz;
    DeviceArray<EdgeKey> key, sorted_key;
    DeviceArray<u8> flags, sorted_flags;
    DeviceArray<i32> corners, order, sorted_order, rank;
    // Scalars the host reads: bad node, bad tetrahedron, unique count, unsorted flag.
    DeviceArray<unsigned long long> scalars;
    DeviceArray<std::byte> scratch; // CUB's temporary storage

    ~Buffers() {
        if (stream) cudaStreamDestroy(stream);
    }

    std::byte* scratch_of(std::size_t bytes) {
        scratch.resize(bytes, "CUB scratch");
        return scratch.data();
    }

    // Every pass after the domain's node arrays are on the device (and
    // tet_source can read its tetrahedra); start: when the compute began.
    template <class Tets>
    Piece run(int domain_id, Tets tet_source, std::size_t nodes, std::size_t tets, float level,
              GpuExtractTimings& timings, std::chrono::steady_clock::time_point start);

    unsigned long long read_scalar(std::size_t i) {
        unsigned long long value = 0;
        check_cuda(cudaMemcpyAsync(&value, scalars.data() + i, sizeof value, cudaMemcpyDeviceToHost, stream),
                   "reading a count");
        check_cuda(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
        return value;
    }
};

GpuInfo gpu_info() {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) return {false, std::string("no usable CUDA device (") + cudaGetErrorString(status) + ")"};
    if (count == 0) return {false, "no CUDA device"};
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) return {false, "CUDA device 0 cannot be queried"};
    return {true, std::string(prop.name) + ", " + std::to_string(prop.totalGlobalMem >> 20) + " MiB, compute capability " +
                      std::to_string(prop.major) + "." + std::to_string(prop.minor)};
}

GpuExtractor::GpuExtractor(int device) : buffers_(std::make_unique<Buffers>()) {
    const GpuInfo info = gpu_info();
    if (!info.available) throw Error("GPU extraction: " + info.description);
    buffers_->device = device;
    check_cuda(cudaSetDevice(device), "cudaSetDevice");
    check_cuda(cudaStreamCreateWithFlags(&buffers_->stream, cudaStreamNonBlocking), "cudaStreamCreate");
    const CaseTable table = make_case_table();
    check_cuda(cudaMemcpyToSymbol(c_cases, &table, sizeof table), "copying the case table");
    check_cuda(cudaMemcpyToSymbol(c_cell_orders, kCellTetOrders, sizeof kCellTetOrders), "copying the cell split");
    buffers_->scalars.resize(4, "scalars");
}

GpuExtractor::~GpuExtractor() = default;

template <class Tets>
Piece GpuExtractor::Buffers::run(int domain_id, Tets tet_source, std::size_t nodes, std::size_t tets, float level,
                                 GpuExtractTimings& timings, std::chrono::steady_clock::time_point start) {
    Buffers& b = *this;
    // 1. classify
    const unsigned long long no_tet = ULLONG_MAX, zero = 0;
    check_cuda(cudaMemcpyAsync(b.scalars.data(), &zero, sizeof zero, cudaMemcpyHostToDevice, stream), "reset");
    check_cuda(cudaMemcpyAsync(b.scalars.data() + 1, &no_tet, sizeof no_tet, cudaMemcpyHostToDevice, stream), "reset");
    b.above.resize(nodes, "node classes");
    if (nodes) {
        classify_nodes<<<blocks_for(nodes), kBlock, 0, stream>>>(nodes, b.f.data(), level, b.above.data(),
                                                                  b.scalars.data());
        check_launch("classify_nodes");
    }
    if (const unsigned long long bad = b.read_scalar(0)) {
        GlobalId id = 0;
        check_cuda(cudaMemcpy(&id, b.gid.data() + (bad - 1), sizeof id, cudaMemcpyDeviceToHost), "reading a node id");
        extract_rules::throw_bad_value(domain_id, id);
    }

    // 2. count and emit the crossings
    b.pattern.resize(tets, "tetrahedron cases");
    b.crossings.resize(tets + 1, "crossing counts");
    b.triangles_per_tet.resize(tets + 1, "triangle counts");
    b.first_crossing.resize(tets + 1, "crossing offsets");
    b.first_triangle.resize(tets + 1, "triangle offsets");
    check_cuda(cudaMemsetAsync(b.crossings.data() + tets, 0, sizeof(u32), stream), "reset");
    check_cuda(cudaMemsetAsync(b.triangles_per_tet.data() + tets, 0, sizeof(u32), stream), "reset");
    if (tets) {
        count_crossings<<<blocks_for(tets), kBlock, 0, stream>>>(tets, tet_source, static_cast<u32>(nodes),
                                                                  b.above.data(), b.pattern.data(), b.crossings.data(),
                                                                  b.triangles_per_tet.data(), b.scalars.data() + 1);
        check_launch("count_crossings");
    }
    if (const unsigned long long bad = b.read_scalar(1); bad != no_tet)
        extract_rules::throw_bad_tet(domain_id, static_cast<std::int64_t>(bad));
    std::size_t scratch_bytes = 0;
    check_cuda(cub::DeviceScan::ExclusiveSum(nullptr, scratch_bytes, b.crossings.data(), b.first_crossing.data(),
                                             tets + 1, stream),
               "scan");
    check_cuda(cub::DeviceScan::ExclusiveSum(b.scratch_of(scratch_bytes), scratch_bytes, b.crossings.data(),
                                             b.first_crossing.data(), tets + 1, stream),
               "scanning crossing counts");
    check_cuda(cub::DeviceScan::ExclusiveSum(b.scratch_of(scratch_bytes), scratch_bytes, b.triangles_per_tet.data(),
                                             b.first_triangle.data(), tets + 1, stream),
               "scanning triangle counts");
    u32 totals[2] = {0, 0};
    check_cuda(cudaMemcpyAsync(&totals[0], b.first_crossing.data() + tets, sizeof(u32), cudaMemcpyDeviceToHost, stream),
               "reading the crossing count");
    check_cuda(cudaMemcpyAsync(&totals[1], b.first_triangle.data() + tets, sizeof(u32), cudaMemcpyDeviceToHost, stream),
               "reading the triangle count");
    check_cuda(cudaStreamSynchronize(stream), "counting crossings");
    const std::size_t crossing_count = totals[0], triangle_count = totals[1];
    if (triangle_count > static_cast<std::size_t>(INT32_MAX)) extract_rules::throw_too_large(domain_id);

    b.codes.resize(crossing_count, "crossing codes");
    b.sorted_codes.resize(crossing_count, "sorted crossing codes");
    b.edges.resize(crossing_count, "crossing edges");
    if (tets) {
        emit_crossings<<<blocks_for(tets), kBlock, 0, stream>>>(tets, tet_source, b.pattern.data(),
                                                                 b.first_crossing.data(), b.codes.data());
        check_launch("emit_crossings");
    }

    // 3. number: sort (the codes' bits above the largest node index are 0)
    // and drop repeats; vertex i is the i-th crossing edge in (lo, hi) order.
    const int end_bit = 32 + bits_for(nodes);
    std::size_t vertex_count = 0;
    if (crossing_count) {
        scratch_bytes = 0;
        check_cuda(cub::DeviceRadixSort::SortKeys(nullptr, scratch_bytes, b.codes.data(), b.sorted_codes.data(),
                                                  crossing_count, 0, end_bit, stream),
                   "sort");
        check_cuda(cub::DeviceRadixSort::SortKeys(b.scratch_of(scratch_bytes), scratch_bytes, b.codes.data(),
                                                  b.sorted_codes.data(), crossing_count, 0, end_bit, stream),
                   "sorting crossing edges");
        auto* selected = b.scalars.data() + 2;
        scratch_bytes = 0;
        check_cuda(cub::DeviceSelect::Unique(nullptr, scratch_bytes, b.sorted_codes.data(), b.edges.data(), selected,
                                             crossing_count, stream),
                   "unique");
        check_cuda(cub::DeviceSelect::Unique(b.scratch_of(scratch_bytes), scratch_bytes, b.sorted_codes.data(),
                                             b.edges.data(), selected, crossing_count, stream),
                   "removing repeated crossing edges");
        vertex_count = static_cast<std::size_t>(b.read_scalar(2));
    }

    // 4. place, 5. connect
    b.vx.resize(vertex_count, "vertex x");
    b.vy.resize(vertex_count, "vertex y");
    b.vz.resize(vertex_count, "vertex z");
    b.key.resize(vertex_count, "vertex keys");
    b.flags.resize(vertex_count, "vertex flags");
    b.corners.resize(3 * triangle_count, "triangles");
    VertexArrays vertices{b.vx.data(), b.vy.data(), b.vz.data(), b.key.data(), b.flags.data()};
    if (vertex_count) {
        const NodeArrays node{b.x.data(), b.y.data(), b.z.data(), b.f.data(), b.gid.data(), b.interface.data()};
        place_vertices<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.edges.data(), node,
                                                                         b.shared.data(), b.shared.size(), level,
                                                                         vertices);
        check_launch("place_vertices");
        connect<<<blocks_for(tets), kBlock, 0, stream>>>(tets, tet_source, b.pattern.data(), b.first_triangle.data(),
                                                          b.edges.data(), vertex_count, b.gid.data(), b.corners.data());
        check_launch("connect");
    }

    // 6. order by key where local numbering is not global order (unstructured
    // meshes; lattice domains never need it).
    bool reordered = false;
    if (vertex_count > 1) {
        check_cuda(cudaMemsetAsync(b.scalars.data() + 3, 0, sizeof(unsigned long long), stream), "reset");
        find_unsorted<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.key.data(),
                                                                        b.scalars.data() + 3);
        check_launch("find_unsorted");
        reordered = b.read_scalar(3) != 0;
    }
    if (reordered) {
        b.order.resize(vertex_count, "vertex order");
        b.sorted_order.resize(vertex_count, "vertex order");
        b.sorted_key.resize(vertex_count, "sorted keys");
        b.rank.resize(vertex_count, "vertex ranks");
        b.sx.resize(vertex_count, "sorted x");
        b.sy.resize(vertex_count, "sorted y");
        b.sz.resize(vertex_count, "sorted z");
        b.sorted_flags.resize(vertex_count, "sorted flags");
        number_in_order<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.order.data());
        check_launch("number_in_order");
        scratch_bytes = 0;
        check_cuda(cub::DeviceRadixSort::SortPairs(nullptr, scratch_bytes, b.key.data(), b.sorted_key.data(),
                                                   b.order.data(), b.sorted_order.data(), vertex_count, 0, 64, stream),
                   "sort");
        check_cuda(cub::DeviceRadixSort::SortPairs(b.scratch_of(scratch_bytes), scratch_bytes, b.key.data(),
                                                   b.sorted_key.data(), b.order.data(), b.sorted_order.data(),
                                                   vertex_count, 0, 64, stream),
                   "sorting vertices by key");
        vertices = VertexArrays{b.sx.data(), b.sy.data(), b.sz.data(), b.sorted_key.data(), b.sorted_flags.data()};
        gather_vertices<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.sorted_order.data(),
                                                                          b.vx.data(), b.vy.data(), b.vz.data(),
                                                                          b.flags.data(), vertices, b.rank.data());
        check_launch("gather_vertices");
        if (triangle_count) {
            rename_corners<<<blocks_for(3 * triangle_count), kBlock, 0, stream>>>(3 * triangle_count, b.rank.data(),
                                                                                   b.corners.data());
            check_launch("rename_corners");
        }
    }
    check_cuda(cudaStreamSynchronize(stream), "extracting");
    timings.compute = seconds_since(start);
    start = std::chrono::steady_clock::now();

    Piece piece;
    const float* px = reordered ? b.sx.data() : b.vx.data();
    const float* py = reordered ? b.sy.data() : b.vy.data();
    const float* pz = reordered ? b.sz.data() : b.vz.data();
    const EdgeKey* pkey = vertices.key;
    const u8* pflags = vertices.flags;
    auto fetch = [&](auto& host, const auto* device, std::size_t n) {
        host.resize(n);
        if (n)
            check_cuda(cudaMemcpyAsync(host.data(), device, n * sizeof(host[0]), cudaMemcpyDeviceToHost, stream),
                       "downloading the piece");
    };
    fetch(piece.x, px, vertex_count);
    fetch(piece.y, py, vertex_count);
    fetch(piece.z, pz, vertex_count);
    fetch(piece.key, pkey, vertex_count);
    fetch(piece.flags, pflags, vertex_count);
    fetch(piece.triangles, b.corners.data(), 3 * triangle_count);
    check_cuda(cudaStreamSynchronize(stream), "downloading the piece");
    piece.domains = {domain_id};
    timings.download = seconds_since(start);
    return piece;
}

Piece GpuExtractor::extract(const Domain& domain, float level) {
    extract_rules::check_domain(domain);
    extract_rules::check_level(level);
    Buffers& b = *buffers_;
    check_cuda(cudaSetDevice(b.device), "cudaSetDevice");
    const std::size_t tets = domain.tet_count();
    if (tets > UINT32_MAX / 4)
        throw Error(extract_rules::domain_name(domain.id) + ": too many tetrahedra for the GPU path");
    auto start = std::chrono::steady_clock::now();
    b.x.upload(domain.x, b.stream, "uploading x");
    b.y.upload(domain.y, b.stream, "uploading y");
    b.z.upload(domain.z, b.stream, "uploading z");
    b.f.upload(domain.f, b.stream, "uploading f");
    b.gid.upload(domain.gid, b.stream, "uploading node ids");
    b.interface.upload(domain.interface, b.stream, "uploading interface masks");
    b.shared.upload(domain.shared_edges, b.stream, "uploading shared edges");
    b.tets.upload(domain.tets, b.stream, "uploading tetrahedra");
    check_cuda(cudaStreamSynchronize(b.stream), "uploading the domain");
    timings_.upload = seconds_since(start);
    return b.run(domain.id, TetArray{reinterpret_cast<const int4*>(b.tets.data())}, domain.node_count(), tets, level,
                 timings_, std::chrono::steady_clock::now());
}

Piece GpuExtractor::extract(const Decomposition& decomposition, int domain, const std::vector<float>& values,
                            float level) {
    const CellBox& box = decomposition.box(domain);
    const std::size_t nodes = decomposition.node_count(domain);
    if (values.size() != nodes) throw Error(extract_rules::domain_name(domain) + ": node arrays differ in length");
    if (nodes > static_cast<std::size_t>(INT32_MAX) / extract_rules::kBucket)
        throw Error(extract_rules::domain_name(domain) + ": too many nodes for one domain (" + std::to_string(nodes) +
                    ")");
    extract_rules::check_level(level);
    const std::size_t tets = static_cast<std::size_t>(box.cells()) * 6;
    if (tets > UINT32_MAX / 4)
        throw Error(extract_rules::domain_name(domain) + ": too many tetrahedra for the GPU path");
    Buffers& b = *buffers_;
    check_cuda(cudaSetDevice(b.device), "cudaSetDevice");
    auto start = std::chrono::steady_clock::now();
    b.f.upload(values, b.stream, "uploading f");
    check_cuda(cudaStreamSynchronize(b.stream), "uploading the field values");
    timings_.upload = seconds_since(start);

    start = std::chrono::steady_clock::now();
    const std::int64_t n = decomposition.lattice().n();
    LatticeNodes nodes_of{};
    nodes_of.n = n;
    for (int axis = 0; axis < 3; ++axis) nodes_of.lo[axis] = box.lo[static_cast<std::size_t>(axis)];
    nodes_of.nx = box.hi[0] - box.lo[0];
    nodes_of.ny = box.hi[1] - box.lo[1];
    nodes_of.nz = box.hi[2] - box.lo[2];
    nodes_of.px = nodes_of.nx + 1;
    nodes_of.py = nodes_of.ny + 1;
    nodes_of.open_faces = decomposition.open_faces(domain);
    b.x.resize(nodes, "x");
    b.y.resize(nodes, "y");
    b.z.resize(nodes, "z");
    b.gid.resize(nodes, "node ids");
    b.interface.resize(nodes, "interface masks");
    b.shared.resize(0, "shared edges"); // a box's node masks tell its shared edges
    if (nodes) {
        make_lattice_nodes<<<blocks_for(nodes), kBlock, 0, b.stream>>>(nodes, nodes_of, b.x.data(), b.y.data(),
                                                                        b.z.data(), b.gid.data(), b.interface.data());
        check_launch("make_lattice_nodes");
    }
    const LatticeTets tet_source{nodes_of.nx, nodes_of.ny, nodes_of.px, nodes_of.py};
    return b.run(domain, tet_source, nodes, tets, level, timings_, start);
}

} // namespace tetiso
