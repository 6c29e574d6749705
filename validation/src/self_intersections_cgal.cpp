// Self-intersection count through CGAL's Polygon Mesh Processing
// (CGAL::Polygon_mesh_processing::self_intersections, exact predicates), for
// `tetiso check` and the reference comparisons: edge collapse can fold a
// surface through itself without changing any count check_topology makes.
//
// CGAL is optional (core must build without it): without it, or when the
// mesh cannot become a CGAL surface mesh as it is, the answer is nullopt.
// PMP works on a halfedge mesh, which needs a manifold, orientable soup;
// orient_polygon_soup would make any soup one by duplicating vertices, but
// then triangles that met at a duplicated vertex would no longer count as
// neighbours and their contact would be reported as an intersection. So only
// a soup that orient_polygon_soup can orient without duplicating anything is
// measured (a consistent orientation is fine to impose: it changes no
// intersection).
#include "tetiso/check.hpp"

#if defined(TETISO_HAVE_CGAL)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <iterator>
#include <utility>
#endif

namespace tetiso {

bool have_self_intersections() {
#if defined(TETISO_HAVE_CGAL)
    return true;
#else
    return false;
#endif
}

std::optional<std::size_t> count_self_intersections(const Piece& mesh) {
    const std::optional<std::vector<TrianglePair>> pairs = find_self_intersections(mesh);
    if (!pairs) return std::nullopt;
    return pairs->size();
}

std::optional<std::vector<TrianglePair>> find_self_intersections(const Piece& mesh) {
    validate_indexed_mesh(mesh, "self-intersections");
#if defined(TETISO_HAVE_CGAL)
    namespace PMP = CGAL::Polygon_mesh_processing;
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Point = Kernel::Point_3;
    using Mesh = CGAL::Surface_mesh<Point>;

    // Only referenced vertices go in: isolated points are no part of the
    // surface. Collapsed triangles are left out (check_topology counts them).
    const std::size_t nv = mesh.x.size();
    std::vector<std::size_t> renumber(nv, nv);
    std::vector<Point> points;
    std::vector<std::array<std::size_t, 3>> triangles;
    std::vector<std::int64_t> original; // the mesh's index of each triangle that goes in
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const std::int32_t* v = &mesh.triangles[3 * t];
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
        original.push_back(static_cast<std::int64_t>(t));
        std::array<std::size_t, 3> f{};
        for (int c = 0; c < 3; ++c) {
            if (renumber[v[c]] == nv) {
                renumber[v[c]] = points.size();
                points.emplace_back(mesh.x[v[c]], mesh.y[v[c]], mesh.z[v[c]]);
            }
            f[c] = renumber[v[c]];
        }
        triangles.push_back(f);
    }
    if (triangles.empty()) return std::vector<TrianglePair>{};

    const std::size_t points_before = points.size();
    if (!PMP::orient_polygon_soup(points, triangles) || points.size() != points_before) return std::nullopt;
    if (!PMP::is_polygon_soup_a_polygon_mesh(triangles)) return std::nullopt;
    Mesh surface;
    PMP::polygon_soup_to_polygon_mesh(points, triangles, surface);

    std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
    PMP::self_intersections(surface, std::back_inserter(pairs));
    // A degenerate face is reported paired with itself; it is not an
    // intersection of two triangles, and check_topology already counts it.
    // Faces are numbered in the order the soup listed them, so a face's index
    // is its place in `original`.
    std::vector<TrianglePair> found;
    for (const auto& [f, g] : pairs) {
        if (f == g) continue;
        const std::int64_t a = original[static_cast<std::size_t>(f.idx())];
        const std::int64_t b = original[static_cast<std::size_t>(g.idx())];
        found.push_back({std::min(a, b), std::max(a, b)});
    }
    std::sort(found.begin(), found.end());
    return found;
#else
    return std::nullopt;
#endif
}

} // namespace tetiso
