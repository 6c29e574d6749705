// Marching tetrahedra (paper, section "Isosurface generation algorithm",
// steps 1-6) written once over the data-parallel backends (exec_host.hpp,
// exec_cuda.cuh), as Viskores' contour filter is over its devices: a CUDA
// Device (extract_gpu.cu) runs them, and so does the host where its own
// bucket numbering does not apply (extract.cpp), with the per-element
// functions the host's numbering uses too (extract_rules.hpp), so every
// piece is the same bytes.
//
//  1. classify every node as above or below the level;
//  2. count each tetrahedron's crossings and triangles, and scan the counts;
//  3. number: every cut tetrahedron writes its crossing edges as 64-bit codes
//     (local lo << 32 | local hi); sorted, repeats dropped, vertex i is the
//     i-th crossing edge in (lo, hi) order;
//  4. place each vertex on its edge;
//  5. connect: each cut tetrahedron finds its corners by binary search among
//     the numbered edges, its triangles written in tetrahedron order;
//  6. order the vertices by key where local numbering is not global order
//     (unstructured meshes; lattice domains never need it).
//
// The tetrahedron source is a template parameter: an array of corners
// (TetArray), or the lattice's cells computed from a tetrahedron's index
// (LatticeTets), which a device evaluates without the array ever existing.
#pragma once

#include <climits>
#include <cmath>
#include <cstdint>

#include "extract_rules.hpp"
#include "lattice_cells.hpp"

