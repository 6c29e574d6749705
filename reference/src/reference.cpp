// Which baselines this build of tetiso_reference holds; the answers are fixed
// at configure time by the libraries CMake found.
#include "tetiso/reference.hpp"

namespace tetiso::reference {

bool has_vtk() {
#ifdef TETISO_HAVE_VTK
    return true;
#else
    return false;
#endif
}

bool has_meshoptimizer() {
#ifdef TETISO_HAVE_MESHOPTIMIZER
    return true;
#else
    return false;
#endif
}

bool has_cgal_simplify() {
#ifdef TETISO_HAVE_CGAL_SIMPLIFY
    return true;
#else
    return false;
#endif
}

bool has_openmesh() {
#ifdef TETISO_HAVE_OPENMESH
    return true;
#else
    return false;
#endif
}

} // namespace tetiso::reference
