"""ParaView plugin: "tetiso reduced contour", the isosurface of a point array
of an unstructured grid of tetrahedra, reduced by tetiso (marching
tetrahedra, then rounds of parallel edge collapse and flip that keep every
component's topology and every raw vertex within the error bound).

Loaded by tetiso.load_paraview_plugin() (Debian 12's ParaView needs what
that function does first; elsewhere Tools > Manage Plugins > Load New, or
PV_PLUGIN_PATH, load this file too). It needs `import tetiso` to work in
ParaView's Python: the package installed, or PYTHONPATH=build/python. It is
part of the package for that reason, and is not imported by it.

The filter runs tetiso.extract on the grid it is given, as one domain: the
same surface, to the byte, as `tetiso extract --mesh GRID.vtu --array NAME
--level L --reduce --phi PHI --max-error H`. Under a parallel pvbatch or
pvserver each process contours its own part, unseamed; run it on the whole
grid (builtin session) for one surface.
"""
import numpy as np
from paraview.util.vtkAlgorithm import VTKPythonAlgorithmBase, smdomain, smhint, smproperty, smproxy
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import (
    VTK_TETRA,
    vtkCellArray,
    vtkDataObject,
    vtkDataSetAttributes,
    vtkPolyData,
    vtkUnstructuredGrid,
)

# Cells that bound no volume, skipped as a solver's boundary markers, as
# tetiso's .vtu reader skips them (README, Input meshes): vertices, lines,
# polygons and their quadratic and higher-order forms.
SURFACE_CELL_TYPES = {1, 2, 3, 4, 5, 6, 7, 8, 9, 21, 22, 23, 28, 30, 31, 32, 34, 35, 36, 37, 68, 69, 70, 75, 76, 77}


def grid_arrays(grid, array_name):
    """Points, tetrahedra and the named point array of a vtkUnstructuredGrid,
    ghost cells and lower-dimensional cells left out. Nodes are numbered as
    the grid numbers its points (its GlobalIds, if any, are not used), as
    tetiso's .vtu reader numbers them."""
    wrapped = dsa.WrapDataObject(grid)
    if grid.GetNumberOfPoints() == 0:
        raise ValueError("tetiso reduced contour: the input has no points")
    values = grid.GetPointData().GetArray(array_name) if array_name else None
    if values is None:
        raise ValueError(f"tetiso reduced contour: the input has no point array {array_name!r}")
    if values.GetNumberOfComponents() != 1:
        raise ValueError(f"tetiso reduced contour: point array {array_name!r} has "
                         f"{values.GetNumberOfComponents()} components, not 1")
    types = numpy_support.vtk_to_numpy(grid.GetCellTypesArray())
    cells = grid.GetCells()
    offsets = numpy_support.vtk_to_numpy(cells.GetOffsetsArray())
    connectivity = numpy_support.vtk_to_numpy(cells.GetConnectivityArray())
    ghosts = grid.GetCellData().GetArray(vtkDataSetAttributes.GhostArrayName())
    ghost = np.zeros(len(types), bool) if ghosts is None else numpy_support.vtk_to_numpy(ghosts) != 0
    keep = (types == VTK_TETRA) & ~ghost
    other = ~ghost & (types != VTK_TETRA) & ~np.isin(types, list(SURFACE_CELL_TYPES))
    if other.any():
        cell = int(np.argmax(other))
        raise ValueError(f"tetiso reduced contour: cell {cell} is of VTK type {int(types[cell])}; "
                         "only linear tetrahedra (type 10) bound volume here")
    starts = offsets[:-1][keep]
    tets = np.stack([connectivity[starts + k] for k in range(4)], axis=1)
    return np.asarray(wrapped.Points), tets, numpy_support.vtk_to_numpy(values)


def surface_to_polydata(surface, output):
    """The surface as vtkPolyData, with tetiso's arrays under the names its
    .vtp writer gives them."""
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(surface.points, deep=True))
    output.SetPoints(points)
    triangles = vtkCellArray()
    offsets = np.arange(0, 3 * surface.triangle_count + 1, 3, dtype=np.int64)
    triangles.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
                      numpy_support.numpy_to_vtkIdTypeArray(surface.triangles.astype(np.int64).ravel(), deep=True))
    output.SetPolys(triangles)
    for name, values, data in (("tetiso_key", surface.keys, output.GetPointData()),
                               ("tetiso_flags", surface.flags, output.GetPointData()),
                               ("tetiso_error_bound", surface.error, output.GetCellData())):
        if len(values):
            array = numpy_support.numpy_to_vtk(np.ascontiguousarray(values), deep=True)
            array.SetName(name)
            data.AddArray(array)