namespace tetiso::marching {

using i32 = std::int32_t;
using i64 = std::int64_t;
using u8 = std::uint8_t;
using u32 = std::uint32_t;
using u64 = std::uint64_t;

// The case table as the per-element code reads it, passed by value (a device
// reads it from its kernels' parameters): per pattern, the crossing count
// and the two tet-corner numbers of each crossing's edge, in case order.
struct CaseTable {
    i32 crossings[16];
    i32 corner[16][4][2];
};

constexpr CaseTable make_case_table() {
    CaseTable table{};
    for (int p = 0; p < 16; ++p) {
        const extract_rules::MarchCase& c = extract_rules::kCases[static_cast<std::size_t>(p)];
        table.crossings[p] = c.crossings;
        for (int k = 0; k < 4; ++k)
            for (int end = 0; end < 2; ++end)
                table.corner[p][k][end] = extract_rules::kEdgesOfTet[c.edge[static_cast<std::size_t>(k)]][end];
    }
    return table;
}

// The pattern of a tetrahedron naming a node that does not exist.
constexpr u8 kBadTet = 16;

struct Corners {
    i32 v[4];
};

struct TetArray {
    const i32* tets; // 4 local node indices each
    TETISO_HD Corners operator()(i64 t) const {
        const i32* c = tets + 4 * t;
        return Corners{{c[0], c[1], c[2], c[3]}};
    }
};

struct LatticeTets {
    lattice_cells::Box box;
    TETISO_HD Corners operator()(i64 t) const {
        const lattice_cells::Tet tet = lattice_cells::tet(box, t);
        return Corners{{tet.v[0], tet.v[1], tet.v[2], tet.v[3]}};
    }
};

TETISO_HD inline u64 edge_code(const Corners& v, const CaseTable& cases, unsigned pattern, int k) {
    const i32 a = v.v[cases.corner[pattern][k][0]], b = v.v[cases.corner[pattern][k][1]];
    const i32 lo = a < b ? a : b, hi = a < b ? b : a;
    return (static_cast<u64>(lo) << 32) | static_cast<u32>(hi);
}

TETISO_HD inline bool is_finite(float value) {
#ifdef __CUDA_ARCH__
    return isfinite(value);
#else
    return std::isfinite(value);
#endif
}

// The first position in sorted[0, n) not below key.
TETISO_HD inline i64 lower_bound(const u64* sorted, i64 n, u64 key) {
    i64 lo = 0, hi = n;
    while (lo < hi) {
        const i64 mid = lo + (hi - lo) / 2;
        if (sorted[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

// What the passes keep, in the backend's memory (a CUDA Device keeps them
// from one domain to the next).
template <class Exec>
struct Arrays {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<u8> above, pattern;
    Array<u32> first_crossing, first_triangle;
    Array<u64> codes, edges;
    Array<i32> found;      // indices of bad nodes or tetrahedra, when there are any
    Array<GlobalId> id;    // a bad node's id, read back
    // The surface, and its vertices again in key order where they are not.
    Array<float> x, y, z, sorted_x, sorted_y, sorted_z;
    Array<EdgeKey> key, sorted_key;
    Array<u8> flags, sorted_flags;
    Array<i32> corners, order, rank;
};

// The extracted surface, in the passes' arrays (valid until the next call).
struct Surface {
    const float *x, *y, *z;
    const EdgeKey* key;
    const u8* flags;
    const i32* triangles;
    i32 vertices, triangle_count;
};

// A pattern's crossings and triangles from the number of its corners
// above the level, k: every edge from one of the k to one of the others is
// crossed. The scans read them so rather than from the case table, which a
// functor would carry into every thread of the device's scan.
TETISO_HD constexpr u32 crossings_of(unsigned pattern) {
    const unsigned above = (pattern & 1u) + ((pattern >> 1) & 1u) + ((pattern >> 2) & 1u) + ((pattern >> 3) & 1u);
    return above * (4u - above);
}
TETISO_HD constexpr u32 triangles_of(unsigned pattern) {
    const u32 crossings = crossings_of(pattern);
    return crossings == 4 ? 2 : (crossings == 3 ? 1 : 0);
}
constexpr bool counts_match_cases() {
    for (unsigned p = 0; p < 16; ++p)
        if (crossings_of(p) != static_cast<u32>(extract_rules::kCases[p].crossings)) return false;
    return true;
}
static_assert(counts_match_cases(), "the crossings of a pattern are those of its case");

inline int bits_for(i64 n) {
    int bits = 1;
    while (bits < 32 && (i64{1} << bits) < n) ++bits;
    return bits;
}

// The node arrays `node` (nodes of them) and `tets` are in the backend's
// memory. Throws the errors extract() documents, the same on every backend:
// the largest node with a value that is not finite, the smallest
// tetrahedron naming a node that does not exist.
template <class Exec, class Tets>
Surface march(Exec& exec, Arrays<Exec>& a, const extract_rules::NodeView& node, i64 nodes, const Tets& tets,
              i64 tet_count, float level, int domain_id) {
    if (tet_count > static_cast<i64>(UINT32_MAX / 4))
        throw Error(extract_rules::domain_name(domain_id) + ": too many tetrahedra for one domain");
    const CaseTable cases = make_case_table();

    // 1. classify
    a.above.resize(static_cast<std::size_t>(nodes));
    u8* above = a.above.data();
    const float* f = node.f;
    exec.for_each(nodes, [=] TETISO_HD(i64 v) { above[v] = f[v] >= level ? 1 : 0; });
    if (exec.count(nodes, [=] TETISO_HD(i64 v) { return !is_finite(f[v]); }) > 0) {
        const i32 bad = exec.filter(nodes, [=] TETISO_HD(i64 v) { return !is_finite(f[v]); }, a.found);
        const i64 last = exec.get(a.found, bad - 1);
        a.id.resize(1);
        GlobalId* id = a.id.data();
        const GlobalId* gid = node.gid;
        exec.for_each(1, [=] TETISO_HD(i64) { id[0] = gid[last]; });
        extract_rules::throw_bad_value(domain_id, exec.get(a.id, 0));
    }

    // 2. count
    a.pattern.resize(static_cast<std::size_t>(tet_count));
    u8* pattern = a.pattern.data();
    const auto node_limit = static_cast<u32>(nodes);
    exec.for_each(tet_count, [=] TETISO_HD(i64 t) {
        const Corners v = tets(t);
        bool bad = false;
        for (int k = 0; k < 4; ++k) bad = bad || static_cast<u32>(v.v[k]) >= node_limit;
        pattern[t] = bad ? kBadTet
                         : static_cast<u8>(above[v.v[0]] | (above[v.v[1]] << 1) | (above[v.v[2]] << 2) |
                                           (above[v.v[3]] << 3));
    });
    if (exec.count(tet_count, [=] TETISO_HD(i64 t) { return pattern[t] == kBadTet; }) > 0) {
        exec.filter(tet_count, [=] TETISO_HD(i64 t) { return pattern[t] == kBadTet; }, a.found);
        extract_rules::throw_bad_tet(domain_id, exec.get(a.found, 0));
    }
    const u64 crossing_count =
        exec.exclusive_sum(tet_count, [=] TETISO_HD(i64 t) { return crossings_of(pattern[t]); }, a.first_crossing);
    const u64 triangle_count =
        exec.exclusive_sum(tet_count, [=] TETISO_HD(i64 t) { return triangles_of(pattern[t]); }, a.first_triangle);
    if (triangle_count > static_cast<u64>(INT32_MAX)) extract_rules::throw_too_large(domain_id);

    // 3. number (the codes' bits above the largest node index are 0)
    a.codes.resize(static_cast<std::size_t>(crossing_count));
    u64* codes = a.codes.data();
    const u32* first_crossing = a.first_crossing.data();
    exec.for_each(tet_count, [=] TETISO_HD(i64 t) {
        const unsigned p = pattern[t];
        const int count = cases.crossings[p];
        if (count == 0) return;
        const Corners v = tets(t);
        u64* out = codes + first_crossing[t];
        for (int k = 0; k < count; ++k) out[k] = edge_code(v, cases, p, k);
    });
    const i64 vertex_count =
        exec.sort_unique(a.codes, static_cast<i64>(crossing_count), 32 + bits_for(nodes), a.edges);
    if (vertex_count > static_cast<i64>(INT32_MAX)) extract_rules::throw_too_large(domain_id);

    // 4. place
    a.x.resize(static_cast<std::size_t>(vertex_count));
    a.y.resize(static_cast<std::size_t>(vertex_count));
    a.z.resize(static_cast<std::size_t>(vertex_count));
    a.key.resize(static_cast<std::size_t>(vertex_count));
    a.flags.resize(static_cast<std::size_t>(vertex_count));
    float *x = a.x.data(), *y = a.y.data(), *z = a.z.data();
    EdgeKey* key = a.key.data();
    u8* flags = a.flags.data();
    const u64* edges = a.edges.data();
    exec.for_each(vertex_count, [=] TETISO_HD(i64 i) {
        const extract_rules::CrossingVertex v =
            extract_rules::place_crossing(node, static_cast<std::size_t>(edges[i] >> 32),
                                          static_cast<std::size_t>(edges[i] & 0xffffffffu), level);
        x[i] = v.x;
        y[i] = v.y;
        z[i] = v.z;
        key[i] = v.key;
        flags[i] = v.flags;
    });

    // 5. connect
    a.corners.resize(static_cast<std::size_t>(3 * triangle_count));
    i32* corners = a.corners.data();
    const u32* first_triangle = a.first_triangle.data();
    const GlobalId* gid = node.gid;
    exec.for_each(tet_count, [=] TETISO_HD(i64 t) {
        const unsigned p = pattern[t];
        const int count = cases.crossings[p];
        if (count == 0) return;
        const Corners v = tets(t);
        i32 vertex[4];
        EdgeKey order[4]; // global key of each crossing, to split quads the same way in every domain
        for (int k = 0; k < count; ++k) {
            const u64 code = edge_code(v, cases, p, k);
            vertex[k] = static_cast<i32>(lower_bound(edges, vertex_count, code));
            order[k] = edge_key(gid[code >> 32], gid[code & 0xffffffffu]);
        }
        extract_rules::emit_triangles(count, vertex, order, corners + 3 * static_cast<i64>(first_triangle[t]));
    });

    // 6. order by key
    Surface s{x, y, z, key, flags, corners, static_cast<i32>(vertex_count), static_cast<i32>(triangle_count)};
    const i64 pairs = vertex_count > 0 ? vertex_count - 1 : 0;
    if (exec.count(pairs, [=] TETISO_HD(i64 i) { return key[i] > key[i + 1]; }) > 0) {
        exec.order_by_key(a.key, vertex_count, a.order);
        a.sorted_x.resize(static_cast<std::size_t>(vertex_count));
        a.sorted_y.resize(static_cast<std::size_t>(vertex_count));
        a.sorted_z.resize(static_cast<std::size_t>(vertex_count));
        a.sorted_key.resize(static_cast<std::size_t>(vertex_count));
        a.sorted_flags.resize(static_cast<std::size_t>(vertex_count));
        a.rank.resize(static_cast<std::size_t>(vertex_count));
        float *sx = a.sorted_x.data(), *sy = a.sorted_y.data(), *sz = a.sorted_z.data();
        EdgeKey* sorted_key = a.sorted_key.data();
        u8* sorted_flags = a.sorted_flags.data();
        i32* rank = a.rank.data();
        const i32* order = a.order.data();
        exec.for_each(vertex_count, [=] TETISO_HD(i64 i) {
            const i32 from = order[i];
            sx[i] = x[from];
            sy[i] = y[from];
            sz[i] = z[from];
            sorted_key[i] = key[from];
            sorted_flags[i] = flags[from];
            rank[from] = static_cast<i32>(i);
        });
        exec.for_each(3 * static_cast<i64>(triangle_count), [=] TETISO_HD(i64 i) { corners[i] = rank[corners[i]]; });
        s = Surface{sx, sy, sz, sorted_key, sorted_flags, corners, s.vertices, s.triangle_count};
    }
    // Keys repeat only if node ids do, which check_domain refuses.
    const EdgeKey* sorted = s.key;
    if (exec.count(pairs, [=] TETISO_HD(i64 i) { return sorted[i] == sorted[i + 1]; }) > 0)
        throw InternalError(extract_rules::domain_name(domain_id) + ": two vertices of the surface share a key");
    return s;
}

} // namespace tetiso::marching
