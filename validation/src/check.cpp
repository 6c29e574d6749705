// Topology of an indexed triangle mesh, for tests, benchmarks and
// `tetiso check` (check.hpp). Reduction and seaming are only correct if every
// component keeps its genus, boundary loops and orientability and no
// non-manifold spot or degenerate triangle appears; this file measures those
// on any mesh, clean or not, in O(n log n) without recursion:
//
//   1. collapsed triangles (a repeated index) are set aside: they have no
//      surface, and keeping them would invent loop edges and double edges;
//   2. components: union-find over vertices, joined by each triangle;
//   3. edges: half-edges bucketed by their smaller end (a counting sort),
//      each bucket sorted by the other end, so equal edges are adjacent runs;
//      one pass over the runs counts boundary (1 triangle), manifold (2) and
//      non-manifold (3+) edges, orientation, and joins
//        - triangle orientations, in a union-find with parity (two
//          triangles across a 2-triangle edge must agree; a contradiction
//          in a component makes it non-orientable),
//        - the corners of each vertex across shared edges (the sets left are
//          the fans around the vertex; 2+ fans make it non-manifold);
//   4. boundary loops: boundary edges are paired at each vertex, inside one
//      fan where possible (that is how a loop continues at a vertex where
//      several loops meet, e.g. two disks touching at a rim vertex), then a
//      union-find over boundary edges counts the loops. Undirected, so a
//      non-orientable boundary (Möbius strip) is one loop, not a broken walk;
//   5. per component: chi = V - E + F and genus (2 - chi - b) / 2;
//   6. geometry: zero-area triangles (float cross product exactly 0), the
//      minimum angle of each triangle, duplicate positions (bit-identical).
// Union-find roots are always the smallest index of their set, so every label
// and every count is independent of the order of the work.
#include "tetiso/check.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <numeric>
#include <utility>
#include <string>

#include "tetiso/error.hpp"

namespace tetiso {

namespace {

// Path halving keeps finds short without recursion; linking the larger root
// under the smaller keeps roots deterministic (the set's smallest index).
std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

void unite(std::vector<std::int32_t>& parent, std::int32_t a, std::int32_t b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a < b) parent[b] = a;
    else if (b < a) parent[a] = b;
}

// Union-find where each element also carries one bit relative to its parent:
// whether its orientation must be flipped to agree with the parent's. Parent
// and bit share one word (parent << 1 | bit): one cache miss per step, not two.
struct ParityForest {
    std::vector<std::uint32_t> link;

    explicit ParityForest(std::size_t n) : link(n) {
        for (std::size_t i = 0; i < n; ++i) link[i] = static_cast<std::uint32_t>(i) << 1;
    }

    // Root of x, and x's parity relative to it.
    std::pair<std::uint32_t, std::uint32_t> find(std::uint32_t x) {
        std::uint32_t acc = 0;
        while ((link[x] >> 1) != x) {
            const std::uint32_t up = link[x] >> 1;
            if ((link[up] >> 1) != up) // halve the path, folding the parity in
                link[x] = (link[up] & ~1u) | ((link[x] ^ link[up]) & 1u);
            acc ^= link[x] & 1u;
            x = link[x] >> 1;
        }
        return {x, acc};
    }

