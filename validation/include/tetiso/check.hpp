// The topology checker: what tests, benchmarks and `tetiso check` measure on a
// surface (docs/ARCHITECTURE.md, "Validation"). Reduction and seaming must
// keep the topology of every component — genus, boundary loops,
// orientability — and must not create non-manifold spots, inverted or
// degenerate triangles; and the reduced surface must stay close to the
// original. Both are measured here on any indexed triangle mesh: nothing is
// assumed about manifoldness, orientation or cleanliness, so the checker can
// describe broken meshes instead of crashing on them.
//
//   check_topology  counts, components, Euler characteristic and genus per
//                   component, boundary loops, non-manifold edges and
//                   vertices, orientation, degenerate triangles, angles
//                   (check.cpp; sorting and union-find on flat arrays)
//   hausdorff       symmetric Hausdorff distance estimated from dense
//                   deterministic samples with exact point-to-triangle
//                   distances (hausdorff.cpp; a BVH on flat arrays)
//   find_self_intersections  optional, through CGAL
//                   (self_intersections_cgal.cpp)
//   contract_violations  the surface contract as a gate, one line per
//                   violated clause (contract.cpp)
//
// Only the triangles and x, y, z of a Piece are read; keys, flags and domains
// are ignored, so meshes built by hand in tests need not fill them.
#pragma once

#include <array>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "tetiso/mesh.hpp"

namespace tetiso {

// Throws tetiso::Error naming `what` (e.g. "mesh a") if x, y, z differ in
// length, a coordinate is NaN or infinite, the triangle array is not a
// multiple of 3, an index is out of range, or the mesh is too large for
// 32-bit half-edge ids. check_topology, hausdorff and
// count_self_intersections call it first.
void validate_indexed_mesh(const Piece& mesh, std::string_view what = "mesh");

// What makes two components the same surface up to homeomorphism.
// `genus` is the orientable genus for orientable components and the number of
// cross-caps (non-orientable genus, 2 - chi - b) for non-orientable ones.
// Meaningful for manifold components only; see ComponentReport::manifold.
struct TopologySignature {
    std::int64_t genus = 0;
    std::int64_t boundary_loops = 0;
    bool orientable = true;
    auto operator<=>(const TopologySignature&) const = default;
};

struct ComponentReport {
    std::int64_t vertices = 0;        // referenced vertices of the component
    std::int64_t edges = 0;
    std::int64_t triangles = 0;       // triangles kept for topology (not collapsed)
    std::int64_t euler = 0;           // vertices - edges + triangles
    std::int64_t boundary_edges = 0;
    std::int64_t boundary_loops = 0;
    std::int64_t genus = 0;           // as in TopologySignature
    // Orientation is judged across edges of exactly two triangles: a
    // non-manifold edge allows no consistent orientation and is reported
    // through non_manifold_edges instead.
    bool orientable = true;           // a consistent orientation exists
    bool oriented = true;             // the given orientation is consistent
    std::int64_t misoriented_edges = 0;
    std::int64_t non_manifold_edges = 0;
    std::int64_t non_manifold_vertices = 0;
    bool manifold = true;             // no non-manifold edge or vertex
    std::int32_t first_vertex = 0;    // smallest vertex index: names the component

