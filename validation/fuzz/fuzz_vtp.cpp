// VTK XML PolyData (raw appended), as read_piece takes it. What reads must
// survive the round trip through the writer.
#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = tetiso::fuzz::write_file("input.vtp", tetiso::fuzz::bytes_of(data, size));
    tetiso::Piece piece;
    try {
        piece = tetiso::read_piece(path);
    } catch (const tetiso::Error&) {
        return 0;
    }
    const auto again = path.parent_path() / "again.vtp";
    tetiso::write_piece(piece, again);
    if (tetiso::read_piece(again).key != piece.key) __builtin_trap();
    return 0;
}
