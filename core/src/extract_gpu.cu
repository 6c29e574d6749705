// Marching tetrahedra on a CUDA Device (tetiso/device.hpp). The CPU version
// (extract.cpp) numbers crossings through per-node buckets filled by atomics;
// here every cut tetrahedron writes its crossing edges as 64-bit codes
// (local lo << 32 | local hi), and one radix sort and unique give the vertices
// in (lo, hi) order — the CPU's order, with no bucket to overflow. Triangles
// find their corners by binary search in that sorted list. Each pass is one
// kernel or one CUB primitive on the Gpu's stream, and every scalar the host
// needs (a count, the first bad element) is read once, at a boundary.
//
// Bit-identical to the CPU: a lattice domain's nodes, tetrahedra and
// built-in field, a crossing's placement and a tetrahedron's triangles are
// the per-element functions the CPU calls (lattice_cells.hpp,
// field_formulas.hpp, extract_rules.hpp), compiled with --fmad=false (no
// fused multiply-add, as the host is built with -ffp-contract=off) and IEEE
// division (nvcc's default -prec-div=true).
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
#include "field_formulas.hpp"
#include "device_cuda.cuh"
#include "lattice_cells.hpp"
#include "tetiso/error.hpp"
#include "tetiso/lattice.hpp"

namespace tetiso {
namespace {

using u8 = std::uint8_t;
using u32 = std::uint32_t;
using u64 = std::uint64_t;
using i32 = std::int32_t;

using cuda::check;
using cuda::DeviceArray;

void check_cuda(cudaError_t status, const char* what) { check(status, what); }

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

using cuda::blocks_for;
using cuda::kBlock;

// Grid-stride loops: any element count fits any grid.
#define TETISO_FOR_EACH(i, n) \
    for (std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; i < (n); \
         i += static_cast<std::size_t>(gridDim.x) * blockDim.x)

// A lattice domain's nodes (lattice_cells.hpp) and, for a built-in field,
// its values (field_formulas.hpp): what make_domain and field_values give.
__global__ void make_lattice_nodes(std::size_t count, lattice_cells::Box box, bool evaluate, BuiltinField field,
                                   float* x, float* y, float* z, float* f, GlobalId* gid, u8* interface) {
    TETISO_FOR_EACH(v, count) {
        const lattice_cells::Node node = lattice_cells::node(box, static_cast<std::int64_t>(v));
        x[v] = static_cast<float>(node.x);
        y[v] = static_cast<float>(node.y);
        z[v] = static_cast<float>(node.z);
        gid[v] = node.gid;
        interface[v] = node.interface;
        if (evaluate) f[v] = static_cast<float>(field_formulas::value(field, node.x, node.y, node.z));
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

// Where the per-tetrahedron kernels read a tetrahedron: an uploaded array, or
// the lattice's split computed from the tetrahedron's index.
struct TetArray {
    const int4* corners;
    __device__ int4 operator()(std::size_t t) const { return corners[t]; }
};

struct LatticeTets {
    lattice_cells::Box box;
    __device__ int4 operator()(std::size_t t) const {
        const lattice_cells::Tet tet = lattice_cells::tet(box, static_cast<std::int64_t>(t));
        return make_int4(tet.v[0], tet.v[1], tet.v[2], tet.v[3]);
    }
};

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

struct VertexArrays {
    float *x, *y, *z;
    EdgeKey* key;
    u8* flags;
};

// 4. place: the CPU's placement, extract_rules::place_crossing.
__global__ void place_vertices(std::size_t count, const u64* edges, extract_rules::NodeView node, float level,
                               VertexArrays out) {
    TETISO_FOR_EACH(i, count) {
        const extract_rules::CrossingVertex v =
            extract_rules::place_crossing(node, static_cast<std::size_t>(edges[i] >> 32),
                                          static_cast<std::size_t>(edges[i] & 0xffffffffu), level);
        out.x[i] = v.x;
        out.y[i] = v.y;
        out.z[i] = v.z;
        out.key[i] = v.key;
        out.flags[i] = v.flags;
    }
}

// 5. connect: a cut tetrahedron's one or two triangles (extract_rules::
// emit_triangles), in tetrahedron order.
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
            vertex[k] = static_cast<i32>(lower_bound(edges, vertex_count, code));
            order[k] = edge_key(gid[code >> 32], gid[code & 0xffffffffu]);
        }
        extract_rules::emit_triangles(count, vertex, order, triangles + 3 * static_cast<std::size_t>(first_triangle[t]));
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

std::byte* scratch_of(ExtractionBuffers& b, std::size_t bytes) {
    b.scratch.resize(bytes > 0 ? bytes : 1);
    return b.scratch.data();
}

unsigned long long read_scalar(ExtractionBuffers& b, cudaStream_t stream, std::size_t i) {
    unsigned long long value = 0;
    check_cuda(cudaMemcpyAsync(&value, b.scalars.data() + i, sizeof value, cudaMemcpyDeviceToHost, stream),
               "reading a count");
    check_cuda(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
    return value;
}

// Every pass after the domain's node arrays are on the device (and
// tet_source can read its tetrahedra). The surface stays in the buffers.
template <class Tets>
DeviceSurface run_extraction(ExtractionBuffers& b, cudaStream_t stream, int domain_id, Tets tet_source,
                             std::size_t nodes, std::size_t tets, float level) {
    if (!b.case_table_loaded) {
        const CaseTable table = make_case_table();
        check_cuda(cudaMemcpyToSymbol(c_cases, &table, sizeof table), "copying the case table");
        b.case_table_loaded = true;
    }
    // 1. classify
    const unsigned long long no_tet = ULLONG_MAX, zero = 0;
    check_cuda(cudaMemcpyAsync(b.scalars.data(), &zero, sizeof zero, cudaMemcpyHostToDevice, stream), "reset");
    check_cuda(cudaMemcpyAsync(b.scalars.data() + 1, &no_tet, sizeof no_tet, cudaMemcpyHostToDevice, stream), "reset");
    b.above.resize(nodes);
    if (nodes) {
        classify_nodes<<<blocks_for(nodes), kBlock, 0, stream>>>(nodes, b.f.data(), level, b.above.data(),
                                                                  b.scalars.data());
        check_launch("classify_nodes");
    }
    if (const unsigned long long bad = read_scalar(b, stream, 0)) {
        GlobalId id = 0;
        check_cuda(cudaMemcpy(&id, b.gid.data() + (bad - 1), sizeof id, cudaMemcpyDeviceToHost), "reading a node id");
        extract_rules::throw_bad_value(domain_id, id);
    }

    // 2. count and emit the crossings
    b.pattern.resize(tets);
    b.crossings.resize(tets + 1);
    b.triangles_per_tet.resize(tets + 1);
    b.first_crossing.resize(tets + 1);
    b.first_triangle.resize(tets + 1);
    check_cuda(cudaMemsetAsync(b.crossings.data() + tets, 0, sizeof(u32), stream), "reset");
    check_cuda(cudaMemsetAsync(b.triangles_per_tet.data() + tets, 0, sizeof(u32), stream), "reset");
    if (tets) {
        count_crossings<<<blocks_for(tets), kBlock, 0, stream>>>(tets, tet_source, static_cast<u32>(nodes),
                                                                  b.above.data(), b.pattern.data(), b.crossings.data(),
                                                                  b.triangles_per_tet.data(), b.scalars.data() + 1);
        check_launch("count_crossings");
    }
    if (const unsigned long long bad = read_scalar(b, stream, 1); bad != no_tet)
        extract_rules::throw_bad_tet(domain_id, static_cast<std::int64_t>(bad));
    std::size_t scratch_bytes = 0;
    check_cuda(cub::DeviceScan::ExclusiveSum(nullptr, scratch_bytes, b.crossings.data(), b.first_crossing.data(),
                                             tets + 1, stream),
               "scan");
    check_cuda(cub::DeviceScan::ExclusiveSum(scratch_of(b, scratch_bytes), scratch_bytes, b.crossings.data(),
                                             b.first_crossing.data(), tets + 1, stream),
               "scanning crossing counts");
    check_cuda(cub::DeviceScan::ExclusiveSum(scratch_of(b, scratch_bytes), scratch_bytes, b.triangles_per_tet.data(),
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

    b.codes.resize(crossing_count);
    b.sorted_codes.resize(crossing_count);
    b.edges.resize(crossing_count);
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
        check_cuda(cub::DeviceRadixSort::SortKeys(scratch_of(b, scratch_bytes), scratch_bytes, b.codes.data(),
                                                  b.sorted_codes.data(), crossing_count, 0, end_bit, stream),
                   "sorting crossing edges");
        auto* selected = b.scalars.data() + 2;
        scratch_bytes = 0;
        check_cuda(cub::DeviceSelect::Unique(nullptr, scratch_bytes, b.sorted_codes.data(), b.edges.data(), selected,
                                             crossing_count, stream),
                   "unique");
        check_cuda(cub::DeviceSelect::Unique(scratch_of(b, scratch_bytes), scratch_bytes, b.sorted_codes.data(),
                                             b.edges.data(), selected, crossing_count, stream),
                   "removing repeated crossing edges");
        vertex_count = static_cast<std::size_t>(read_scalar(b, stream, 2));
    }

    // 4. place, 5. connect
    b.vx.resize(vertex_count);
    b.vy.resize(vertex_count);
    b.vz.resize(vertex_count);
    b.key.resize(vertex_count);
    b.flags.resize(vertex_count);
    b.corners.resize(3 * triangle_count);
    VertexArrays vertices{b.vx.data(), b.vy.data(), b.vz.data(), b.key.data(), b.flags.data()};
    if (vertex_count) {
        const extract_rules::NodeView node{b.x.data(),   b.y.data(),         b.z.data(),     b.f.data(),
                                           b.gid.data(), b.interface.data(), b.shared.data(), b.shared.size()};
        place_vertices<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.edges.data(), node, level,
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
        reordered = read_scalar(b, stream, 3) != 0;
    }
    if (reordered) {
        b.order.resize(vertex_count);
        b.sorted_order.resize(vertex_count);
        b.sorted_key.resize(vertex_count);
        b.rank.resize(vertex_count);
        b.sx.resize(vertex_count);
        b.sy.resize(vertex_count);
        b.sz.resize(vertex_count);
        b.sorted_flags.resize(vertex_count);
        number_in_order<<<blocks_for(vertex_count), kBlock, 0, stream>>>(vertex_count, b.order.data());
        check_launch("number_in_order");
        scratch_bytes = 0;
        check_cuda(cub::DeviceRadixSort::SortPairs(nullptr, scratch_bytes, b.key.data(), b.sorted_key.data(),
                                                   b.order.data(), b.sorted_order.data(), vertex_count, 0, 64, stream),
                   "sort");
        check_cuda(cub::DeviceRadixSort::SortPairs(scratch_of(b, scratch_bytes), scratch_bytes, b.key.data(),
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
    return DeviceSurface{vertices.x,    vertices.y, vertices.z, vertices.key, vertices.flags, b.corners.data(),
                         static_cast<std::int32_t>(vertex_count), static_cast<std::int32_t>(triangle_count), domain_id};
}

template <class T, class Allocator>
void upload(DeviceArray<T>& device, const std::vector<T, Allocator>& host, cudaStream_t stream, const char* what) {
    device.resize(host.size());
    if (!host.empty())
        check_cuda(cudaMemcpyAsync(device.data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice, stream),
                   what);
}

} // namespace

DeviceSurface Device::State::extract(const Domain& domain, float level) {
    extract_rules::check_domain(domain);
    extract_rules::check_level(level);
    use_device();
    ExtractionBuffers& b = extraction;
    const std::size_t tets = domain.tet_count();
    if (tets > UINT32_MAX / 4)
        throw Error(extract_rules::domain_name(domain.id) + ": too many tetrahedra for the GPU path");
    auto start = std::chrono::steady_clock::now();
    upload(b.x, domain.x, stream, "uploading x");
    upload(b.y, domain.y, stream, "uploading y");
    upload(b.z, domain.z, stream, "uploading z");
    upload(b.f, domain.f, stream, "uploading f");
    upload(b.gid, domain.gid, stream, "uploading node ids");
    upload(b.interface, domain.interface, stream, "uploading interface masks");
    upload(b.shared, domain.shared_edges, stream, "uploading shared edges");
    upload(b.tets, domain.tets, stream, "uploading tetrahedra");
    check_cuda(cudaStreamSynchronize(stream), "uploading the domain");
    timings.upload = seconds_since(start);
    start = std::chrono::steady_clock::now();
    const DeviceSurface surface = run_extraction(b, stream, domain.id, TetArray{reinterpret_cast<const int4*>(b.tets.data())},
                                                 domain.node_count(), tets, level);
    timings.extract = seconds_since(start);
    return surface;
}

DeviceSurface Device::State::extract(const Decomposition& decomposition, int domain, const Field& field, float level) {
    const CellBox& box = decomposition.box(domain);
    const std::size_t nodes = decomposition.node_count(domain);
    if (nodes > static_cast<std::size_t>(INT32_MAX) / extract_rules::kBucket)
        throw Error(extract_rules::domain_name(domain) + ": too many nodes for one domain (" + std::to_string(nodes) +
                    ")");
    extract_rules::check_level(level);
    const std::size_t tets = static_cast<std::size_t>(box.cells()) * 6;
    if (tets > UINT32_MAX / 4)
        throw Error(extract_rules::domain_name(domain) + ": too many tetrahedra for the GPU path");
    use_device();
    ExtractionBuffers& b = extraction;
    auto start = std::chrono::steady_clock::now();
    // A built-in field is evaluated on the device; another (an expression)
    // on the host, its values uploaded.
    const std::optional<BuiltinField> builtin = field.builtin();
    if (!builtin) upload(b.f, decomposition.field_values(domain, field), stream, "uploading f");
    else b.f.resize(nodes);
    check_cuda(cudaStreamSynchronize(stream), "uploading the field values");
    timings.upload = seconds_since(start);

    start = std::chrono::steady_clock::now();
    const lattice_cells::Box cells = lattice_cells::box_of(decomposition.lattice(), box, decomposition.open_faces(domain));
    b.x.resize(nodes);
    b.y.resize(nodes);
    b.z.resize(nodes);
    b.gid.resize(nodes);
    b.interface.resize(nodes);
    b.shared.resize(0); // a box's node masks tell its shared edges
    if (nodes) {
        make_lattice_nodes<<<blocks_for(nodes), kBlock, 0, stream>>>(
            nodes, cells, builtin.has_value(), builtin.value_or(BuiltinField::paper), b.x.data(), b.y.data(), b.z.data(),
            b.f.data(), b.gid.data(), b.interface.data());
        check_launch("make_lattice_nodes");
    }
    const DeviceSurface surface = run_extraction(b, stream, domain, LatticeTets{cells}, nodes, tets, level);
    timings.extract = seconds_since(start);
    return surface;
}

Piece Device::State::download(const DeviceSurface& s) {
    const auto start = std::chrono::steady_clock::now();
    Piece piece;
    auto fetch = [&](auto& host, const auto* device, std::size_t n) {
        host.resize(n);
        if (n)
            check_cuda(cudaMemcpyAsync(host.data(), device, n * sizeof(host[0]), cudaMemcpyDeviceToHost, stream),
                       "downloading the piece");
    };
    const auto nv = static_cast<std::size_t>(s.vertices), nt = static_cast<std::size_t>(s.triangle_count);
    fetch(piece.x, s.x, nv);
    fetch(piece.y, s.y, nv);
    fetch(piece.z, s.z, nv);
    fetch(piece.key, s.key, nv);
    fetch(piece.flags, s.flags, nv);
    fetch(piece.triangles, s.triangles, 3 * nt);
    check_cuda(cudaStreamSynchronize(stream), "downloading the piece");
    piece.domains = {s.domain};
    timings.download = seconds_since(start);
    return piece;
}

} // namespace tetiso
