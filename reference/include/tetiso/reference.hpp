// Baselines that tetiso is measured against, behind one flat interface so that
// benchmarks and tests never include a third-party header:
//
//   VTK            vtkContour3DLinearGrid with point merging: the production
//                  marching-tetrahedra filter that extraction must beat;
//   meshoptimizer  meshopt_simplify: a serial quadric edge-collapse simplifier,
//                  the yardstick for reduction's speed (it does not keep
//                  topology);
//   CGAL           Surface_mesh_simplification::edge_collapse with
//                  Garland–Heckbert plane quadrics, and
//   OpenMesh       DecimaterT with its quadric module: the careful serial
//                  simplifiers, which keep topology (link condition), the
//                  yardstick for what that guarantee usually costs.
//
// Each baseline is compiled only where its library was found at configure
// time; TETISO_HAVE_VTK, TETISO_HAVE_MESHOPTIMIZER, TETISO_HAVE_CGAL_SIMPLIFY
// and TETISO_HAVE_OPENMESH (set on every target that links tetiso_reference)
// say which are here, and the has_*() functions say the same at run time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "tetiso/mesh.hpp"

namespace tetiso::reference {

bool has_vtk();
bool has_meshoptimizer();
bool has_cgal_simplify();
bool has_openmesh();

#ifdef TETISO_HAVE_VTK

// Size of one contour, to check a baseline against tetiso on the same input.
struct ContourCounts {
    std::int64_t points = 0;
    std::int64_t triangles = 0;
};

// VTK's threading layer (vtkSMPTools) is process-wide, so it is chosen once,
// before timing, not per run. threads == 1 selects the Sequential backend:
// the filter's SequentialProcessing flag alone leaves its point-merging sort
// (vtkSMPTools::Sort) on the default backend, which is parallel. Otherwise
// VTK's default backend (TBB in Debian's VTK 9.1) is used with at most
// `threads` threads. Returns the name of the backend now in use.
std::string vtk_set_threads(int threads);

// The backend VTK was built to use by default ("TBB", "STDThread", ...).
std::string vtk_default_backend();

// VTK's version, for reports ("9.1.0").
std::string vtk_version();

// vtkContour3DLinearGrid over a vtkUnstructuredGrid of VTK_TETRA cells that
// holds the same nodes, tetrahedra and float field as a tetiso Domain.
// Building the grid happens once, in the constructor, so that contour()
// times VTK's filter alone.
class VtkContour {
public:
    // Copies the domain into VTK's layout (float points, 64-bit cell ids,
    // which is VTK's native and fastest connectivity). Throws tetiso::Error if
    // a tetrahedron refers to a node that does not exist.
    explicit VtkContour(const Domain& domain);
    ~VtkContour();
    VtkContour(VtkContour&&) noexcept;
    VtkContour& operator=(VtkContour&&) noexcept;

    // Runs the filter's Update() once: merged points, no attribute
    // interpolation, normals or scalars; SequentialProcessing on when
    // `sequential` is. Returns the size of the output.
    ContourCounts contour(float level, bool sequential);

    // The output of the last contour() as a Piece, for sanity checks only:
    // keys are 0..n-1 (VTK keeps no edge ids), flags are 0, and the triangles
    // keep VTK's orientation.
    Piece surface() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

#endif // TETISO_HAVE_VTK

#ifdef TETISO_HAVE_MESHOPTIMIZER

// Simplifies a piece with meshopt_simplify (quadric error, edge collapse, the
// piece's topology kept) until it has at most `target_triangles` triangles or
// the next collapse would exceed `target_error`, a distance relative to the
// piece's extent (meshoptimizer's convention; 1 means unbounded).
// `lock_border` keeps vertices on open boundaries in place. The result keeps
// the surviving vertices with their positions, keys and flags (so the Piece
// invariant holds), and the piece's domains; locked flags are not honoured
// inside the piece, which meshoptimizer 0.18 cannot express. If
// `result_error` is given it receives meshoptimizer's relative error.
// Throws tetiso::Error if a triangle refers to a vertex that does not exist.
Piece meshopt_simplify(const Piece& piece, std::size_t target_triangles, float target_error = 1.0f,
                       bool lock_border = false, float* result_error = nullptr);

#endif // TETISO_HAVE_MESHOPTIMIZER

// The careful baselines below take the piece as a halfedge mesh, so they
// throw tetiso::Error, naming the triangle, for a non-manifold piece (and for
// arrays of mismatched length or a triangle that refers to a vertex that does
// not exist). Both simplify to at most `target_triangles` triangles, with the
// error unbounded, borders free to move along themselves, and locked flags not
// honoured (neither library can express them without a per-collapse callback,
// which would no longer be the baseline as shipped). The result keeps the
// surviving vertices in input order with their keys and flags, so the Piece
// invariant holds, and the piece's domains.

#ifdef TETISO_HAVE_CGAL_SIMPLIFY

// CGAL's edge_collapse with GarlandHeckbert_plane_policies: quadric cost and
// the quadric's optimal position for the survivor (so survivors move).
Piece cgal_simplify(const Piece& piece, std::size_t target_triangles);

#endif // TETISO_HAVE_CGAL_SIMPLIFY

#ifdef TETISO_HAVE_OPENMESH

// OpenMesh's DecimaterT with ModQuadricT: quadric cost, halfedge collapses
// (survivors keep their positions).
Piece openmesh_decimate(const Piece& piece, std::size_t target_triangles);

#endif // TETISO_HAVE_OPENMESH

} // namespace tetiso::reference
