"""Run by pvbatch (test_paraview_plugin.sh): ParaView offers the filter, with
its properties; on a grid read by ParaView's own reader it gives
tetiso.extract's surface on the same arrays (itself the bytes of `tetiso
extract --mesh`, test_same_as_cli.py); a property out of range fails the
update with tetiso's message. Exits non-zero on any failure."""
import runpy
import sys

import numpy as np
from paraview import servermanager, simple
from paraview.simple import XMLUnstructuredGridReader
from vtkmodules.util import numpy_support

import tetiso

loader, mesh = sys.argv[1], sys.argv[2]
runpy.run_path(loader)      # load_tetiso_plugin.py, as paraview --script runs it
grid = XMLUnstructuredGridReader(FileName=[mesh])
contour = simple.tetisoreducedcontour(Input=grid)   # the label, as paraview.simple names it
for name in ("ContourBy", "Level", "Phi", "MaxError", "Reduce", "Threads"):
    assert name in contour.ListProperties(), (name, contour.ListProperties())
assert contour.Phi == 0.9 and contour.MaxError == 0.25 and contour.Reduce == 1 and contour.Threads == 0
contour.ContourBy = ["POINTS", "distance"]
contour.Level = 2.1
contour.Phi = 0.8
contour.UpdatePipeline()
output = servermanager.Fetch(contour)

read = servermanager.Fetch(grid)
points = numpy_support.vtk_to_numpy(read.GetPoints().GetData())
tets = numpy_support.vtk_to_numpy(read.GetCells().GetConnectivityArray()).reshape(-1, 4)
distance = numpy_support.vtk_to_numpy(read.GetPointData().GetArray("distance"))
expected = tetiso.extract(points, tets, distance, 2.1, reduce=True, phi=0.8)
raw = tetiso.extract(points, tets, distance, 2.1)

got_points = numpy_support.vtk_to_numpy(output.GetPoints().GetData())
got_triangles = numpy_support.vtk_to_numpy(output.GetPolys().GetConnectivityArray()).reshape(-1, 3)
got_keys = numpy_support.vtk_to_numpy(output.GetPointData().GetArray("tetiso_key"))
assert 0 < expected.triangle_count < raw.triangle_count
assert np.array_equal(got_points, expected.points), "the filter's points are tetiso.extract's"
assert np.array_equal(got_triangles, expected.triangles), "and so are its triangles"
assert np.array_equal(got_keys, expected.keys)
assert output.GetCellData().GetArray("tetiso_error_bound") is not None

contour.Reduce = 0
contour.UpdatePipeline()
assert servermanager.Fetch(contour).GetNumberOfCells() == raw.triangle_count, "Reduce off: the raw surface"

contour.Reduce = 1
contour.Phi = 0.0      # refused by tetiso ("phi: 0 is outside (0, 1]"): the update fails, nothing comes out
contour.UpdatePipeline()
assert servermanager.Fetch(contour).GetNumberOfCells() == 0, "phi = 0 was taken"
print("the ParaView plugin gives tetiso's surface:", expected.triangle_count, "of", raw.triangle_count, "triangles")
