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

__all__ = [
    "Error",
    "Lattice",
    "Surface",
    "check",
    "extract",
    "extract_lattice",
    "have_self_intersections",
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
