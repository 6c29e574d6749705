// The values of one DataArray of a VTK XML file, decoded: ascii numbers, or
// binary data (inline or appended; raw or base64; whole or in zlib blocks)
// behind headers of the file's header type. io_vtu.cpp finds the arrays; a
// failure is a tetiso::Error naming the file and the array.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <pugixml.hpp>

namespace tetiso::vtu {

// How a file encodes its binary arrays: its VTKFile element's header_type
// and compressor, and its AppendedData block.
struct Encoding {
    std::string_view appended; // the bytes after AppendedData's '_', or empty
    bool appended_base64 = false;
    bool compressed = false; // vtkZLibDataCompressor
    std::size_t header_bytes = 4; // UInt32 headers, or 8 for UInt64
};

// A DataArray's type attribute.
enum class Scalar { int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32, float64 };

// The scalar a type attribute names (VTK's names, Char and UChar included),
// or none.
std::optional<Scalar> scalar_of(std::string_view name);
bool is_integer(Scalar s);

class ArrayReader {
public:
    // name: the file's, for messages; encoding.appended must outlive the reader.
    ArrayReader(std::string name, Encoding encoding);

    // The `count` values of `array`, converted to T (double, int64, int32 or
    // uint8); fails unless the array holds exactly that many, each in T's
    // range. what: the array, for messages.
    template <class T>
    std::vector<T> read(const pugi::xml_node& array, std::uint64_t count, const std::string& what) const;

private:
    [[noreturn]] void fail(const std::string& what) const;
    std::uint64_t read_header_word(const unsigned char* at) const;
    std::string decode_base64(std::string_view text, const std::string& what) const;
    // The bytes of an array of `count` values of `scalar` (binary
    // encodings): a view into the file for uncompressed raw data, else into
    // `storage`, which holds what was decoded.
    std::string_view binary_payload(const pugi::xml_node& array, std::uint64_t count, Scalar scalar,
                                    const std::string& what, std::string& storage) const;
    std::string inflate(std::string_view header, std::string_view blocks, std::uint64_t expected, const std::string& what) const;

    std::string name_;
    Encoding encoding_;
};

} // namespace tetiso::vtu
