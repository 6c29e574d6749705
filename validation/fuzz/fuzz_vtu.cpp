// libFuzzer target: any bytes as a .vtu piece (core/src/io_vtu.cpp), then,
// where they read, as the domain built from them. The only outcome allowed
// besides success is tetiso::Error; AddressSanitizer and UBSan catch reads
// out of bounds, overflows and bad casts on the way. Seeds:
// validation/fuzz/corpus/vtu/ (meshes/solver/make_fixtures.py).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tetiso/error.hpp"
#include "tetiso/io_vtu.hpp"
#include "tetiso/mesh_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    for (const bool ids : {false, true}) {
        tetiso::VtuRequest request;
        request.array = "distance";
        request.require_node_ids = ids;
        try {
            const tetiso::MeshArrays arrays = tetiso::parse_vtu(bytes, "fuzz.vtu", request);
            if (!ids) (void)tetiso::domain_from_arrays(arrays, nullptr);
        } catch (const tetiso::Error&) {
        }
    }
    return 0;
}
