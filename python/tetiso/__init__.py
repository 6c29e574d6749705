"""tetiso: reduced isosurfaces of tetrahedral meshes, over NumPy arrays.

The library behind the `tetiso` command (extract, reduce, seam, check), built
with pybind11. Every bad input raises tetiso.Error with the message the CLI
prints; the GIL is released while the library works; results are Surfaces
whose arrays are read-only views of their own memory. See README.md,
"Python", and docs/ARCHITECTURE.md, "python/".
"""
import os as _os

# libgomp reads its wait policy once, when it is loaded (with the extension
# below): threads that wait spin for a while before they sleep, which on a
# machine whose cores other processes use slows a parallel stage by several
# times. As the `tetiso` command does, wait passively unless the user chose.
if "OMP_WAIT_POLICY" not in _os.environ and "GOMP_SPINCOUNT" not in _os.environ:
    _os.environ["OMP_WAIT_POLICY"] = "passive"

from ._tetiso import (  # noqa: E402
    Error,
    Lattice,
    Surface,
    __version__,
    check,
    extract,
    extract_lattice,
    have_self_intersections,
    merge,
    read,
    reduce,
    seam,
)



def load_paraview_plugin():
    """Loads the "tetiso reduced contour" filter (paraview_filter.py, beside
    this file) into the ParaView whose Python runs this: the GUI (its Python
    shell, or `paraview --script=python/paraview/load_tetiso_plugin.py`),
    pvpython or pvbatch. It is then in the Filters menu and
    paraview.simple.tetisoreducedcontour.

    Debian 12's ParaView 5.11.0 cannot load any Python plugin by itself: its
    decorator module (paraview.detail.pythonalgorithm) imports
    inspect.getargspec, which Python 3.11 removed. It reads only the argument
    names, which inspect.getfullargspec gives alike, so that is put in its
    place where it is missing, before the plugin is loaded."""
    import inspect

    if not hasattr(inspect, "getargspec"):
        inspect.getargspec = inspect.getfullargspec
    from paraview.simple import LoadPlugin

    LoadPlugin(_os.path.join(_os.path.dirname(_os.path.abspath(__file__)), "paraview_filter.py"), remote=False)


__all__ = [
    "Error",
    "Lattice",
    "Surface",
    "check",
    "extract",
    "extract_lattice",
    "have_self_intersections",
    "load_paraview_plugin",
    "merge",
    "read",
    "reduce",
    "seam",
]

# The in-situ session, where tetiso was built with MPI and mpi4py's headers.
try:
    from ._tetiso import InSituSession  # noqa: F401
    __all__.append("InSituSession")
except ImportError:
    pass
