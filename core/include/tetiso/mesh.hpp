// The two data types that flow through tetiso, both structures of flat arrays
// (docs/ARCHITECTURE.md, "Data"):
//
//   Domain — one part of a tetrahedral mesh with a nodal field, as a solver
//            hands it over: node positions and values, global node ids, which
//            interface faces each node lies on, and tetrahedra.
//   Piece  — a triangulated isosurface (or a part of one): vertex positions,
//            the global edge key of each vertex, per-vertex flags, triangles.
//
// A Piece keeps one invariant that every stage relies on: its vertices are
// sorted by key and the keys are unique. Seaming two pieces is then a linear
// merge, and two pieces of the same surface compare element by element.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tetiso {

using GlobalId = std::int64_t;
using EdgeKey = std::uint64_t;

// Largest global node id that fits in half of an EdgeKey.
inline constexpr GlobalId kMaxGlobalId = (GlobalId{1} << 32) - 1;

// The most threads a stage accepts (ExtractOptions, ReduceOptions, the job's
// tasks). OpenMP takes any count and fails far above the machine's cores:
// libgomp overflows its stack at 10^5 threads and cannot create 5 * 10^4, and
// neither says which option was at fault.
inline constexpr int kMaxThreads = 1024;

// The key of the mesh edge between two nodes: both global ids packed, the
// smaller in the high half. It depends on the edge alone, never on the domain
// that computed it, which is what makes seaming algebraic.
constexpr EdgeKey edge_key(GlobalId a, GlobalId b) {
    const GlobalId lo = a < b ? a : b;
    const GlobalId hi = a < b ? b : a;
    return (static_cast<EdgeKey>(lo) << 32) | static_cast<EdgeKey>(hi);
}
constexpr GlobalId edge_key_low(EdgeKey key) { return static_cast<GlobalId>(key >> 32); }
constexpr GlobalId edge_key_high(EdgeKey key) { return static_cast<GlobalId>(key & 0xffffffffu); }

struct Domain {
    int id = 0;
    std::vector<float> x, y, z;     // node positions
    std::vector<float> f;           // nodal field, linear inside each tetrahedron
    std::vector<GlobalId> gid;      // global node id, unique over the whole mesh
    // Bit s is set when the node lies on interface surface s of this domain
    // (a surface it shares with other domains; the outer boundary of the whole
    // mesh is no interface). An edge lies on an interface exactly when the
    // masks of its two ends share a bit and, where shared_edges is not
    // empty, its key is listed there.
    std::vector<std::uint8_t> interface;
    // For a domain that is no box (a part of an unstructured mesh), whose
    // node masks cannot tell a shared edge from a chord through the domain:
    // the keys of the edges it shares with other domains, sorted.
    std::vector<EdgeKey> shared_edges;
    std::vector<std::int32_t> tets; // 4 local node indices each, positively oriented

    std::size_t node_count() const { return gid.size(); }
    std::size_t tet_count() const { return tets.size() / 4; }
};

// Mean length of a domain's tetrahedron edges, each edge counted once per
// tetrahedron: an unstructured mesh's spacing, the unit of error bounds that
// is h on the lattice. 0 for a domain without tetrahedra.
double mean_edge_length(const Domain& domain);

enum VertexFlag : std::uint8_t {
    // The vertex lies on an interface to a domain that is not part of this
    // piece yet: reduction must neither move nor remove it.
    kLocked = 1u << 0,
};

struct Piece {
    std::vector<float> x, y, z;
    std::vector<EdgeKey> key;           // sorted ascending, unique
    std::vector<std::uint8_t> flags;    // VertexFlag bits
    std::vector<std::int32_t> triangles; // 3 vertex indices each; counter-clockwise
                                         // seen from the side of increasing field
    std::vector<int> domains;           // sorted ids of the domains this piece covers
    // Per triangle, or empty for all zero: the bound on the distance from the
    // raw isosurface's vertices that this triangle's region stands for to the
    // surface. A later reduction takes such a triangle whole as a sample,
    // this bound as its base, and keeps base plus distance under
    // ReduceOptions::max_error, so a region reduced again after a seam
    // spends only what is left of one budget for the whole job; unless the
    // triangle carries its raw vertices (below), which are measured anew.
    std::vector<float> error;
    // Raw isosurface vertices kept for a later reduction of their region (a
    // seam's): sample_xyz holds three coordinates per sample and
    // sample_triangle the triangle that stands for it. A triangle with
    // sampled[t] set stands for exactly the samples it holds (none, maybe),
    // and a reduction measures each again against its new faces, so the
    // bound there is re-spent, not added to. Any other triangle stands for
    // raw vertices within error[t] of it, wherever they are (its samples
    // were dropped as too far from any interface still open). Only with
    // `error` set; `sampled` empty means no triangle is.
    std::vector<float> sample_xyz;
    std::vector<std::int32_t> sample_triangle;
    std::vector<std::uint8_t> sampled;

    std::size_t vertex_count() const { return key.size(); }
    std::size_t triangle_count() const { return triangles.size() / 3; }
    std::size_t sample_count() const { return sample_triangle.size(); }
    bool triangle_sampled(std::size_t t) const { return !sampled.empty() && sampled[t] != 0; }
    float triangle_error(std::size_t t) const { return error.empty() ? 0.0f : error[t]; }
};

// Restores the Piece invariant after a stage that numbered vertices in
// another order: reorders vertices by key (stable) and renumbers triangles.
// Returns false, leaving the piece sorted, if two vertices share a key.
bool order_by_key(Piece& piece);

} // namespace tetiso