@smproxy.filter(name="TetisoReducedContour", label="tetiso reduced contour")
@smhint.xml('<ShowInMenu category="tetiso" />')
@smproperty.input(name="Input", port_index=0)
@smdomain.datatype(dataTypes=["vtkUnstructuredGrid"], composite_data_supported=False)
@smdomain.xml('<InputArrayDomain name="input_array" attribute_type="point" number_of_components="1"/>')
class TetisoReducedContour(VTKPythonAlgorithmBase):
    """Isosurface of a point array, reduced with its topology kept and every
    raw vertex within the error bound."""

    def __init__(self):
        VTKPythonAlgorithmBase.__init__(self, nInputPorts=1, nOutputPorts=1, outputType="vtkPolyData")
        self._array = None
        self._level = 0.0
        self._phi = 0.9
        self._max_error = 0.25
        self._reduce = True
        self._threads = 0

    @smproperty.xml("""
        <StringVectorProperty name="ContourBy" label="Contour By" command="SetInputArrayToProcess"
                              number_of_elements="5" element_types="0 0 0 0 2" animateable="0">
          <ArrayListDomain name="array_list" attribute_type="Scalars" input_domain_name="input_array">
            <RequiredProperties><Property name="Input" function="Input"/></RequiredProperties>
          </ArrayListDomain>
          <Documentation>The point array whose isosurface is made.</Documentation>
        </StringVectorProperty>""")
    def SetInputArrayToProcess(self, index, port, connection, association, name):
        self._array = name
        self.Modified()
        return super().SetInputArrayToProcess(index, port, connection, association, name)

    @smproperty.doublevector(name="Level", default_values=0.0)
    @smdomain.xml('<DoubleRangeDomain name="range"/>')
    @smdomain.xml("<Documentation>The isosurface's value of the array.</Documentation>")
    def SetLevel(self, level):
        self._level = float(level)
        self.Modified()

    @smproperty.intvector(name="Reduce", default_values=1)
    @smdomain.xml('<BooleanDomain name="bool"/>')
    @smdomain.xml("<Documentation>Reduce the surface (off: the raw marching-tetrahedra surface).</Documentation>")
    def SetReduce(self, reduce):
        self._reduce = bool(reduce)
        self.Modified()

    @smproperty.doublevector(name="Phi", label="Phi", default_values=0.9)
    @smdomain.xml('<DoubleRangeDomain name="range" min="0.0" max="1.0"/>')
    @smdomain.xml("<Documentation>The paper's threshold, in (0, 1]: an edge collapses when its Phi exceeds it."
                  "</Documentation>")
    @smhint.xml('<PropertyWidgetDecorator type="GenericDecorator" mode="visibility" property="Reduce" value="1"/>')
    def SetPhi(self, phi):
        self._phi = float(phi)
        self.Modified()

    @smproperty.doublevector(name="MaxError", label="Max Error", default_values=0.25)
    @smdomain.xml('<DoubleRangeDomain name="range" min="0.0"/>')
    @smdomain.xml("<Documentation>Bound on the distance from every raw vertex to the reduced surface, in mean "
                  "tetrahedron edge lengths of the grid (0: none).</Documentation>")
    @smhint.xml('<PropertyWidgetDecorator type="GenericDecorator" mode="visibility" property="Reduce" value="1"/>')
    def SetMaxError(self, max_error):
        self._max_error = float(max_error)
        self.Modified()

    @smproperty.intvector(name="Threads", label="Threads", default_values=0)
    @smdomain.xml('<IntRangeDomain name="range" min="0" max="1024"/>')
    @smdomain.xml("<Documentation>Threads (0: all cores); the surface does not depend on it.</Documentation>")
    def SetThreads(self, threads):
        self._threads = int(threads)
        self.Modified()

    def FillInputPortInformation(self, port, info):
        info.Set(self.INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid")
        return 1

    def RequestData(self, request, in_info, out_info):
        import tetiso  # here, so that loading the plugin never fails for want of the module

        grid = vtkUnstructuredGrid.GetData(in_info[0], 0)
        output = vtkPolyData.GetData(out_info, 0)
        points, tets, values = grid_arrays(grid, self._array)
        surface = tetiso.extract(points, tets, values, self._level, reduce=self._reduce,
                                 phi=self._phi, max_error=self._max_error, threads=self._threads)
        surface_to_polydata(surface, output)
        return 1
