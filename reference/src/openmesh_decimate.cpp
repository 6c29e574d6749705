// The OpenMesh baseline for reduction: DecimaterT with the quadric module
// (ModQuadricT, error unbounded), a careful serial simplifier driven by a
// priority heap. Its collapses are halfedge collapses, so the survivors keep
// their positions, and each is refused unless OpenMesh's is_collapse_ok (the
// link condition, border rules) passes: it keeps the topology. The adapter
// builds a TriMesh from the piece's arrays and copies the result back; both
// copies are part of what a caller times.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <string>
#include <vector>

#include "reference_piece.hpp"
#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {
namespace {

using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;

} // namespace

Piece openmesh_decimate(const Piece& piece, std::size_t target_triangles) {
    check_piece_arrays("openmesh_decimate", piece);
    const std::size_t n = piece.vertex_count();
    Mesh mesh;
    mesh.reserve(n, 3 * piece.triangle_count(), piece.triangle_count());
    std::vector<Mesh::VertexHandle> handle(n);
    for (std::size_t v = 0; v < n; ++v) handle[v] = mesh.add_vertex(Mesh::Point(piece.x[v], piece.y[v], piece.z[v]));
    for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
        const auto corner = [&](int c) { return handle[static_cast<std::size_t>(piece.triangles[3 * t + c])]; };
        // OpenMesh reports a face it cannot add (a complex edge or vertex) on
        // std::cerr and returns an invalid handle; the piece is refused whole.
        if (!mesh.add_face(corner(0), corner(1), corner(2)).is_valid())
            throw Error("openmesh_decimate: triangle " + std::to_string(t) +
                        " would make the surface non-manifold; OpenMesh's halfedge mesh cannot hold it");
    }

    OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
    OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
    decimater.add(quadric);
    decimater.module(quadric).unset_max_err();
    if (!decimater.initialize()) throw Error("openmesh_decimate: the decimater did not initialize");
    decimater.decimate_to_faces(0, target_triangles);

    // Deleted vertices and faces are only marked until garbage collection,
    // which is skipped: the handles still index the input's vertices. The
    // ranges skip what is marked while the decimater, which owns the status
    // flags, is alive (its destructor releases them).
    std::vector<std::int32_t> renumber(n, -1);
    for (const Mesh::VertexHandle v : mesh.vertices()) renumber[static_cast<std::size_t>(v.idx())] = 0;
    Piece out = survivors(piece, renumber, [&](std::size_t v, float& x, float& y, float& z) {
        const Mesh::Point& p = mesh.point(handle[v]);
        x = p[0];
        y = p[1];
        z = p[2];
    });
    out.triangles.reserve(3 * mesh.n_faces());
    for (const Mesh::FaceHandle f : mesh.faces())
        for (const Mesh::VertexHandle v : mesh.fv_range(f))
            out.triangles.push_back(renumber[static_cast<std::size_t>(v.idx())]);
    return out;
}

} // namespace tetiso::reference