    TopologySignature signature() const { return {genus, boundary_loops, orientable}; }
};

// Minimum angle of each triangle, in degrees, over the triangles that are
// neither collapsed nor of zero area.
struct AngleStats {
    std::int64_t triangles = 0;       // triangles measured
    double min = 0.0;                 // 0 when no triangle was measured
    double p01 = 0.0;                 // 1st percentile (nearest rank)
    double mean = 0.0;
    std::int64_t below_1 = 0;         // strictly below 1, 5 and 10 degrees
    std::int64_t below_5 = 0;
    std::int64_t below_10 = 0;
};

struct CheckOptions {
    // Triangles whose minimum angle is below this (degrees) count as near
    // degenerate; collapsed and zero-area triangles are counted apart.
    double near_degenerate_angle_deg = 1.0;
};

// Where a problem is, so that a user can find it: the mesh's own indices
// and a point to look at. `vertices` holds the triangle's three corners, an
// edge's two ends (smaller first) or the one vertex; `at` is their centroid.
struct ProblemSpot {
    std::int64_t triangle = -1; // for a degenerate triangle, else -1
    std::vector<std::int32_t> vertices;
    std::array<double, 3> at{};
};

// The first problems of each kind, in the order of the mesh's indices
// (triangles for degenerate ones, then edges by their smaller and larger end,
// vertices by index), at most kMaxProblemSpots each: the counts in
// TopologyReport say how many there are in all.
inline constexpr std::size_t kMaxProblemSpots = 8;
struct ProblemSpots {
    std::vector<ProblemSpot> degenerate_triangles; // collapsed or zero area
    // Vertices of one position: the group's first kMaxProblemSpots vertices
    // in index order, the groups in the order of their first vertex.
    std::vector<ProblemSpot> duplicate_positions;
    std::vector<ProblemSpot> non_manifold_edges;
    std::vector<ProblemSpot> non_manifold_vertices;
    std::vector<ProblemSpot> misoriented_edges;
};

struct TopologyReport {
    std::int64_t vertices = 0;             // all vertices, referenced or not
    std::int64_t triangles = 0;            // all triangles
    std::int64_t referenced_vertices = 0;  // used by a non-collapsed triangle
    std::int64_t edges = 0;                // distinct undirected edges
    std::int64_t components = 0;           // connected through shared vertices
    std::int64_t euler = 0;                // referenced_vertices - edges + (triangles - collapsed)

    std::int64_t boundary_edges = 0;       // edges of exactly 1 triangle
    std::int64_t boundary_loops = 0;
    std::int64_t non_manifold_edges = 0;   // edges of 3 or more triangles
    // Vertices whose triangles, joined across shared edges, form 2+ fans
    // (a bow-tie); the ends of a non-manifold edge count only if they are
    // pinched as well, the edge itself is counted above.
    std::int64_t non_manifold_vertices = 0;
    std::int64_t misoriented_edges = 0;    // 2-triangle edges run the same way by both
    std::int64_t duplicate_triangles = 0;  // same vertex set as an earlier triangle

    // A triangle with a repeated vertex index is "collapsed": it has no
    // surface and is left out of every count above except `triangles`.
    std::int64_t collapsed_triangles = 0;
    std::int64_t zero_area_triangles = 0;  // distinct indices, float cross product exactly 0
    std::int64_t degenerate_triangles = 0; // collapsed + zero area
    std::int64_t near_degenerate_triangles = 0;
    double near_degenerate_angle_deg = 1.0;
    // Vertices whose x, y, z are bit-identical to those of another vertex,
    // counted without the first of each group (how many a merge would remove).
    std::int64_t duplicate_positions = 0;

    bool closed = true;                    // no boundary edge
    bool manifold = true;                  // no non-manifold edge or vertex
    bool orientable = true;                // every component orientable
    bool oriented = true;                  // misoriented_edges == 0

    AngleStats min_angle;
    ProblemSpots where;

