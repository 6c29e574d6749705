"""Loads the tetiso ParaView plugin (tetiso_filter.py, beside this file) into
the ParaView that runs it: `paraview --script=load_tetiso_plugin.py`, or in
pvpython and pvbatch `runpy.run_path(".../load_tetiso_plugin.py")`; the
filter is then "tetiso reduced contour" in the Filters menu (Alphabetical,
and a tetiso category), and paraview.simple.tetisoreducedcontour.

Debian 12's ParaView 5.11.0 cannot load any Python plugin by itself: its
decorator module (paraview.detail.pythonalgorithm) imports
inspect.getargspec, which Python 3.11 removed. It reads only the argument
names, which inspect.getfullargspec gives alike, so that is put in its place
where it is missing, before the plugin is loaded.
"""
import inspect
import os

if not hasattr(inspect, "getargspec"):
    inspect.getargspec = inspect.getfullargspec

from paraview.simple import LoadPlugin  # noqa: E402

LoadPlugin(os.path.join(os.path.dirname(os.path.abspath(__file__)), "tetiso_filter.py"), remote=False)