    // Records "parity(a) xor parity(b) == relation"; false if that
    // contradicts what is already known.
    bool unite(std::uint32_t a, std::uint32_t b, std::uint32_t relation) {
        const auto [ra, pa] = find(a);
        const auto [rb, pb] = find(b);
        if (ra == rb) return (pa ^ pb) == relation;
        link[std::max(ra, rb)] = std::min(ra, rb) << 1 | (pa ^ pb ^ relation);
        return true;
    }
};

// floor(n / 2) for negative n as well: genus of a non-manifold component can
// come out odd or negative, and should still be reproducible.
std::int64_t floor_half(std::int64_t n) { return n >= 0 ? n / 2 : -((-n + 1) / 2); }

// The corner of triangle h / 3 at `vertex`, given half-edge h of that
// triangle that starts or ends at `vertex`.
std::uint32_t corner_at(const std::int32_t* tri, std::uint32_t h, std::int32_t vertex) {
    if (tri[h] == vertex) return h;
    const std::uint32_t t = h / 3;
    return 3 * t + (h % 3 + 1) % 3;
}

struct BoundaryEnd {
    std::int32_t vertex;
    std::int32_t fan;    // root corner of the fan the boundary edge bounds here
    std::int32_t other;  // the edge's other end
    std::int32_t edge;   // index into the boundary edge list
    auto operator<=>(const BoundaryEnd&) const = default;
};

// Pairs the boundary edges meeting at each vertex and counts the loops they
// form; per-component counts go to loops_per_component.
std::int64_t count_boundary_loops(const std::int32_t* tri,
                                  const std::vector<std::uint32_t>& boundary_half_edges,
                                  std::vector<std::int32_t>& corner_parent,
                                  const std::vector<std::int32_t>& component,
                                  std::vector<std::int64_t>& loops_per_component) {
    const std::size_t nb = boundary_half_edges.size();
    std::vector<BoundaryEnd> ends;
    ends.reserve(2 * nb);
    for (std::size_t e = 0; e < nb; ++e) {
        const std::uint32_t h = boundary_half_edges[e];
        const std::int32_t a = tri[h];
        const std::int32_t b = tri[3 * (h / 3) + (h % 3 + 1) % 3];
        ends.push_back({a, find_root(corner_parent, static_cast<std::int32_t>(h)), b,
                        static_cast<std::int32_t>(e)});
        ends.push_back({b, find_root(corner_parent, static_cast<std::int32_t>(corner_at(tri, h, b))),
                        a, static_cast<std::int32_t>(e)});
    }
    std::sort(ends.begin(), ends.end());

    std::vector<std::int32_t> parent(nb);
    std::iota(parent.begin(), parent.end(), 0);
    std::vector<std::int32_t> leftover;
    for (std::size_t g = 0; g < ends.size();) {
        std::size_t g_end = g;
        while (g_end < ends.size() && ends[g_end].vertex == ends[g].vertex) ++g_end;
        // Inside one fan the boundary edges come in pairs (an open fan has
        // two ends); edges of fans with an odd count (only next to
        // non-manifold edges) are paired among themselves in sorted order,
        // and a last odd one ends an open chain, still counted as a loop.
        leftover.clear();
        for (std::size_t f = g; f < g_end;) {
            std::size_t f_end = f;
            while (f_end < g_end && ends[f_end].fan == ends[f].fan) ++f_end;
            std::size_t i = f;
            for (; i + 1 < f_end; i += 2) unite(parent, ends[i].edge, ends[i + 1].edge);
            if (i < f_end) leftover.push_back(ends[i].edge);
            f = f_end;
        }
        for (std::size_t i = 0; i + 1 < leftover.size(); i += 2) unite(parent, leftover[i], leftover[i + 1]);
        g = g_end;
    }

    std::int64_t loops = 0;
    for (std::size_t e = 0; e < nb; ++e) {
        if (find_root(parent, static_cast<std::int32_t>(e)) != static_cast<std::int32_t>(e)) continue;
        ++loops;
        ++loops_per_component[component[tri[boundary_half_edges[e]]]];
    }
    return loops;
}

// Minimum angle of each kept triangle in degrees, or -1 for zero-area ones
// (float cross product exactly 0). Independent per triangle, so parallel and
// still deterministic.
std::vector<float> minimum_angles(const Piece& mesh, const std::vector<std::uint8_t>& kept) {
    const std::int64_t nt = static_cast<std::int64_t>(mesh.triangle_count());
    const std::int32_t* tri = mesh.triangles.data();
    std::vector<float> angle(static_cast<std::size_t>(nt), -1.0f);
#if defined(_OPENMP)
#pragma omp parallel for schedule(static)
#endif
    for (std::int64_t t = 0; t < nt; ++t) {
        if (!kept[t]) continue;
        const std::int32_t v[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
        // The zero-area test is done in float on purpose: it is the
        // precision the mesh is stored and rendered in.
        const float ux = mesh.x[v[1]] - mesh.x[v[0]], uy = mesh.y[v[1]] - mesh.y[v[0]], uz = mesh.z[v[1]] - mesh.z[v[0]];
        const float wx = mesh.x[v[2]] - mesh.x[v[0]], wy = mesh.y[v[2]] - mesh.y[v[0]], wz = mesh.z[v[2]] - mesh.z[v[0]];
        const float cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
        if (cx == 0.0f && cy == 0.0f && cz == 0.0f) continue;

        double p[3][3];
        for (int i = 0; i < 3; ++i) p[i][0] = mesh.x[v[i]], p[i][1] = mesh.y[v[i]], p[i][2] = mesh.z[v[i]];
        // The smallest angle faces the shortest edge; atan2 of |cross| and
        // dot stays accurate for angles near 0 where acos does not.
        double len2[3];
        for (int i = 0; i < 3; ++i) {
            const double* q = p[(i + 1) % 3];
            const double* r = p[(i + 2) % 3];
            len2[i] = (q[0] - r[0]) * (q[0] - r[0]) + (q[1] - r[1]) * (q[1] - r[1]) + (q[2] - r[2]) * (q[2] - r[2]);
        }
        const int s = len2[0] <= len2[1] ? (len2[0] <= len2[2] ? 0 : 2) : (len2[1] <= len2[2] ? 1 : 2);
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) e1[k] = p[(s + 1) % 3][k] - p[s][k], e2[k] = p[(s + 2) % 3][k] - p[s][k];
        const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double cross = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        const double dot = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
        angle[t] = static_cast<float>(std::atan2(cross, dot) * (180.0 / std::numbers::pi));
    }
    return angle;
}

// Open addressing on the bit patterns: linear time, where sorting 96-bit
// keys was a large part of the whole check. Equality is bitwise, as asked:
// 0.0 and -0.0 differ, and a NaN would equal its own copy (none get here).
// Returns each duplicate as (first vertex of its position, the duplicate).
std::vector<std::pair<std::int32_t, std::int32_t>> find_duplicate_positions(const Piece& mesh) {
    const std::size_t nv = mesh.x.size();
    auto bits = [&mesh](std::size_t v) {
        return std::array<std::uint32_t, 3>{std::bit_cast<std::uint32_t>(mesh.x[v]), std::bit_cast<std::uint32_t>(mesh.y[v]),
                                            std::bit_cast<std::uint32_t>(mesh.z[v])};
    };
    const std::size_t size = std::bit_ceil(2 * nv + 1);
    std::vector<std::int32_t> table(size, -1);
    std::vector<std::pair<std::int32_t, std::int32_t>> duplicates;
    for (std::size_t v = 0; v < nv; ++v) {
        const std::array<std::uint32_t, 3> b = bits(v);
        std::uint64_t h = (static_cast<std::uint64_t>(b[0]) << 32 | b[1]) * 0x9e3779b97f4a7c15ull;
        h = (h ^ (h >> 29) ^ b[2]) * 0xbf58476d1ce4e5b9ull;
        for (std::size_t slot = (h ^ (h >> 32)) & (size - 1);; slot = (slot + 1) & (size - 1)) {
            if (table[slot] < 0) {
                table[slot] = static_cast<std::int32_t>(v);
                break;
            }
            if (bits(static_cast<std::size_t>(table[slot])) == b) {
                duplicates.emplace_back(table[slot], static_cast<std::int32_t>(v));
                break;
            }
        }
    }
    return duplicates;
}

// Records a problem spot unless `spots` holds kMaxProblemSpots already.
void note_spot(std::vector<ProblemSpot>& spots, const Piece& mesh, std::int64_t triangle,
               std::initializer_list<std::int32_t> vertices) {
    if (spots.size() >= kMaxProblemSpots) return;
    ProblemSpot& spot = spots.emplace_back();
    spot.triangle = triangle;
    spot.vertices.assign(vertices);
    for (const std::int32_t v : vertices) {
        spot.at[0] += mesh.x[static_cast<std::size_t>(v)];
        spot.at[1] += mesh.y[static_cast<std::size_t>(v)];
        spot.at[2] += mesh.z[static_cast<std::size_t>(v)];
    }
    for (double& c : spot.at) c /= static_cast<double>(vertices.size());
}

} // namespace

