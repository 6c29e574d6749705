"""Loads tetiso's ParaView filter, "tetiso reduced contour", into the
ParaView that runs this script: `paraview --script=load_tetiso_plugin.py`
(the GUI), or pvpython and pvbatch. The filter ships with the tetiso package
(tetiso/paraview_filter.py), so `import tetiso` must work in ParaView's
Python: the package installed, or PYTHONPATH=build/python. See
tetiso.load_paraview_plugin.
"""
import tetiso

tetiso.load_paraview_plugin()
