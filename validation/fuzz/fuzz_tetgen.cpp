// TetGen .node and .ele: one input holds both, the .ele after the first line
// "#ele" (seeds in corpus/tetgen/ are laid out so). The field is node
// attribute 0 when the input starts with '#attribute', else a built-in one.
// A mesh that reads is extracted, as `tetiso extract --mesh` would.
#include <string>

#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/tetgen.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view input = tetiso::fuzz::bytes_of(data, size);
    static const std::string_view kSeparator = "\n#ele\n";
    const std::size_t at = input.find(kSeparator);
    const std::string_view node = input.substr(0, at);
    const std::string_view ele = at == std::string_view::npos ? std::string_view() : input.substr(at + kSeparator.size());
    tetiso::fuzz::write_file("mesh.node", node);
    tetiso::fuzz::write_file("mesh.ele", ele);
    static const auto field = tetiso::make_field("sphere");
    tetiso::TetgenSource source{tetiso::fuzz::scratch() / "mesh", std::nullopt, field.get()};
    if (input.starts_with("#attribute")) source.attribute = 0;
    try {
        const tetiso::Domain mesh = tetiso::read_tetgen(source);
        tetiso::extract(mesh, 0.5f);
    } catch (const tetiso::Error&) {
    }
    return 0;
}
