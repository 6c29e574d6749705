// The parts of the module, one file each: the Surface type and its files
// (surface.cpp), the stages (stages.cpp: extract, reduce, the lattice, seam,
// merge), the checker (checks.cpp) and the in-situ session (insitu.cpp).
#pragma once

#include <pybind11/pybind11.h>

namespace tetiso::python {

namespace py = pybind11;

void register_surface(py::module_& m);
void register_stages(py::module_& m);
void register_checks(py::module_& m);
// Where the in-situ library and mpi4py's headers are (TETISO_PYTHON_INSITU).
void register_insitu(py::module_& m);

} // namespace tetiso::python
