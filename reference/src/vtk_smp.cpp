// Choice of VTK's threading backend, in a translation unit of its own:
// vtkSMPTools.h of VTK 9.1 declares constructors with template-ids, which
// C++20 forbids (CWG 2237) and GCC rejects, so this file is compiled as C++17
// (see CMakeLists.txt); the tetiso headers it includes are valid C++17 too.
#include <vtkSMP.h>
#include <vtkSMPTools.h>

#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {

std::string vtk_default_backend() { return VTK_SMP_BACKEND; }

std::string vtk_set_threads(int threads) {
    const char* backend = threads == 1 ? "Sequential" : VTK_SMP_BACKEND;
    if (!vtkSMPTools::SetBackend(backend)) throw Error(std::string("VTK has no SMP backend named ") + backend);
    vtkSMPTools::Initialize(threads > 0 ? threads : 0);
    return vtkSMPTools::GetBackend();
}

} // namespace tetiso::reference