void validate_indexed_mesh(const Piece& mesh, std::string_view what) {
    const std::string name(what);
    const std::size_t nv = mesh.x.size();
    if (mesh.y.size() != nv || mesh.z.size() != nv)
        throw Error(name + ": x, y, z have different lengths (" + std::to_string(mesh.x.size()) + ", " +
                    std::to_string(mesh.y.size()) + ", " + std::to_string(mesh.z.size()) + ")");
    if (mesh.triangles.size() % 3 != 0)
        throw Error(name + ": triangle index array has " + std::to_string(mesh.triangles.size()) +
                    " entries, not a multiple of 3");
    // Half-edge ids are 32-bit in the checker: 3 per triangle.
    if (nv > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) ||
        mesh.triangles.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
        throw Error(name + ": too large for 32-bit indices (" + std::to_string(nv) + " vertices, " +
                    std::to_string(mesh.triangle_count()) + " triangles)");
    for (std::size_t v = 0; v < nv; ++v)
        if (!std::isfinite(mesh.x[v]) || !std::isfinite(mesh.y[v]) || !std::isfinite(mesh.z[v]))
            throw Error(name + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const std::int32_t v = mesh.triangles[i];
        if (v < 0 || static_cast<std::size_t>(v) >= nv)
            throw Error(name + ": triangle " + std::to_string(i / 3) + " has vertex index " + std::to_string(v) +
                        " outside [0, " + std::to_string(nv) + ")");
    }
}

