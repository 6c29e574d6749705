// The CGAL baseline for reduction: Surface_mesh_simplification's edge
// collapse with Garland–Heckbert plane quadrics (cost and optimal placement),
// a careful serial simplifier: it refuses collapses that break the link
// condition, so it keeps the topology that meshoptimizer does not. The
// adapter builds a CGAL::Surface_mesh from the piece's arrays and copies the
// result back; both copies are part of what a caller times, as they are for
// meshoptimizer.
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <string>
#include <vector>

#include "reference_piece.hpp"
#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMS = CGAL::Surface_mesh_simplification;

// Stops at the triangle count (CGAL's own count predicates count edges, and an
// open surface has no fixed ratio of edges to faces).
struct FaceCountStop {
    const Mesh* mesh;
    std::size_t target;
    template <class FT, class Profile>
    bool operator()(const FT&, const Profile&, std::size_t, std::size_t) const {
        return mesh->number_of_faces() <= target;
    }
};

} // namespace

Piece cgal_simplify(const Piece& piece, std::size_t target_triangles) {
    check_piece_arrays("cgal_simplify", piece);
    const std::size_t n = piece.vertex_count();
    Mesh mesh;
    mesh.reserve(static_cast<Mesh::size_type>(n), static_cast<Mesh::size_type>(3 * piece.triangle_count()),
                 static_cast<Mesh::size_type>(piece.triangle_count()));
    for (std::size_t v = 0; v < n; ++v) mesh.add_vertex(Kernel::Point_3(piece.x[v], piece.y[v], piece.z[v]));
    for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
        const auto corner = [&](int c) { return Mesh::Vertex_index(static_cast<Mesh::size_type>(piece.triangles[3 * t + c])); };
        if (mesh.add_face(corner(0), corner(1), corner(2)) == Mesh::null_face())
            throw Error("cgal_simplify: triangle " + std::to_string(t) +
                        " would make the surface non-manifold; CGAL's halfedge mesh cannot hold it");
    }

    SMS::GarlandHeckbert_plane_policies<Mesh, Kernel> policies(mesh);
    SMS::edge_collapse(mesh, FaceCountStop{&mesh, target_triangles},
                       CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));

    // Vertices keep their indices until garbage is collected, so the survivors
    // map straight back to the input's keys and flags.
    std::vector<std::int32_t> renumber(n, -1);
    std::vector<Kernel::Point_3> moved(n);
    for (const Mesh::Vertex_index v : mesh.vertices()) {
        renumber[v.idx()] = 0;
        moved[v.idx()] = mesh.point(v);
    }
    Piece out = survivors(piece, renumber, [&](std::size_t v, float& x, float& y, float& z) {
        x = static_cast<float>(moved[v].x());
        y = static_cast<float>(moved[v].y());
        z = static_cast<float>(moved[v].z());
    });
    out.triangles.reserve(3 * mesh.number_of_faces());
    for (const Mesh::Face_index f : mesh.faces())
        for (const Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
            out.triangles.push_back(renumber[v.idx()]);
    return out;
}

} // namespace tetiso::reference
