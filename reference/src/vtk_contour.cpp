// The VTK baseline for extraction: vtkContour3DLinearGrid, VTK's specialised
// marching-tetrahedra filter for unstructured grids of linear cells, with point
// merging so that its output is an indexed surface like a Piece.
//
// The grid is built once per domain and kept; contour() only marks the filter
// modified and runs Update(), which is what a VTK pipeline pays for each new
// isovalue. Cells are stored with VTK's native 64-bit ids: with 32-bit storage
// the filter's cell iterator copies every cell's ids into a buffer, which would
// handicap the baseline.
#include <vtkCellArray.h>
#include <vtkContour3DLinearGrid.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVersion.h>

#include <numeric>
#include <string>

#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {

namespace {

// The filter handles composite data too, so its output is typed as a plain
// data object; for an unstructured grid input it is always poly data.
vtkPolyData* output_of(vtkContour3DLinearGrid& filter) {
    vtkPolyData* out = vtkPolyData::SafeDownCast(filter.GetOutputDataObject(0));
    if (out == nullptr) throw Error("vtkContour3DLinearGrid produced no poly data");
    return out;
}

} // namespace

std::string vtk_version() { return vtkVersion::GetVTKVersion(); }

struct VtkContour::Impl {
    vtkSmartPointer<vtkUnstructuredGrid> grid;
    vtkSmartPointer<vtkContour3DLinearGrid> filter;
};

VtkContour::VtkContour(const Domain& domain) : impl_(std::make_unique<Impl>()) {
    const std::size_t nodes = domain.node_count();
    const std::size_t tets = domain.tet_count();
    if (domain.x.size() != nodes || domain.y.size() != nodes || domain.z.size() != nodes || domain.f.size() != nodes)
        throw Error("domain " + std::to_string(domain.id) + ": node arrays differ in length");

    vtkNew<vtkFloatArray> coordinates;
    coordinates->SetNumberOfComponents(3);
    coordinates->SetNumberOfTuples(static_cast<vtkIdType>(nodes));
    float* xyz = coordinates->GetPointer(0);
    for (std::size_t v = 0; v < nodes; ++v) {
        xyz[3 * v] = domain.x[v];
        xyz[3 * v + 1] = domain.y[v];
        xyz[3 * v + 2] = domain.z[v];
    }
    vtkNew<vtkPoints> points;
    points->SetData(coordinates);

    vtkNew<vtkFloatArray> field;
    field->SetName("f");
    field->SetNumberOfTuples(static_cast<vtkIdType>(nodes));
    std::copy(domain.f.begin(), domain.f.end(), field->GetPointer(0));

    vtkNew<vtkIdTypeArray> offsets;
    offsets->SetNumberOfTuples(static_cast<vtkIdType>(tets + 1));
    vtkIdType* offset = offsets->GetPointer(0);
    for (std::size_t t = 0; t <= tets; ++t) offset[t] = static_cast<vtkIdType>(4 * t);
    vtkNew<vtkIdTypeArray> connectivity;
    connectivity->SetNumberOfTuples(static_cast<vtkIdType>(4 * tets));
    vtkIdType* ids = connectivity->GetPointer(0);
    for (std::size_t i = 0; i < 4 * tets; ++i) {
        const std::int32_t node = domain.tets[i];
        if (node < 0 || static_cast<std::size_t>(node) >= nodes)
            throw Error("domain " + std::to_string(domain.id) + ": tetrahedron " + std::to_string(i / 4) +
                        " refers to a node that does not exist");
        ids[i] = node;
    }
    vtkNew<vtkCellArray> cells;
    cells->SetData(offsets, connectivity);

    impl_->grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    impl_->grid->SetPoints(points);
    impl_->grid->SetCells(VTK_TETRA, cells);
    impl_->grid->GetPointData()->SetScalars(field);

    impl_->filter = vtkSmartPointer<vtkContour3DLinearGrid>::New();
    impl_->filter->SetInputData(impl_->grid);
    impl_->filter->MergePointsOn();
    impl_->filter->InterpolateAttributesOff();
    impl_->filter->ComputeNormalsOff();
    impl_->filter->ComputeScalarsOff();
    impl_->filter->UseScalarTreeOff();
}

VtkContour::~VtkContour() = default;
VtkContour::VtkContour(VtkContour&&) noexcept = default;
VtkContour& VtkContour::operator=(VtkContour&&) noexcept = default;

ContourCounts VtkContour::contour(float level, bool sequential) {
    vtkContour3DLinearGrid& filter = *impl_->filter;
    filter.SetValue(0, static_cast<double>(level));
    filter.SetSequentialProcessing(sequential);
    // Without this a repeated Update() with unchanged parameters is a no-op.
    filter.Modified();
    filter.Update();
    vtkPolyData* out = output_of(filter);
    return {out->GetNumberOfPoints(), out->GetNumberOfPolys()};
}

Piece VtkContour::surface() const {
    vtkPolyData* out = output_of(*impl_->filter);
    Piece piece;
    const vtkIdType n = out->GetNumberOfPoints();
    piece.x.resize(static_cast<std::size_t>(n));
    piece.y.resize(piece.x.size());
    piece.z.resize(piece.x.size());
    piece.key.resize(piece.x.size());
    piece.flags.assign(piece.x.size(), 0);
    std::iota(piece.key.begin(), piece.key.end(), EdgeKey{0});
    for (vtkIdType v = 0; v < n; ++v) {
        double p[3];
        out->GetPoint(v, p);
        const auto i = static_cast<std::size_t>(v);
        piece.x[i] = static_cast<float>(p[0]);
        piece.y[i] = static_cast<float>(p[1]);
        piece.z[i] = static_cast<float>(p[2]);
    }
    vtkCellArray* polys = out->GetPolys();
    piece.triangles.reserve(static_cast<std::size_t>(3 * polys->GetNumberOfCells()));
    vtkIdType size = 0;
    const vtkIdType* corners = nullptr;
    for (polys->InitTraversal(); polys->GetNextCell(size, corners) != 0;) {
        if (size != 3) throw Error("VTK contour produced a polygon with " + std::to_string(size) + " corners");
        for (vtkIdType k = 0; k < 3; ++k) piece.triangles.push_back(static_cast<std::int32_t>(corners[k]));
    }
    piece.domains.clear();
    return piece;
}

} // namespace tetiso::reference