TopologyReport check_topology(const Piece& mesh, const CheckOptions& options) {
    validate_indexed_mesh(mesh);
    if (!(options.near_degenerate_angle_deg >= 0.0 && options.near_degenerate_angle_deg <= 60.0))
        throw Error("check: near-degenerate angle must be in [0, 60] degrees, not " +
                    std::to_string(options.near_degenerate_angle_deg));

    const std::size_t nv = mesh.x.size();
    const std::size_t nt = mesh.triangle_count();
    const std::int32_t* tri = mesh.triangles.data();
    TopologyReport r;
    r.vertices = static_cast<std::int64_t>(nv);
    r.triangles = static_cast<std::int64_t>(nt);
    r.near_degenerate_angle_deg = options.near_degenerate_angle_deg;

    // 1. Collapsed triangles.
    std::vector<std::uint8_t> kept(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        const std::int32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
        kept[t] = a != b && b != c && a != c;
        r.collapsed_triangles += !kept[t];
    }

    // 2. Components through shared vertices, numbered by smallest vertex.
    std::vector<std::int32_t> vertex_parent(nv);
    std::iota(vertex_parent.begin(), vertex_parent.end(), 0);
    std::vector<std::uint8_t> referenced(nv, 0);
    for (std::size_t t = 0; t < nt; ++t) {
        if (!kept[t]) continue;
        unite(vertex_parent, tri[3 * t], tri[3 * t + 1]);
        unite(vertex_parent, tri[3 * t], tri[3 * t + 2]);
        referenced[tri[3 * t]] = referenced[tri[3 * t + 1]] = referenced[tri[3 * t + 2]] = 1;
    }
    std::vector<std::int32_t> component(nv, -1);
    std::vector<ComponentReport>& pc = r.per_component;
    for (std::size_t v = 0; v < nv; ++v) {
        if (!referenced[v]) continue;
        const std::int32_t root = find_root(vertex_parent, static_cast<std::int32_t>(v));
        if (root == static_cast<std::int32_t>(v)) {
            component[v] = static_cast<std::int32_t>(pc.size());
            pc.emplace_back().first_vertex = root;
        } else {
            component[v] = component[root]; // roots are smallest, so already numbered
        }
        ++pc[component[v]].vertices;
        ++r.referenced_vertices;
    }
    vertex_parent = {};
    for (std::size_t t = 0; t < nt; ++t)
        if (kept[t]) ++pc[component[tri[3 * t]]].triangles;

    // 3. Half-edges h = 3t + i (from corner i to corner i+1 of triangle t),
    //    bucketed by their smaller end; entry = other end << 32 | h, so a
    //    plain sort of a bucket groups equal edges in half-edge order.
    std::vector<std::uint64_t> offset(nv + 1, 0);
    for (std::size_t t = 0; t < nt; ++t) {
        if (!kept[t]) continue;
        const std::int32_t v[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
        for (int i = 0; i < 3; ++i) ++offset[std::min(v[i], v[(i + 1) % 3]) + 1];
    }
    std::partial_sum(offset.begin(), offset.end(), offset.begin());
    std::vector<std::uint64_t> entry(offset[nv]);
    {
        std::vector<std::uint64_t> fill(offset.begin(), offset.end() - 1);
        for (std::size_t t = 0; t < nt; ++t) {
            if (!kept[t]) continue;
            const std::int32_t v[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
            for (int i = 0; i < 3; ++i) {
                const std::int32_t a = v[i], b = v[(i + 1) % 3];
                entry[fill[std::min(a, b)]++] = static_cast<std::uint64_t>(std::max(a, b)) << 32 | (3 * t + i);
            }
        }
    }
    // Buckets are independent: sort them in parallel, walk them in order.
    const std::int64_t nv64 = static_cast<std::int64_t>(nv);
#if defined(_OPENMP)
#pragma omp parallel for schedule(dynamic, 4096)
#endif
    for (std::int64_t v = 0; v < nv64; ++v)
        std::sort(entry.begin() + static_cast<std::ptrdiff_t>(offset[v]),
                  entry.begin() + static_cast<std::ptrdiff_t>(offset[v + 1]));

    std::vector<std::int32_t> corner_parent(3 * nt);
    std::iota(corner_parent.begin(), corner_parent.end(), 0);
    ParityForest orientation(nt);
    std::vector<std::uint8_t> contradiction(pc.size(), 0);
    std::vector<std::uint32_t> boundary;
    std::vector<std::int32_t> thirds;
    for (std::size_t v = 0; v < nv; ++v) {
        const auto first = entry.begin() + static_cast<std::ptrdiff_t>(offset[v]);
        const auto last = entry.begin() + static_cast<std::ptrdiff_t>(offset[v + 1]);
        const std::int32_t lo = static_cast<std::int32_t>(v);
        for (auto run = first; run != last;) {
            const std::int32_t hi = static_cast<std::int32_t>(*run >> 32);
            auto run_end = run + 1;
            while (run_end != last && static_cast<std::int32_t>(*run_end >> 32) == hi) ++run_end;
            const std::ptrdiff_t m = run_end - run;
            ComponentReport& c = pc[component[lo]];
            ++r.edges;
            ++c.edges;
            const std::uint32_t h0 = static_cast<std::uint32_t>(*run);
            if (m == 1) {
                boundary.push_back(h0);
                ++c.boundary_edges;
            } else {
                if (m >= 3) {
                    ++c.non_manifold_edges;
                    note_spot(r.where.non_manifold_edges, mesh, -1, {lo, hi});
                }
                if (m == 2) {
                    const std::uint32_t h1 = static_cast<std::uint32_t>(run[1]);
                    const bool same_way = tri[h0] == tri[h1];
                    c.misoriented_edges += same_way;
                    if (same_way) note_spot(r.where.misoriented_edges, mesh, -1, {lo, hi});
                    if (!orientation.unite(h0 / 3, h1 / 3, same_way ? 1u : 0u))
                        contradiction[component[lo]] = 1;
                }
                // Triangles sharing an edge share the fan of both its ends.
                thirds.clear();
                for (auto it = run; it != run_end; ++it) {
                    const std::uint32_t h = static_cast<std::uint32_t>(*it);
                    if (it != run) {
                        unite(corner_parent, static_cast<std::int32_t>(corner_at(tri, h0, lo)),
                              static_cast<std::int32_t>(corner_at(tri, h, lo)));
                        unite(corner_parent, static_cast<std::int32_t>(corner_at(tri, h0, hi)),
                              static_cast<std::int32_t>(corner_at(tri, h, hi)));
                    }
                    // A triangle is looked at for duplicates only at the edge
                    // of its two smallest vertices: its third is the largest.
                    const std::int32_t third = tri[3 * (h / 3) + (h % 3 + 2) % 3];
                    if (third > hi) thirds.push_back(third);
                }
                std::sort(thirds.begin(), thirds.end());
                for (std::size_t i = 1; i < thirds.size(); ++i) r.duplicate_triangles += thirds[i] == thirds[i - 1];
            }
            run = run_end;
        }
    }
    entry = {};
    offset = {};

    // Fans: one root corner per fan, so counting roots per vertex counts fans.
    std::vector<std::int32_t> fans(nv, 0);
    for (std::size_t k = 0; k < 3 * nt; ++k)
        if (kept[k / 3] && find_root(corner_parent, static_cast<std::int32_t>(k)) == static_cast<std::int32_t>(k))
            ++fans[tri[k]];
    for (std::size_t v = 0; v < nv; ++v)
        if (fans[v] > 1) {
            ++pc[component[v]].non_manifold_vertices;
            note_spot(r.where.non_manifold_vertices, mesh, -1, {static_cast<std::int32_t>(v)});
        }

    // 4. Boundary loops.
    std::vector<std::int64_t> loops(pc.size(), 0);
    r.boundary_loops = count_boundary_loops(tri, boundary, corner_parent, component, loops);

    // 5. Per component, and the totals.
    for (std::size_t i = 0; i < pc.size(); ++i) {
        ComponentReport& c = pc[i];
        c.euler = c.vertices - c.edges + c.triangles;
        c.boundary_loops = loops[i];
        c.orientable = !contradiction[i];
        c.oriented = c.misoriented_edges == 0;
        c.manifold = c.non_manifold_edges == 0 && c.non_manifold_vertices == 0;
        const std::int64_t k = 2 - c.euler - c.boundary_loops;
        c.genus = c.orientable ? floor_half(k) : k;
        r.boundary_edges += c.boundary_edges;
        r.non_manifold_edges += c.non_manifold_edges;
        r.non_manifold_vertices += c.non_manifold_vertices;
        r.misoriented_edges += c.misoriented_edges;
        r.orientable = r.orientable && c.orientable;
        r.signatures.push_back(c.signature());
    }
    std::sort(r.signatures.begin(), r.signatures.end());
    r.components = static_cast<std::int64_t>(pc.size());
    r.euler = r.referenced_vertices - r.edges + (r.triangles - r.collapsed_triangles);
    r.closed = r.boundary_edges == 0;
    r.manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
    r.oriented = r.misoriented_edges == 0;

    // 6. Geometry.
    const std::vector<float> angle = minimum_angles(mesh, kept);
    std::vector<float> measured;
    measured.reserve(nt);
    double sum = 0.0; // serial, in triangle order: reproducible
    for (std::size_t t = 0; t < nt; ++t) {
        if (!kept[t] || angle[t] < 0.0f)
            note_spot(r.where.degenerate_triangles, mesh, static_cast<std::int64_t>(t),
                      {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]});
        if (!kept[t]) continue;
        if (angle[t] < 0.0f) {
            ++r.zero_area_triangles;
            continue;
        }
        const double a = angle[t];
        measured.push_back(angle[t]);
        sum += a;
        r.min_angle.below_1 += a < 1.0;
        r.min_angle.below_5 += a < 5.0;
        r.min_angle.below_10 += a < 10.0;
        r.near_degenerate_triangles += a < options.near_degenerate_angle_deg;
    }
    r.degenerate_triangles = r.collapsed_triangles + r.zero_area_triangles;
    AngleStats& s = r.min_angle;
    s.triangles = static_cast<std::int64_t>(measured.size());
    if (!measured.empty()) {
        s.mean = sum / static_cast<double>(measured.size());
        s.min = *std::min_element(measured.begin(), measured.end());
        const std::size_t rank = static_cast<std::size_t>(std::ceil(0.01 * static_cast<double>(measured.size())));
        const auto nth = measured.begin() + static_cast<std::ptrdiff_t>(std::max<std::size_t>(rank, 1) - 1);
        std::nth_element(measured.begin(), nth, measured.end());
        s.p01 = *nth;
    }
    std::vector<std::pair<std::int32_t, std::int32_t>> duplicates = find_duplicate_positions(mesh);
    r.duplicate_positions = static_cast<std::int64_t>(duplicates.size());
    std::sort(duplicates.begin(), duplicates.end());
    for (std::size_t i = 0; i < duplicates.size() && r.where.duplicate_positions.size() < kMaxProblemSpots;) {
        const std::int32_t first = duplicates[i].first;
        ProblemSpot& spot = r.where.duplicate_positions.emplace_back();
        spot.vertices.push_back(first);
        for (; i < duplicates.size() && duplicates[i].first == first; ++i)
            if (spot.vertices.size() < kMaxProblemSpots) spot.vertices.push_back(duplicates[i].second);
        spot.at = {mesh.x[static_cast<std::size_t>(first)], mesh.y[static_cast<std::size_t>(first)],
                   mesh.z[static_cast<std::size_t>(first)]};
    }
    return r;
}

bool same_signatures(const TopologyReport& a, const TopologyReport& b) { return a.signatures == b.signatures; }

nlohmann::json to_json(const TopologyReport& r) {
    using nlohmann::json;
    json components = json::array();
    for (const ComponentReport& c : r.per_component)
        components.push_back({{"first_vertex", c.first_vertex},
                              {"vertices", c.vertices},
                              {"edges", c.edges},
                              {"triangles", c.triangles},
                              {"euler", c.euler},
                              {"boundary_edges", c.boundary_edges},
                              {"boundary_loops", c.boundary_loops},
                              {"genus", c.genus},
                              {"orientable", c.orientable},
                              {"oriented", c.oriented},
                              {"misoriented_edges", c.misoriented_edges},
                              {"non_manifold_edges", c.non_manifold_edges},
                              {"non_manifold_vertices", c.non_manifold_vertices},
                              {"manifold", c.manifold}});
    json signatures = json::array();
    for (const TopologySignature& s : r.signatures)
        signatures.push_back({{"genus", s.genus}, {"boundary_loops", s.boundary_loops}, {"orientable", s.orientable}});
    // No measured triangle: the statistics are undefined, say so with null.
    const bool any = r.min_angle.triangles > 0;
    const json min_angle = {{"triangles", r.min_angle.triangles},
                            {"min", any ? json(r.min_angle.min) : json(nullptr)},
                            {"p01", any ? json(r.min_angle.p01) : json(nullptr)},
                            {"mean", any ? json(r.min_angle.mean) : json(nullptr)},
                            {"below_1", r.min_angle.below_1},
                            {"below_5", r.min_angle.below_5},
                            {"below_10", r.min_angle.below_10}};
    auto spots = [](const std::vector<ProblemSpot>& list) {
        json out = json::array();
        for (const ProblemSpot& spot : list) {
            json item = {{"vertices", spot.vertices}, {"at", spot.at}};
            if (spot.triangle >= 0) item["triangle"] = spot.triangle;
            out.push_back(std::move(item));
        }
        return out;
    };
    const json where = {{"degenerate_triangles", spots(r.where.degenerate_triangles)},
                        {"duplicate_positions", spots(r.where.duplicate_positions)},
                        {"non_manifold_edges", spots(r.where.non_manifold_edges)},
                        {"non_manifold_vertices", spots(r.where.non_manifold_vertices)},
                        {"misoriented_edges", spots(r.where.misoriented_edges)}};
    return {{"vertices", r.vertices},
            {"triangles", r.triangles},
            {"referenced_vertices", r.referenced_vertices},
            {"edges", r.edges},
            {"components", r.components},
            {"euler", r.euler},
            {"boundary_edges", r.boundary_edges},
            {"boundary_loops", r.boundary_loops},
            {"non_manifold_edges", r.non_manifold_edges},
            {"non_manifold_vertices", r.non_manifold_vertices},
            {"misoriented_edges", r.misoriented_edges},
            {"duplicate_triangles", r.duplicate_triangles},
            {"collapsed_triangles", r.collapsed_triangles},
            {"zero_area_triangles", r.zero_area_triangles},
            {"degenerate_triangles", r.degenerate_triangles},
            {"near_degenerate_triangles", r.near_degenerate_triangles},
            {"near_degenerate_angle_deg", r.near_degenerate_angle_deg},
            {"duplicate_positions", r.duplicate_positions},
            {"closed", r.closed},
            {"manifold", r.manifold},
            {"orientable", r.orientable},
            {"oriented", r.oriented},
            {"min_angle_deg", min_angle},
            {"signatures", signatures},
            {"where", where},
            {"per_component", components}};
}

} // namespace tetiso
