// Marching tetrahedra over one domain on the host (paper, section
// "Isosurface generation algorithm", steps 1-6). The passes every backend
// shares are marching_tets.hpp's; the host keeps a numbering of its own,
// fused with the march, since on the host it is several times faster than
// sorting the crossing edges (bench_extract):
//
//   1. classify   node -> above (f >= level; equality counts as above, so the
//                 classification of a node never depends on its domain);
//   2. march      tetrahedron -> case; each crossing edge (lo, hi) of a cut
//                 tetrahedron claims a slot in the bucket of its lower local
//                 node (8 slots: a lattice node has 7 higher neighbours), and
//                 the triangles are emitted as slot codes in tetrahedron order;
//   3. number     per node, the filled slots sorted by the higher node give the
//                 vertices, numbered by a prefix sum: vertex order is (lo, hi),
//                 whatever the thread count, and for lattice domains that is
//                 the order of the global edge keys;
//   4. place      each vertex is interpolated from the end with the smaller
//                 global id, keyed, and locked if its edge lies on an interface;
//   5. connect    slot codes are replaced by vertex numbers.
//
// A node with more than 8 higher crossing neighbours (possible in unstructured
// meshes, never in the lattice) sends the whole domain through the shared
// passes, which number by sorting and give the same result. A CUDA Device in
// the options sends the domain to extract_gpu.cu, which runs the shared passes.
#include "tetiso/extract.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "device_entry.hpp"
#include "exec_host.hpp"
#include "extract_rules.hpp"
#include "marching_tets.hpp"
#include "parallel.hpp"
#include "tetiso/error.hpp"