    // Ordered by first_vertex, so reports of the same mesh compare equal.
    std::vector<ComponentReport> per_component;
    // Signatures of all components, sorted: equal lists mean the two surfaces
    // have the same components up to homeomorphism (for manifold components).
    std::vector<TopologySignature> signatures;
};

// O(n log n) in time, O(n) in memory; never recursive. Throws tetiso::Error
// (see validate_indexed_mesh) on malformed input, never on bad topology.
TopologyReport check_topology(const Piece& mesh, const CheckOptions& options = {});

// True when both reports have the same sorted list of component signatures.
bool same_signatures(const TopologyReport& a, const TopologyReport& b);

struct HausdorffOptions {
    // Each triangle is sampled on a barycentric grid of k x k sub-triangles
    // (one sample at each sub-triangle's centroid, k^2 in all) with
    // k = round(longest edge / (sqrt(3) spacing)), clamped to
    // [1, max_subdivisions], in addition to every referenced vertex; so
    // neighbouring samples are about `spacing` apart. spacing <= 0 chooses
    // the smaller of the two meshes' mean edge lengths: the coarse mesh is
    // sampled about as densely as the fine one has vertices.
    double spacing = 0.0;
    int max_subdivisions = 64;
    // Sample the referenced vertices only: forward is then exactly the
    // largest distance of a's vertices to b, the quantity that
    // ReduceOptions::max_error bounds (reduce(in) with a = in).
    bool vertices_only = false;
};

struct HausdorffReport {
    double forward = 0.0;           // max over samples of a of the distance to b
    double backward = 0.0;          // max over samples of b of the distance to a
    double symmetric = 0.0;         // max(forward, backward)
    double mean_forward = 0.0;
    double mean_backward = 0.0;
    double mean = 0.0;              // over the samples of both meshes together
    double diagonal = 0.0;          // bounding-box diagonal of a's referenced vertices
    double relative = 0.0;          // symmetric / diagonal (0 when diagonal is 0)
    double spacing = 0.0;           // the sample spacing used
    std::int64_t samples_a = 0;
    std::int64_t samples_b = 0;
    std::array<double, 3> forward_at{};   // sample of a where forward is reached
    std::array<double, 3> backward_at{};  // sample of b where backward is reached
};

// Estimates the symmetric Hausdorff distance between the surfaces of a and b
// from samples (see HausdorffOptions); each sample's distance to the other
// surface is exact (up to double rounding). The estimate can only be below
// the true value, by at most about the sample spacing. Collapsed triangles
// are ignored; unreferenced vertices are not sampled.
// Two meshes without triangles give an all-zero report; if only one of them
// has no triangle the distance is undefined and tetiso::Error is thrown.
// Deterministic: the result does not depend on the number of threads.
HausdorffReport hausdorff(const Piece& a, const Piece& b, const HausdorffOptions& options = {});

// The JSON that `tetiso check` prints: snake_case keys as named above, the
// angle statistics under "min_angle_deg" (min, p01 and mean null when no
// triangle was measured), the components under "per_component" and the
// signatures as {"genus", "boundary_loops", "orientable"} objects.
nlohmann::json to_json(const TopologyReport& report);
nlohmann::json to_json(const HausdorffReport& report);

// Two triangles of a mesh, by index, first < second.
struct TrianglePair {
    std::int64_t first = 0;
    std::int64_t second = 0;
    auto operator<=>(const TrianglePair&) const = default;
};

// The pairs of triangles that intersect other than in a shared vertex or
// edge, sorted, from CGAL::Polygon_mesh_processing::self_intersections.
// nullopt when tetiso was built without CGAL, or when the mesh cannot be made
// a CGAL surface mesh without splitting it (non-manifold or non-orientable,
// which check_topology reports). Collapsed triangles are ignored; zero-area
// ones are not counted as intersecting.
std::optional<std::vector<TrianglePair>> find_self_intersections(const Piece& mesh);

// How many pairs find_self_intersections finds.
std::optional<std::size_t> count_self_intersections(const Piece& mesh);

// Whether count_self_intersections can ever answer (tetiso built with CGAL).
bool have_self_intersections();

// The surface contract that every surface tetiso writes keeps
// (docs/ARCHITECTURE.md, "Contracts"), as a gate: one line per violated
// clause, naming the count and where the first instance is — degenerate
// triangles (collapsed or of zero float area), duplicate positions,
// self-intersections (when measured: nullopt adds no line), duplicate
// triangles, non-manifold edges or vertices, misoriented edges or
// non-orientable components, and, given a reference (the unreduced surface),
// component signatures that differ from its. Empty when the surface is
// clean. contract.cpp.
std::vector<std::string> contract_violations(const Piece& mesh, const TopologyReport& report,
                                             const std::optional<std::vector<TrianglePair>>& self_intersections,
                                             const TopologyReport* reference = nullptr);

// The first kMaxProblemSpots pairs as {"triangles": [a, b], "at": a's centroid}.
nlohmann::json to_json(const std::vector<TrianglePair>& pairs, const Piece& mesh);

std::array<double, 3> triangle_centroid(const Piece& mesh, std::int64_t triangle);

} // namespace tetiso
