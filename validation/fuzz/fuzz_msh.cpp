// libFuzzer target: any bytes as a Gmsh .msh file (core/src/io_msh.cpp),
// then, where they read, as the domain built from them. The only outcome
// allowed besides success is tetiso::Error. Seeds: validation/fuzz/corpus/msh/
// (meshes/solver/make_fixtures.py; Gmsh writes them).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tetiso/error.hpp"
#include "tetiso/io_msh.hpp"
#include "tetiso/mesh_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    for (const char* view : {"distance", ""}) {
        try {
            const tetiso::MeshArrays arrays = tetiso::parse_msh(bytes, "fuzz.msh", view);
            if (!arrays.f.empty()) (void)tetiso::domain_from_arrays(arrays, nullptr);
        } catch (const tetiso::Error&) {
        }
    }
    return 0;
}