namespace tetiso {
namespace {

using extract_rules::domain_name;
using extract_rules::kBucket;
using extract_rules::kCases;
using extract_rules::kEdgesOfTet;
using extract_rules::MarchCase;

constexpr std::int32_t kEmpty = -1;
constexpr std::size_t kTetChunk = 1 << 15;

// Finds or claims the slot of edge (lo, hi) in lo's bucket; returns its code
// lo * kBucket + slot (check_domain keeps it within int32), or -1 if the
// bucket is full.
template <bool Concurrent>
std::int32_t claim(std::int32_t* slots, std::int32_t lo, std::int32_t hi) {
    std::int32_t* bucket = slots + static_cast<std::int64_t>(lo) * kBucket;
    for (int s = 0; s < kBucket; ++s) {
        if constexpr (Concurrent) {
            std::atomic_ref<std::int32_t> slot(bucket[s]);
            std::int32_t seen = slot.load(std::memory_order_relaxed);
            if (seen == kEmpty && slot.compare_exchange_strong(seen, hi, std::memory_order_relaxed)) seen = hi;
            if (seen == hi) return lo * kBucket + s;
        } else {
            if (bucket[s] == kEmpty) bucket[s] = hi;
            if (bucket[s] == hi) return lo * kBucket + s;
        }
    }
    return -1;
}

// Triangles of one chunk of tetrahedra, as slot codes.
struct ChunkOutput {
    std::vector<std::int32_t> corners;
    bool overflow = false;
    std::int64_t bad_tet = -1;
};

template <bool Concurrent>
void march_chunk(const Domain& domain, const std::uint8_t* above, std::int32_t* slots, std::size_t first,
                 std::size_t last, ChunkOutput& out) {
    const std::int32_t* tets = domain.tets.data();
    const auto nodes = static_cast<std::uint32_t>(domain.node_count());
    out.corners.reserve((last - first) / 2); // about the most a chunk of a smooth surface emits
    for (std::size_t t = first; t < last; ++t) {
        const std::int32_t* v = tets + 4 * t;
        if (static_cast<std::uint32_t>(v[0]) >= nodes || static_cast<std::uint32_t>(v[1]) >= nodes ||
            static_cast<std::uint32_t>(v[2]) >= nodes || static_cast<std::uint32_t>(v[3]) >= nodes) {
            out.bad_tet = static_cast<std::int64_t>(t);
            return;
        }
        const unsigned pattern = above[v[0]] | (above[v[1]] << 1) | (above[v[2]] << 2) | (above[v[3]] << 3);
        if (pattern == 0 || pattern == 15) continue;
        const MarchCase& c = kCases[pattern];
        std::int32_t code[4];
        EdgeKey order[4]; // global key of each crossing, to split quads the same way in every domain
        for (int k = 0; k < c.crossings; ++k) {
            const std::int32_t a = v[kEdgesOfTet[c.edge[static_cast<std::size_t>(k)]][0]];
            const std::int32_t b = v[kEdgesOfTet[c.edge[static_cast<std::size_t>(k)]][1]];
            const std::int32_t lo = std::min(a, b), hi = std::max(a, b);
            code[k] = claim<Concurrent>(slots, lo, hi);
            if (code[k] < 0) {
                out.overflow = true;
                return;
            }
            if (c.crossings == 4)
                order[k] = edge_key(domain.gid[static_cast<std::size_t>(a)], domain.gid[static_cast<std::size_t>(b)]);
        }
        std::int32_t corners[6];
        const int emitted = extract_rules::emit_triangles(c.crossings, code, order, corners);
        out.corners.insert(out.corners.end(), corners, corners + emitted);
    }
}

extract_rules::NodeView node_view(const Domain& domain) {
    return {domain.x.data(), domain.y.data(), domain.z.data(), domain.f.data(), domain.gid.data(),
            domain.interface.data(), domain.shared_edges.data(), domain.shared_edges.size()};
}

void place_vertex(const extract_rules::NodeView& node, float level, std::int32_t lo, std::int32_t hi, Piece& piece,
                  std::size_t vertex) {
    const extract_rules::CrossingVertex v =
        extract_rules::place_crossing(node, static_cast<std::size_t>(lo), static_cast<std::size_t>(hi), level);
    piece.x[vertex] = v.x;
    piece.y[vertex] = v.y;
    piece.z[vertex] = v.z;
    piece.key[vertex] = v.key;
    piece.flags[vertex] = v.flags;
}

void resize_vertices(Piece& piece, std::size_t n) {
    piece.x.resize(n);
    piece.y.resize(n);
    piece.z.resize(n);
    piece.key.resize(n);
    piece.flags.resize(n);
}

template <class T, class Allocator>
void copy_out(const T* from, std::size_t n, std::vector<T, Allocator>& to) {
    to.assign(from, from + n);
}

// The fallback: the passes every backend shares (marching_tets.hpp), whose
// numbering sorts the crossing edges instead of bucketing them. Used only
// when a bucket overflows.
Piece extract_by_passes(const Domain& domain, float level, int threads) {
    HostExec exec;
    exec.threads = threads;
    marching::Arrays<HostExec> arrays;
    const marching::Surface s =
        marching::march(exec, arrays, node_view(domain), static_cast<std::int64_t>(domain.node_count()),
                        marching::TetArray{domain.tets.data()}, static_cast<std::int64_t>(domain.tet_count()), level,
                        domain.id);
    Piece piece;
    const auto nv = static_cast<std::size_t>(s.vertices);
    copy_out(s.x, nv, piece.x);
    copy_out(s.y, nv, piece.y);
    copy_out(s.z, nv, piece.z);
    copy_out(s.key, nv, piece.key);
    copy_out(s.flags, nv, piece.flags);
    copy_out(s.triangles, 3 * static_cast<std::size_t>(s.triangle_count), piece.triangles);
    return piece;
}

} // namespace

void extract_rules::check_domain(const Domain& domain) {
    const std::size_t n = domain.node_count();
    if (domain.x.size() != n || domain.y.size() != n || domain.z.size() != n || domain.f.size() != n ||
        domain.interface.size() != n)
        throw Error(domain_name(domain.id) + ": node arrays differ in length");
    if (domain.tets.size() % 4 != 0) throw Error(domain_name(domain.id) + ": tetrahedron array is not a multiple of 4");
    if (!std::is_sorted(domain.shared_edges.begin(), domain.shared_edges.end()))
        throw Error(domain_name(domain.id) + ": shared edge keys are not sorted");
    if (n > static_cast<std::size_t>(INT32_MAX) / kBucket)
        throw Error(domain_name(domain.id) + ": too many nodes for one domain (" + std::to_string(n) + ")");
    // Vertex keys are made of node ids: a repeated id would give two vertices
    // one key. Ids in ascending order (the lattice's, most files') are
    // checked in one pass.
    if (std::adjacent_find(domain.gid.begin(), domain.gid.end(), std::greater_equal<GlobalId>()) != domain.gid.end()) {
        std::vector<GlobalId> sorted = domain.gid;
        std::sort(sorted.begin(), sorted.end());
        const auto repeated = std::adjacent_find(sorted.begin(), sorted.end());
        if (repeated != sorted.end())
            throw Error(domain_name(domain.id) + ": node id " + std::to_string(*repeated) + " appears more than once");
    }
}

namespace {

Piece extract_on_host(const Domain& domain, float level, int threads) {
    extract_rules::check_domain(domain);
    const std::size_t nodes = domain.node_count();
    const std::size_t tets = domain.tet_count();
    extract_rules::check_level(level);

    // 1. classify
    std::vector<std::uint8_t> above(nodes);
    std::int64_t bad_node = -1;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(max : bad_node)
    for (std::int64_t v = 0; v < static_cast<std::int64_t>(nodes); ++v) {
        const float value = domain.f[static_cast<std::size_t>(v)];
        if (!std::isfinite(value)) bad_node = std::max(bad_node, v);
        above[static_cast<std::size_t>(v)] = value >= level ? 1 : 0;
    }
    if (bad_node >= 0) extract_rules::throw_bad_value(domain.id, domain.gid[static_cast<std::size_t>(bad_node)]);

    // 2. march
    std::vector<std::int32_t> slots(nodes * kBucket, kEmpty);
    const std::size_t chunks = (tets + kTetChunk - 1) / kTetChunk;
    std::vector<ChunkOutput> outputs(chunks);
    if (threads == 1 || chunks == 1) {
        for (std::size_t c = 0; c < chunks; ++c)
            march_chunk<false>(domain, above.data(), slots.data(), c * kTetChunk, std::min(tets, (c + 1) * kTetChunk),
                               outputs[c]);
    } else {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
        for (std::int64_t c = 0; c < static_cast<std::int64_t>(chunks); ++c) {
            const auto chunk = static_cast<std::size_t>(c);
            march_chunk<true>(domain, above.data(), slots.data(), chunk * kTetChunk,
                              std::min(tets, (chunk + 1) * kTetChunk), outputs[chunk]);
        }
    }
    bool overflow = false;
    for (const ChunkOutput& out : outputs) {
        if (out.bad_tet >= 0) extract_rules::throw_bad_tet(domain.id, out.bad_tet);
        overflow = overflow || out.overflow;
    }
    Piece piece;
    if (overflow) {
        piece = extract_by_passes(domain, level, threads);
    } else {
        // 3. number: vertices of node v are first[v] .. first[v] + filled(v) - 1
        std::vector<std::int32_t> first(nodes + 1, 0);
        for (std::size_t v = 0; v < nodes; ++v) {
            const std::int32_t* bucket = slots.data() + v * kBucket;
            int filled = 0;
            while (filled < kBucket && bucket[filled] != kEmpty) ++filled;
            first[v + 1] = first[v] + filled;
        }
        resize_vertices(piece, static_cast<std::size_t>(first[nodes]));

        // 4. place; the bucket's slots are rewritten from higher node to vertex
        const extract_rules::NodeView nodes_of = node_view(domain);
#pragma omp parallel for num_threads(threads) schedule(static, 4096)
        for (std::int64_t node = 0; node < static_cast<std::int64_t>(nodes); ++node) {
            const auto v = static_cast<std::size_t>(node);
            const int filled = first[v + 1] - first[v];
            if (filled == 0) continue;
            std::int32_t* bucket = slots.data() + v * kBucket;
            std::int32_t higher[kBucket];
            std::copy(bucket, bucket + filled, higher);
            for (int s = 0; s < filled; ++s) {
                int rank = 0;
                for (int r = 0; r < filled; ++r) rank += higher[r] < higher[s] ? 1 : 0;
                const std::size_t vertex = static_cast<std::size_t>(first[v] + rank);
                place_vertex(nodes_of, level, static_cast<std::int32_t>(node), higher[s], piece, vertex);
                bucket[s] = static_cast<std::int32_t>(vertex);
            }
        }

        // 5. connect
        std::vector<std::size_t> offset(chunks + 1, 0);
        for (std::size_t c = 0; c < chunks; ++c) offset[c + 1] = offset[c] + outputs[c].corners.size();
        piece.triangles.resize(offset[chunks]);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
        for (std::int64_t c = 0; c < static_cast<std::int64_t>(chunks); ++c) {
            const auto chunk = static_cast<std::size_t>(c);
            std::int32_t* out = piece.triangles.data() + offset[chunk];
            for (const std::int32_t code : outputs[chunk].corners) *out++ = slots[static_cast<std::size_t>(code)];
            std::vector<std::int32_t>().swap(outputs[chunk].corners);
        }
    }
    if (piece.triangles.size() / 3 > static_cast<std::size_t>(INT32_MAX))
        extract_rules::throw_too_large(domain.id);
    // Lattice domains number nodes in global order, so this is a no-op there.
    // Keys repeat only if node ids do, which check_domain refuses.
    if (!order_by_key(piece))
        throw InternalError(domain_name(domain.id) + ": two vertices of the surface share a key");
    piece.domains = {domain.id};
    return piece;
}

} // namespace

Piece extract(const Domain& domain, float level, const ExtractOptions& options, StageSeconds* seconds) {
    const int threads = parallel::resolve_threads(options.threads); // checked whatever the device
    if (options.device.is_gpu()) return on_gpu::extract(options.device.state(), domain, level, nullptr, nullptr, seconds);
    const auto start = std::chrono::steady_clock::now();
    Piece piece = extract_on_host(domain, level, threads);
    if (seconds) seconds->extract += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return piece;
}

} // namespace tetiso
