// `import tetiso`'s extension, tetiso._tetiso (python/tetiso/__init__.py
// re-exports it): the library's stages over NumPy arrays. Every tetiso::Error
// becomes a tetiso.Error with the same message, the one the CLI prints after
// "tetiso: ".
#include "module.hpp"

#include "tetiso/error.hpp"

PYBIND11_MODULE(_tetiso, m) {
    using namespace tetiso::python;
    m.doc() = "tetiso: reduced isosurfaces of tetrahedral meshes (extract, reduce, seam, check) over NumPy arrays";
    py::register_exception<tetiso::Error>(m, "Error", PyExc_Exception);
    m.attr("Error").attr("__module__") = "tetiso";
    m.attr("Error").attr("__doc__") = "Bad input to tetiso: the message names the argument, element or file at fault.";
    register_surface(m);
    register_stages(m);
    register_checks(m);
#ifdef TETISO_PYTHON_INSITU
    register_insitu(m);
#endif
    m.attr("__version__") = "0.1.0";
}
