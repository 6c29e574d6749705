// The parts of the module, one file each: the Surface type and its files
// (surface.cpp), the stages (stages.cpp: extract, reduce, the lattice, seam,
// merge) and the checker (checks.cpp).
#pragma once

#include <pybind11/pybind11.h>

namespace tetiso::python {

namespace py = pybind11;

void register_surface(py::module_& m);
void register_stages(py::module_& m);
void register_checks(py::module_& m);

} // namespace tetiso::python
