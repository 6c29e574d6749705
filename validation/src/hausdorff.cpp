// Symmetric Hausdorff distance between two triangle meshes, estimated by
// sampling (check.hpp): how far the reduced surface strays from the original
// one, in both directions, since a reduction can both cut corners (original
// far from reduced) and bulge (reduced far from original).
//
// Samples of each mesh are its referenced vertices plus, per triangle, the
// centroids of a k x k barycentric subdivision, with k set by the triangle's
// longest edge and a target spacing: a coarse triangle is sampled about as
// densely as the fine mesh's vertices are spaced. Denser sampling costs time
// linearly and moves the estimate little, since near its maximum the
// distance varies smoothly. Each sample's distance to the other mesh is exact
// (closest point on a triangle, Ericson, "Real-Time Collision Detection",
// 5.1.5, in double), found through a bounding volume hierarchy built on flat
// arrays by median splits, traversed nearest child first with the previous
// sample's nearest triangle as the first bound (consecutive samples are
// close, so most of the tree is pruned at once).
//
// Determinism: samples are processed in fixed chunks; each chunk keeps its
// own maximum and sum, and chunks are combined in chunk order, so the result
// is the same for any number of OpenMP threads.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "tetiso/check.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

namespace {

constexpr int kLeafSize = 4;
constexpr std::int64_t kVerticesPerChunk = 4096;
constexpr std::int64_t kTrianglesPerChunk = 512;

struct Vec3 {
    double x, y, z;
};
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double norm2(Vec3 a) { return dot(a, a); }

Vec3 vertex(const Piece& m, std::int32_t v) { return {m.x[v], m.y[v], m.z[v]}; }

double segment_distance2(Vec3 p, Vec3 a, Vec3 b) {
    const Vec3 ab = b - a;
    const double len2 = norm2(ab);
    const double t = len2 > 0.0 ? std::clamp(dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return norm2(p - (a + t * ab));
}

// Squared distance from p to triangle abc: the Voronoi-region walk of
// Ericson 5.1.5. A triangle without area has no face region; the walk would
// divide by zero, so it is measured as its three edges.
double triangle_distance2(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    if (norm2(cross(ab, ac)) == 0.0)
        return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return norm2(ap);
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return norm2(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return norm2(p - (a + (d1 / (d1 - d3)) * ab));
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return norm2(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return norm2(p - (a + (d2 / (d2 - d6)) * ac));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
        return norm2(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
    const double denom = va + vb + vc;
    if (!(denom > 0.0)) // rounding on a sliver: fall back to its edges
        return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
    return norm2(p - (a + (vb / denom) * ab + (vc / denom) * ac));
}

// A reference to a subtree: an inner node (count 0) or a leaf, triangles
// [index, index + count) of the leaf-ordered corner array.
struct Child {
    std::int32_t index;
    std::int32_t count;
};

// An inner node stores the boxes of both children: deciding where to go
// next reads one 64-byte node, not two, which matters once the tree no
// longer fits in cache.
struct alignas(64) BvhNode {
    float lo[2][3], hi[2][3];
    Child child[2];
};

struct Bvh {
    std::vector<BvhNode> nodes;
    Child root{0, 0};
    float lo[3], hi[3];         // root box
    std::vector<float> corners; // 9 floats per triangle, in leaf order
};

std::vector<std::int32_t> kept_triangles(const Piece& m) {
    std::vector<std::int32_t> kept;
    const std::int32_t* tri = m.triangles.data();
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
        if (tri[3 * t] != tri[3 * t + 1] && tri[3 * t + 1] != tri[3 * t + 2] && tri[3 * t] != tri[3 * t + 2])
            kept.push_back(static_cast<std::int32_t>(t));
    return kept;
}

// Median split on the longest axis of the centroids, with an explicit work
// list instead of recursion; depth is about log2(n / kLeafSize). No range is
// scanned per level: a child's centroid bounds are its parent's cut at the
// median, and boxes are filled bottom-up once the shape of the tree is known.
Bvh build_bvh(const Piece& m, const std::vector<std::int32_t>& kept) {
    struct Prim {
        float centroid[3];
        std::int32_t triangle;
    };
    const std::int32_t* tri = m.triangles.data();
    const std::size_t n = kept.size();
    std::vector<Prim> prim(n);
    float clo[3], chi[3];
    for (int k = 0; k < 3; ++k) clo[k] = std::numeric_limits<float>::max(), chi[k] = std::numeric_limits<float>::lowest();
    for (std::size_t i = 0; i < n; ++i) {
        Prim& q = prim[i];
        q.triangle = kept[i];
        for (int k = 0; k < 3; ++k) {
            const std::vector<float>& axis = k == 0 ? m.x : k == 1 ? m.y : m.z;
            q.centroid[k] = (axis[tri[3 * q.triangle]] + axis[tri[3 * q.triangle + 1]] + axis[tri[3 * q.triangle + 2]]) / 3.0f;
            clo[k] = std::min(clo[k], q.centroid[k]), chi[k] = std::max(chi[k], q.centroid[k]);
        }
    }

    Bvh bvh;
    bvh.nodes.reserve(n / kLeafSize + 1);
    struct Work {
        std::int32_t begin, end;
        std::int32_t parent, side; // where the reference goes; parent -1: the root
        float clo[3], chi[3];      // bounds of the centroids, possibly loose
    };
    std::vector<Work> work{{0, static_cast<std::int32_t>(n), -1, 0, {clo[0], clo[1], clo[2]}, {chi[0], chi[1], chi[2]}}};
    while (!work.empty()) {
        const Work w = work.back();
        work.pop_back();
        Child ref{w.begin, w.end - w.begin};
        if (w.end - w.begin > kLeafSize) {
            int axis = 0;
            for (int k = 1; k < 3; ++k)
                if (w.chi[k] - w.clo[k] > w.chi[axis] - w.clo[axis]) axis = k;
            const std::int32_t mid = w.begin + (w.end - w.begin) / 2;
            std::nth_element(prim.begin() + w.begin, prim.begin() + mid, prim.begin() + w.end,
                             [axis](const Prim& s, const Prim& t) {
                                 return s.centroid[axis] < t.centroid[axis] ||
                                        (s.centroid[axis] == t.centroid[axis] && s.triangle < t.triangle);
                             });
            ref = {static_cast<std::int32_t>(bvh.nodes.size()), 0};
            bvh.nodes.emplace_back();
            Work left = {w.begin, mid, ref.index, 0, {w.clo[0], w.clo[1], w.clo[2]}, {w.chi[0], w.chi[1], w.chi[2]}};
            Work right = {mid, w.end, ref.index, 1, {w.clo[0], w.clo[1], w.clo[2]}, {w.chi[0], w.chi[1], w.chi[2]}};
            left.chi[axis] = right.clo[axis] = prim[mid].centroid[axis];
            work.push_back(left);
            work.push_back(right);
        }
        if (w.parent < 0) bvh.root = ref;
        else bvh.nodes[w.parent].child[w.side] = ref;
    }

    bvh.corners.resize(9 * n);
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const std::int32_t v = tri[3 * prim[i].triangle + c];
            bvh.corners[9 * i + 3 * c] = m.x[v];
            bvh.corners[9 * i + 3 * c + 1] = m.y[v];
            bvh.corners[9 * i + 3 * c + 2] = m.z[v];
        }

    // Children are created after their parent: in reverse creation order
    // every child box is known before its parent's is needed.
    auto box_of = [&bvh](Child c, float* lo, float* hi) {
        for (int k = 0; k < 3; ++k) lo[k] = std::numeric_limits<float>::max(), hi[k] = std::numeric_limits<float>::lowest();
        if (c.count > 0) {
            for (std::size_t j = 9 * static_cast<std::size_t>(c.index); j < 9 * static_cast<std::size_t>(c.index + c.count); ++j)
                lo[j % 3] = std::min(lo[j % 3], bvh.corners[j]), hi[j % 3] = std::max(hi[j % 3], bvh.corners[j]);
            return;
        }
        const BvhNode& node = bvh.nodes[c.index];
        for (int k = 0; k < 3; ++k)
            lo[k] = std::min(node.lo[0][k], node.lo[1][k]), hi[k] = std::max(node.hi[0][k], node.hi[1][k]);
    };
    for (std::size_t i = bvh.nodes.size(); i-- > 0;)
        for (int side = 0; side < 2; ++side) box_of(bvh.nodes[i].child[side], bvh.nodes[i].lo[side], bvh.nodes[i].hi[side]);
    box_of(bvh.root, bvh.lo, bvh.hi);
    return bvh;
}

// Branch-free: it runs twice per visited node, right after the node's load.
inline double box_distance2(const float* lo, const float* hi, Vec3 p) {
    const double dx = std::max({static_cast<double>(lo[0]) - p.x, p.x - static_cast<double>(hi[0]), 0.0});
    const double dy = std::max({static_cast<double>(lo[1]) - p.y, p.y - static_cast<double>(hi[1]), 0.0});
    const double dz = std::max({static_cast<double>(lo[2]) - p.z, p.z - static_cast<double>(hi[2]), 0.0});
    return dx * dx + dy * dy + dz * dz;
}

double leaf_triangle_distance2(const Bvh& bvh, std::int32_t i, Vec3 p) {
    const float* c = &bvh.corners[9 * static_cast<std::size_t>(i)];
    return triangle_distance2(p, {c[0], c[1], c[2]}, {c[3], c[4], c[5]}, {c[6], c[7], c[8]});
}

// Squared distance from p to the mesh in bvh; `hint` is a triangle (leaf
// order) to start the bound from, updated to the nearest one found.
double nearest_distance2(const Bvh& bvh, Vec3 p, std::int32_t& hint) {
    double best = hint >= 0 ? leaf_triangle_distance2(bvh, hint, p) : std::numeric_limits<double>::infinity();
    struct Entry {
        Child child;
        double d2;
    };
    // Nearer child popped first; the stack holds at most one entry per level
    // plus one, and median splits keep levels below 32 for any int32 count.
    Entry stack[64];
    int top = 0;
    stack[top++] = {bvh.root, box_distance2(bvh.lo, bvh.hi, p)};
    while (top > 0) {
        const Entry e = stack[--top];
        if (e.d2 >= best) continue;
        if (e.child.count > 0) {
            for (std::int32_t i = e.child.index; i < e.child.index + e.child.count; ++i) {
                const double d2 = leaf_triangle_distance2(bvh, i, p);
                if (d2 < best) best = d2, hint = i;
            }
            continue;
        }
        const BvhNode& node = bvh.nodes[e.child.index];
        const double d0 = box_distance2(node.lo[0], node.hi[0], p);
        const double d1 = box_distance2(node.lo[1], node.hi[1], p);
        const int near = d0 <= d1 ? 0 : 1;
        const double d_near = near == 0 ? d0 : d1, d_far = near == 0 ? d1 : d0;
        if (d_far < best) stack[top++] = {node.child[1 - near], d_far};
        if (d_near < best) stack[top++] = {node.child[near], d_near};
    }
    return best;
}

double mean_edge_length(const Piece& m, const std::vector<std::int32_t>& kept) {
    double sum = 0.0;
    for (std::int32_t t : kept) {
        const Vec3 a = vertex(m, m.triangles[3 * t]), b = vertex(m, m.triangles[3 * t + 1]),
                   c = vertex(m, m.triangles[3 * t + 2]);
        sum += std::sqrt(norm2(b - a)) + std::sqrt(norm2(c - b)) + std::sqrt(norm2(a - c));
    }
    return kept.empty() ? 0.0 : sum / (3.0 * static_cast<double>(kept.size()));
}

struct Partial {
    double max = -1.0;
    Vec3 at{0.0, 0.0, 0.0};
    double sum = 0.0;
    std::int64_t count = 0;

    void add(double d, Vec3 p) {
        if (d > max) max = d, at = p;
        sum += d;
        ++count;
    }
};

// Distances from the samples of `source` to `target`, reduced over chunks
// in chunk order.
Partial one_way(const Piece& source, const std::vector<std::int32_t>& source_kept, const Bvh& target,
                double spacing, int max_subdivisions, bool vertices_only) {
    std::vector<std::int32_t> vertices;
    {
        std::vector<std::uint8_t> referenced(source.x.size(), 0);
        for (std::int32_t t : source_kept)
            for (int c = 0; c < 3; ++c) referenced[source.triangles[3 * t + c]] = 1;
        for (std::size_t v = 0; v < referenced.size(); ++v)
            if (referenced[v]) vertices.push_back(static_cast<std::int32_t>(v));
    }
    const std::int64_t nv = static_cast<std::int64_t>(vertices.size());
    const std::int64_t nt = vertices_only ? 0 : static_cast<std::int64_t>(source_kept.size());
    const std::int64_t vertex_chunks = (nv + kVerticesPerChunk - 1) / kVerticesPerChunk;
    const std::int64_t chunks = vertex_chunks + (nt + kTrianglesPerChunk - 1) / kTrianglesPerChunk;
    std::vector<Partial> partial(static_cast<std::size_t>(chunks));

#if defined(_OPENMP)
#pragma omp parallel for schedule(dynamic, 1)
#endif
    for (std::int64_t chunk = 0; chunk < chunks; ++chunk) {
        Partial& out = partial[chunk];
        std::int32_t hint = -1; // reset per chunk: a chunk's result must not depend on the one before
        if (chunk < vertex_chunks) {
            const std::int64_t end = std::min(nv, (chunk + 1) * kVerticesPerChunk);
            for (std::int64_t i = chunk * kVerticesPerChunk; i < end; ++i) {
                const Vec3 p = vertex(source, vertices[i]);
                out.add(std::sqrt(nearest_distance2(target, p, hint)), p);
            }
            continue;
        }
        const std::int64_t begin = (chunk - vertex_chunks) * kTrianglesPerChunk;
        const std::int64_t end = std::min(nt, begin + kTrianglesPerChunk);
        for (std::int64_t i = begin; i < end; ++i) {
            const std::int32_t t = source_kept[i];
            const Vec3 a = vertex(source, source.triangles[3 * t]);
            const Vec3 ab = vertex(source, source.triangles[3 * t + 1]) - a;
            const Vec3 ac = vertex(source, source.triangles[3 * t + 2]) - a;
            const double longest = std::sqrt(std::max({norm2(ab), norm2(ac), norm2(ac - ab)}));
            // Neighbouring sub-triangle centroids are about L / (k sqrt 3)
            // apart, so this k spaces samples about `spacing` apart. Rounded,
            // not ceiled: a triangle of the fine mesh then gets its centroid
            // only (its vertices are samples already).
            const double ratio = spacing > 0.0 ? std::round(longest / (std::sqrt(3.0) * spacing)) : 1.0;
            const int k = ratio >= max_subdivisions ? max_subdivisions : std::max(1, static_cast<int>(ratio));
            const double inv = 1.0 / k;
            // Centroids of the k^2 sub-triangles: k(k+1)/2 pointing like the
            // triangle, at (i + 1/3, j + 1/3) / k, and k(k-1)/2 pointing the
            // other way, at (i + 2/3, j + 2/3) / k.
            for (int u = 0; u < k; ++u)
                for (int v = 0; u + v < k; ++v) {
                    const Vec3 p = a + ((u + 1.0 / 3.0) * inv) * ab + ((v + 1.0 / 3.0) * inv) * ac;
                    out.add(std::sqrt(nearest_distance2(target, p, hint)), p);
                    if (u + v + 1 < k) {
                        const Vec3 q = a + ((u + 2.0 / 3.0) * inv) * ab + ((v + 2.0 / 3.0) * inv) * ac;
                        out.add(std::sqrt(nearest_distance2(target, q, hint)), q);
                    }
                }
        }
    }

    Partial total;
    for (const Partial& p : partial) {
        if (p.count == 0) continue;
        if (p.max > total.max) total.max = p.max, total.at = p.at;
        total.sum += p.sum;
        total.count += p.count;
    }
    return total;
}

} // namespace

HausdorffReport hausdorff(const Piece& a, const Piece& b, const HausdorffOptions& options) {
    validate_indexed_mesh(a, "hausdorff: mesh a");
    validate_indexed_mesh(b, "hausdorff: mesh b");
    if (options.max_subdivisions < 1 || options.max_subdivisions > 4096)
        throw Error("hausdorff: max_subdivisions must be in [1, 4096], not " + std::to_string(options.max_subdivisions));
    if (!std::isfinite(options.spacing))
        throw Error("hausdorff: spacing must be finite");

    const std::vector<std::int32_t> kept_a = kept_triangles(a);
    const std::vector<std::int32_t> kept_b = kept_triangles(b);
    HausdorffReport r;
    if (kept_a.empty() && kept_b.empty()) return r; // two empty surfaces coincide
    if (kept_a.empty() || kept_b.empty())
        throw Error(std::string("hausdorff: mesh ") + (kept_a.empty() ? "a" : "b") +
                    " has no triangle with three distinct vertices, the other has " +
                    std::to_string(kept_a.empty() ? kept_b.size() : kept_a.size()) +
                    "; the distance to an empty surface is undefined");

    r.spacing = options.spacing > 0.0 ? options.spacing : std::min(mean_edge_length(a, kept_a), mean_edge_length(b, kept_b));

    const Bvh bvh_a = build_bvh(a, kept_a);
    const Bvh bvh_b = build_bvh(b, kept_b);
    const Partial fwd = one_way(a, kept_a, bvh_b, r.spacing, options.max_subdivisions, options.vertices_only);
    const Partial bwd = one_way(b, kept_b, bvh_a, r.spacing, options.max_subdivisions, options.vertices_only);

    r.forward = fwd.max;
    r.backward = bwd.max;
    r.symmetric = std::max(r.forward, r.backward);
    r.forward_at = {fwd.at.x, fwd.at.y, fwd.at.z};
    r.backward_at = {bwd.at.x, bwd.at.y, bwd.at.z};
    r.samples_a = fwd.count;
    r.samples_b = bwd.count;
    r.mean_forward = fwd.sum / static_cast<double>(fwd.count);
    r.mean_backward = bwd.sum / static_cast<double>(bwd.count);
    r.mean = (fwd.sum + bwd.sum) / static_cast<double>(fwd.count + bwd.count);

    // The root box of a's tree spans exactly a's referenced vertices.
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (static_cast<double>(bvh_a.hi[k]) - bvh_a.lo[k]) * (static_cast<double>(bvh_a.hi[k]) - bvh_a.lo[k]);
    r.diagonal = std::sqrt(d2);
    r.relative = r.diagonal > 0.0 ? r.symmetric / r.diagonal : 0.0;
    return r;
}

nlohmann::json to_json(const HausdorffReport& r) {
    return {{"forward", r.forward},
            {"backward", r.backward},
            {"symmetric", r.symmetric},
            {"mean_forward", r.mean_forward},
            {"mean_backward", r.mean_backward},
            {"mean", r.mean},
            {"diagonal", r.diagonal},
            {"relative", r.relative},
            {"spacing", r.spacing},
            {"samples_a", r.samples_a},
            {"samples_b", r.samples_b},
            {"forward_at", r.forward_at},
            {"backward_at", r.backward_at}};
}

} // namespace tetiso
