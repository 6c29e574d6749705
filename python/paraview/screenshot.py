"""The README's ParaView picture, made headless: a grid of tetrahedra (the
paper's field on 40^3 nodes of [0,5]^3, VTK's image data cut into
tetrahedra), "tetiso reduced contour" at level 0.5, rendered by pvbatch.

    PYTHONPATH=build/python xvfb-run -a pvbatch python/paraview/screenshot.py OUT.png

Debian's ParaView renders through X: xvfb-run gives it a virtual display
(Mesa's software OpenGL), no GPU needed.
"""
import sys

import numpy as np
from paraview import simple
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter

import tetiso

N = 40
out = sys.argv[1]
tetiso.load_paraview_plugin()

image = vtkImageData()
image.SetDimensions(N, N, N)
image.SetSpacing(*(3 * [5.0 / (N - 1)]))
x, y, z = np.meshgrid(*(3 * [np.linspace(0, 5, N)]), indexing="ij")
paper = 2 * np.cos(10 * x) + 2 * np.sin(10 * y) + np.cos(10 * z)
values = numpy_support.numpy_to_vtk(paper.ravel(order="F"), deep=True)   # x fastest, as VTK orders points
values.SetName("paper")
image.GetPointData().SetScalars(values)
tetrahedra = vtkDataSetTriangleFilter()
tetrahedra.SetInputData(image)
tetrahedra.TetrahedraOnlyOn()
tetrahedra.Update()

grid = simple.PVTrivialProducer()
grid.GetClientSideObject().SetOutput(tetrahedra.GetOutput())
contour = simple.tetisoreducedcontour(Input=grid)
contour.ContourBy = ["POINTS", "paper"]
contour.Level = 0.5
contour.UpdatePipeline()
triangles = simple.servermanager.Fetch(contour).GetNumberOfCells()

view = simple.CreateView("RenderView")
view.ViewSize = [900, 700]
view.OrientationAxesVisibility = 0
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
shown = simple.Show(contour, view)
shown.SetRepresentationType("Surface With Edges")
shown.AmbientColor = shown.DiffuseColor = [0.55, 0.7, 0.9]
shown.EdgeColor = [0.15, 0.2, 0.35]
outline = simple.Show(simple.Outline(Input=grid), view)
outline.DiffuseColor = outline.AmbientColor = [0.3, 0.3, 0.3]
view.CameraPosition = [13.0, -9.0, 10.0]
view.CameraFocalPoint = [2.5, 2.5, 2.5]
view.CameraViewUp = [0, 0, 1]
view.ResetCamera()
simple.Render(view)
simple.SaveScreenshot(out, view, ImageResolution=[900, 700])
print(f"{out}: tetiso reduced contour of {tetrahedra.GetOutput().GetNumberOfCells():,} tetrahedra, "
      f"{triangles:,} triangles")
