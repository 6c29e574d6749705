// VTK XML unstructured grids (see io_vtu.hpp). The file is split in two
// before parsing: the XML (parsed by pugixml) and, where the file has one,
// the appended block after `<AppendedData ...>_`, which in raw encoding is
// arbitrary bytes that no XML parser accepts. Every DataArray is then
// decoded into bytes of its declared type (ascii numbers, base64, raw,
// zlib blocks), its size checked against what the piece's counts require
// before anything of that size is allocated, and converted to the type the
// mesh needs with range checks.
#include "tetiso/io_vtu.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include <pugixml.hpp>
#include <zlib.h>

#include "mapped_file.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

constexpr std::uint8_t kVtkTetra = 10;
// DOLFINx writes its cells as Lagrange cells; one of degree 1 (4 points) is
// a linear tetrahedron.
constexpr std::uint8_t kVtkLagrangeTetra = 71;
// vtkDataSetAttributes::DUPLICATECELL: the cell is a copy of another piece's.
constexpr std::uint8_t kDuplicateCell = 1;
// zlib cannot inflate more than about 1032 bytes from one; a block header
// that promises more is damaged (or a bomb).
constexpr std::uint64_t kMaxInflateRatio = 1100;

enum class Scalar { int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32, float64 };

std::optional<Scalar> scalar_of(std::string_view name) {
    static const std::pair<std::string_view, Scalar> names[] = {
        {"Int8", Scalar::int8},     {"UInt8", Scalar::uint8},     {"Int16", Scalar::int16},
        {"UInt16", Scalar::uint16}, {"Int32", Scalar::int32},     {"UInt32", Scalar::uint32},
        {"Int64", Scalar::int64},   {"UInt64", Scalar::uint64},   {"Float32", Scalar::float32},
        {"Float64", Scalar::float64}, {"Char", Scalar::int8},     {"UChar", Scalar::uint8}};
    for (const auto& [text, scalar] : names)
        if (name == text) return scalar;
    return std::nullopt;
}

std::size_t size_of(Scalar s) {
    switch (s) {
    case Scalar::int8: case Scalar::uint8: return 1;
    case Scalar::int16: case Scalar::uint16: return 2;
    case Scalar::int32: case Scalar::uint32: case Scalar::float32: return 4;
    default: return 8;
    }
}

bool is_integer(Scalar s) { return s != Scalar::float32 && s != Scalar::float64; }

// Names of the cell types a solver may write, for messages.
std::string cell_type_name(int type) {
    switch (type) {
    case 1: return "vertex";
    case 3: return "line";
    case 5: return "triangle";
    case 8: return "pixel";
    case 9: return "quad";
    case 10: return "tetrahedron";
    case 11: return "voxel";
    case 12: return "hexahedron";
    case 13: return "wedge";
    case 14: return "pyramid";
    case 21: return "quadratic edge";
    case 22: return "quadratic triangle";
    case 23: return "quadratic quad";
    case 24: return "quadratic tetrahedron";
    case 25: return "quadratic hexahedron";
    case 28: return "biquadratic quad";
    case 30: return "quadratic linear quad";
    case 34: return "biquadratic triangle";
    case 35: return "cubic line";
    case 42: return "polyhedron";
    case 71: return "Lagrange tetrahedron";
    case 72: return "Lagrange hexahedron";
    default: return "type " + std::to_string(type);
    }
}

// The corners of a lower-dimensional type of fixed size, or 0 for a type
// whose size varies (poly-vertex, polyline, strip, polygon, Lagrange and
// Bezier cells) or any other type. A cell of such a type with another count
// is a mistake, not a boundary marker: a tetrahedron written as a triangle
// with 4 corners would otherwise be skipped, leaving a hole.
int fixed_corner_count(int type) {
    switch (type) {
    case 1: return 1;
    case 3: return 2;
    case 5: return 3;
    case 8: case 9: return 4;
    case 21: return 3;
    case 22: return 6;
    case 23: return 8;
    case 28: return 9;
    case 30: return 6;
    case 34: return 7;
    case 35: return 4;
    default: return 0;
    }
}

// Cells that bound no volume: skipped, as a solver's boundary markers.
bool lower_dimensional(int type) {
    switch (type) {
    case 1: case 2: case 3: case 4: case 5: case 6: case 7: case 8: case 9: // vertices .. quads
    case 21: case 22: case 23: case 28: case 30: case 31: case 32: case 34: case 35: case 36: case 37:
    case 68: case 69: case 70: case 75: case 76: case 77:
        return true;
    default:
        return false;
    }
}

class VtuParser {
public:
    VtuParser(std::string_view bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}

    MeshArrays parse(const VtuRequest& request);

private:
    [[noreturn]] void fail(const std::string& what) const { throw Error(name_ + ": " + what); }

    void split_appended();
    std::uint64_t read_header_word(const unsigned char* at) const {
        if (header_bytes_ == 4) {
            std::uint32_t v;
            std::memcpy(&v, at, 4);
            return v;
        }
        std::uint64_t v;
        std::memcpy(&v, at, 8);
        return v;
    }
    std::string decode_base64(std::string_view text, const std::string& what) const;
    // The bytes of an array of `count` values of `scalar` (binary
    // encodings): a view into the file for uncompressed raw data, else into
    // `storage`, which holds what was decoded.
    std::string_view binary_payload(const pugi::xml_node& array, std::uint64_t count, Scalar scalar,
                                    const std::string& what, std::string& storage) const;
    std::string inflate(std::string_view header, std::string_view blocks, std::uint64_t expected, const std::string& what) const;

    template <class T>
    std::vector<T> read_array(const pugi::xml_node& array, std::uint64_t count, const std::string& what) const;
    pugi::xml_node find_array(const pugi::xml_node& parent, const char* name) const {
        for (const pugi::xml_node a : parent.children("DataArray"))
            if (std::string_view(a.attribute("Name").as_string()) == name) return a;
        return {};
    }
    std::uint64_t count_attribute(const pugi::xml_node& node, const char* attribute) const;

    std::string_view bytes_;
    std::string name_;
    std::string xml_;            // the XML part, closed where the appended block was cut off
    std::string_view appended_;  // the bytes after '_', or empty
    bool appended_base64_ = false;
    bool compressed_ = false;
    std::size_t header_bytes_ = 4;
};

void VtuParser::split_appended() {
    const std::size_t tag = bytes_.find("<AppendedData");
    if (tag == std::string_view::npos) {
        xml_.assign(bytes_);
        return;
    }
    const std::size_t close = bytes_.find('>', tag);
    if (close == std::string_view::npos) fail("the AppendedData element is not closed");
    std::string start_tag(bytes_.substr(tag, close + 1 - tag));
    if (start_tag.size() >= 2 && start_tag[start_tag.size() - 2] == '/') fail("the AppendedData element is empty");
    pugi::xml_document element;
    if (!element.load_string((start_tag + "</AppendedData>").c_str()))
        fail("the AppendedData element's start tag is malformed");
    const std::string_view encoding = element.child("AppendedData").attribute("encoding").as_string("raw");
    if (encoding == "base64")
        appended_base64_ = true;
    else if (encoding != "raw")
        fail("appended data encoding '" + std::string(encoding) + "' is neither raw nor base64");
    const std::size_t underscore = bytes_.find('_', close);
    if (underscore == std::string_view::npos) fail("the appended data has no '_' marker");
    for (std::size_t i = close + 1; i < underscore; ++i)
        if (!std::isspace(static_cast<unsigned char>(bytes_[i]))) fail("text before the appended data's '_' marker");
    appended_ = bytes_.substr(underscore + 1);
    // The XML before the block, closed again: the root is all that is open.
    xml_.assign(bytes_.substr(0, tag));
    xml_ += "</VTKFile>";
}

std::string VtuParser::decode_base64(std::string_view text, const std::string& what) const {
    static const auto table = [] {
        std::array<signed char, 256> t{};
        t.fill(-1);
        const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        for (int i = 0; i < 64; ++i) t[static_cast<unsigned char>(alphabet[i])] = static_cast<signed char>(i);
        return t;
    }();
    std::string out;
    out.reserve(text.size() / 4 * 3 + 3);
    std::uint32_t group = 0;
    int have = 0, padding = 0;
    for (const char c : text) {
        if (std::isspace(static_cast<unsigned char>(c))) continue;
        if (c == '=') {
            if (have < 2) fail(what + ": misplaced '=' in base64 data");
            ++padding;
            group <<= 6;
            if (++have == 4) {
                out.push_back(static_cast<char>(group >> 16));
                if (padding == 1) out.push_back(static_cast<char>(group >> 8));
                group = 0, have = 0, padding = 0;
            }
            continue;
        }
        const int value = table[static_cast<unsigned char>(c)];
        if (value < 0 || padding) fail(what + ": invalid character in base64 data");
        group = group << 6 | static_cast<std::uint32_t>(value);
        if (++have == 4) {
            out.push_back(static_cast<char>(group >> 16));
            out.push_back(static_cast<char>(group >> 8));
            out.push_back(static_cast<char>(group));
            group = 0, have = 0;
        }
    }
    if (have != 0) fail(what + ": base64 data ends inside a group");
    return out;
}

// Length in base64 characters of `bytes` bytes encoded on their own.
std::size_t base64_length(std::uint64_t bytes) { return static_cast<std::size_t>((bytes + 2) / 3 * 4); }

std::string VtuParser::inflate(std::string_view header, std::string_view blocks, std::uint64_t expected,
                               const std::string& what) const {
    const auto* h = reinterpret_cast<const unsigned char*>(header.data());
    const std::uint64_t count = read_header_word(h), block_size = read_header_word(h + header_bytes_),
                        last_size = read_header_word(h + 2 * header_bytes_);
    if (header.size() != (3 + count) * header_bytes_) fail(what + ": compressed block header is truncated");
    std::uint64_t total = 0, compressed = 0;
    for (std::uint64_t b = 0; b < count; ++b) {
        const std::uint64_t size = b + 1 < count || last_size == 0 ? block_size : last_size;
        if (size > block_size) fail(what + ": a compressed block is larger than the block size");
        total += size;
        const std::uint64_t c = read_header_word(h + (3 + b) * header_bytes_);
        if (c > blocks.size() - compressed) fail(what + ": compressed blocks run past the data");
        if (size > kMaxInflateRatio * c + 64) fail(what + ": a compressed block promises more than it can hold");
        compressed += c;
    }
    if (total != expected)
        fail(what + ": " + std::to_string(total) + " bytes compressed, where its values need " + std::to_string(expected));
    std::string out(static_cast<std::size_t>(total), '\0');
    std::uint64_t in_at = 0, out_at = 0;
    for (std::uint64_t b = 0; b < count; ++b) {
        const std::uint64_t size = b + 1 < count || last_size == 0 ? block_size : last_size;
        const std::uint64_t c = read_header_word(h + (3 + b) * header_bytes_);
        uLongf got = static_cast<uLongf>(size);
        const int status = uncompress(reinterpret_cast<Bytef*>(out.data() + out_at), &got,
                                      reinterpret_cast<const Bytef*>(blocks.data() + in_at), static_cast<uLong>(c));
        if (status != Z_OK || got != size) fail(what + ": compressed block " + std::to_string(b) + " is damaged");
        in_at += c;
        out_at += size;
    }
    return out;
}

std::string_view VtuParser::binary_payload(const pugi::xml_node& array, std::uint64_t count, Scalar scalar,
                                           const std::string& what, std::string& storage) const {
    const std::string_view format = array.attribute("format").as_string();
    if (count > std::numeric_limits<std::uint64_t>::max() / 8) fail(what + ": too many values");
    const std::uint64_t expected = count * size_of(scalar);
    std::string header, data;
    if (format == "binary") {
        // Inline base64: the header encoded on its own, then the data.
        std::string text;
        for (const char c : std::string_view(array.text().get()))
            if (!std::isspace(static_cast<unsigned char>(c))) text.push_back(c);
        const std::size_t first = base64_length(header_bytes_ * (compressed_ ? 3 : 1));
        if (text.size() < first) fail(what + ": binary data is shorter than its header");
        if (!compressed_) {
            header = decode_base64(std::string_view(text).substr(0, first), what);
            data = decode_base64(std::string_view(text).substr(first), what);
        } else {
            const std::string start = decode_base64(std::string_view(text).substr(0, first), what);
            const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(start.data()));
            if (blocks > text.size()) fail(what + ": compressed block count exceeds the data");
            const std::size_t length = base64_length(header_bytes_ * (3 + blocks));
            if (text.size() < length) fail(what + ": binary data is shorter than its header");
            header = decode_base64(std::string_view(text).substr(0, length), what);
            data = decode_base64(std::string_view(text).substr(length), what);
        }
    } else if (format == "appended") {
        if (appended_.empty()) fail(what + ": format is appended but the file has no appended data");
        const std::string_view offset_text = array.attribute("offset").as_string();
        std::uint64_t offset = 0;
        const auto [end, ec] = std::from_chars(offset_text.data(), offset_text.data() + offset_text.size(), offset);
        if (ec != std::errc() || end != offset_text.data() + offset_text.size()) fail(what + ": missing or malformed offset");
        if (offset >= appended_.size()) fail(what + ": offset " + std::to_string(offset) + " is past the appended data");
        const std::string_view rest = appended_.substr(static_cast<std::size_t>(offset));
        if (!appended_base64_) {
            if (rest.size() < header_bytes_ * (compressed_ ? 3 : 1)) fail(what + ": appended data is truncated");
            std::uint64_t length = 0;
            if (!compressed_) {
                header.assign(rest.substr(0, header_bytes_));
                length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
            } else {
                const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(rest.data()));
                if (blocks > rest.size() / header_bytes_) fail(what + ": appended data is truncated");
                header.assign(rest.substr(0, static_cast<std::size_t>(header_bytes_ * (3 + blocks))));
                if (header.size() != header_bytes_ * (3 + blocks)) fail(what + ": appended data is truncated");
                for (std::uint64_t b = 0; b < blocks; ++b)
                    length += read_header_word(reinterpret_cast<const unsigned char*>(header.data()) + (3 + b) * header_bytes_);
            }
            if (length > rest.size() - header.size()) fail(what + ": appended data is truncated");
            if (!compressed_) { // the common large case: no copy
                if (length != expected)
                    fail(what + ": " + std::to_string(length) + " bytes, where " + std::to_string(count) +
                         " values need " + std::to_string(expected));
                return rest.substr(header.size(), static_cast<std::size_t>(length));
            }
            data.assign(rest.substr(header.size(), static_cast<std::size_t>(length)));
        } else {
            const std::size_t first = base64_length(header_bytes_ * (compressed_ ? 3 : 1));
            if (rest.size() < first) fail(what + ": appended data is truncated");
            std::string start = decode_base64(rest.substr(0, first), what);
            std::uint64_t length = 0;
            std::size_t header_chars = first;
            if (!compressed_) {
                header = start;
                length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
            } else {
                const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(start.data()));
                if (blocks > rest.size()) fail(what + ": appended data is truncated");
                header_chars = base64_length(header_bytes_ * (3 + blocks));
                if (rest.size() < header_chars) fail(what + ": appended data is truncated");
                header = decode_base64(rest.substr(0, header_chars), what);
                for (std::uint64_t b = 0; b < blocks; ++b)
                    length += read_header_word(reinterpret_cast<const unsigned char*>(header.data()) + (3 + b) * header_bytes_);
            }
            if (length > rest.size()) fail(what + ": appended data is truncated");
            const std::size_t chars = base64_length(length);
            if (chars > rest.size() - header_chars) fail(what + ": appended data is truncated");
            data = decode_base64(rest.substr(header_chars, chars), what);
        }
    } else {
        fail(what + ": unknown format '" + std::string(format) + "'");
    }
    if (compressed_) {
        storage = inflate(header, data, expected, what);
        return storage;
    }
    if (header.size() != header_bytes_) fail(what + ": binary data is shorter than its header");
    const std::uint64_t length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
    if (length != expected)
        fail(what + ": " + std::to_string(length) + " bytes, where " + std::to_string(count) + " values need " +
             std::to_string(expected));
    if (data.size() < expected) fail(what + ": data is truncated");
    data.resize(static_cast<std::size_t>(expected));
    storage = std::move(data);
    return storage;
}

template <class T, class S>
T convert_value(S value, bool& ok) {
    if constexpr (std::is_floating_point_v<T>) {
        return static_cast<T>(value);
    } else if constexpr (std::is_floating_point_v<S>) {
        ok = false; // a float where integers belong: the wrong type
        return T{};
    } else if constexpr (std::is_signed_v<S>) {
        if (value < 0 && !std::is_signed_v<T>) return ok = false, T{};
        if (static_cast<std::int64_t>(value) < static_cast<std::int64_t>(std::numeric_limits<T>::min()) ||
            (value > 0 && static_cast<std::uint64_t>(value) > static_cast<std::uint64_t>(std::numeric_limits<T>::max())))
            return ok = false, T{};
        return static_cast<T>(value);
    } else {
        if (static_cast<std::uint64_t>(value) > static_cast<std::uint64_t>(std::numeric_limits<T>::max())) return ok = false, T{};
        return static_cast<T>(value);
    }
}

template <class T, class S>
void convert_all(std::string_view bytes, std::vector<T>& out, bool& ok) {
    const std::size_t n = bytes.size() / sizeof(S);
    out.resize(n);
    if (n == 0) return; // an empty array's data() may be null, which memcpy must not see
    if constexpr (std::is_same_v<T, S>) {
        std::memcpy(out.data(), bytes.data(), n * sizeof(S));
    } else {
        bool all = true; // checked once at the end: a branch-free loop
        for (std::size_t i = 0; i < n; ++i) {
            S value;
            std::memcpy(&value, bytes.data() + i * sizeof(S), sizeof(S));
            bool one = true;
            out[i] = convert_value<T>(value, one);
            all &= one;
        }
        ok = ok && all;
    }
}

std::uint64_t VtuParser::count_attribute(const pugi::xml_node& node, const char* attribute) const {
    const std::string_view text = node.attribute(attribute).as_string();
    std::uint64_t value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
        fail(std::string(node.name()) + "'s " + attribute + " is missing or not a whole number");
    return value;
}

template <class T>
std::vector<T> VtuParser::read_array(const pugi::xml_node& array, std::uint64_t count, const std::string& what) const {
    if (!array) fail(what + ": missing");
    const std::string_view type = array.attribute("type").as_string();
    const std::optional<Scalar> scalar = scalar_of(type);
    if (!scalar) fail(what + ": unknown type '" + std::string(type) + "'");
    if (std::is_integral_v<T> && !is_integer(*scalar))
        fail(what + ": type " + std::string(type) + " where integers are expected");
    std::vector<T> out;
    bool ok = true;
    if (std::string_view(array.attribute("format").as_string()) == "ascii") {
        // Counted before anything is allocated: the text must hold the values.
        const std::string_view text = array.text().get();
        if (count > text.size() / 2 + 1) fail(what + ": " + std::to_string(count) + " values expected, the text is shorter");
        out.reserve(static_cast<std::size_t>(count));
        const char* at = text.data();
        const char* end = text.data() + text.size();
        while (true) {
            while (at < end && std::isspace(static_cast<unsigned char>(*at))) ++at;
            if (at == end) break;
            if (out.size() == count) fail(what + ": more than the " + std::to_string(count) + " values expected");
            const char* const token = at;
            at = detail::past_plus(at, end);
            if (is_integer(*scalar)) {
                std::int64_t value = 0;
                const auto [next, ec] = std::from_chars(at, end, value);
                if (ec != std::errc() || (next != end && !std::isspace(static_cast<unsigned char>(*next)))) {
                    std::uint64_t big = 0; // UInt64 values above Int64's range
                    const auto [next2, ec2] = std::from_chars(at, end, big);
                    if (ec2 != std::errc() || (next2 != end && !std::isspace(static_cast<unsigned char>(*next2))))
                        fail(what + ": value " + std::to_string(out.size()) + " is not an integer");
                    out.push_back(convert_value<T>(big, ok));
                    at = next2;
                } else {
                    out.push_back(convert_value<T>(value, ok));
                    at = next;
                }
            } else {
                double value = 0;
                const auto [next, ec] = std::from_chars(at, end, value);
                if (ec != std::errc() || (next != end && !std::isspace(static_cast<unsigned char>(*next)))) {
                    fail(what + ": value " + std::to_string(out.size()) + " is not a number");
                }
                out.push_back(convert_value<T>(value, ok));
                at = next;
            }
            if (!ok)
                fail(what + ": value " + std::to_string(out.size() - 1) + " (" + std::string(token, at) +
                     ") is out of range for its use");
        }
        if (out.size() != count)
            fail(what + ": " + std::to_string(out.size()) + " values, where " + std::to_string(count) + " are expected");
        return out;
    }
    std::string storage;
    const std::string_view bytes = binary_payload(array, count, *scalar, what, storage);
    switch (*scalar) {
    case Scalar::int8: convert_all<T, std::int8_t>(bytes, out, ok); break;
    case Scalar::uint8: convert_all<T, std::uint8_t>(bytes, out, ok); break;
    case Scalar::int16: convert_all<T, std::int16_t>(bytes, out, ok); break;
    case Scalar::uint16: convert_all<T, std::uint16_t>(bytes, out, ok); break;
    case Scalar::int32: convert_all<T, std::int32_t>(bytes, out, ok); break;
    case Scalar::uint32: convert_all<T, std::uint32_t>(bytes, out, ok); break;
    case Scalar::int64: convert_all<T, std::int64_t>(bytes, out, ok); break;
    case Scalar::uint64: convert_all<T, std::uint64_t>(bytes, out, ok); break;
    case Scalar::float32: convert_all<T, float>(bytes, out, ok); break;
    case Scalar::float64: convert_all<T, double>(bytes, out, ok); break;
    }
    if (!ok) fail(what + ": a value is out of range for its use");
    return out;
}

MeshArrays VtuParser::parse(const VtuRequest& request) {
    split_appended();
    pugi::xml_document document;
    const pugi::xml_parse_result parsed = document.load_buffer(xml_.data(), xml_.size());
    if (!parsed) fail(std::string("not well-formed XML (") + parsed.description() + " at byte " + std::to_string(parsed.offset) + ")");
    const pugi::xml_node root = document.child("VTKFile");
    if (!root) fail("not a VTK XML file (no VTKFile element)");
    if (std::string_view(root.attribute("type").as_string()) != "UnstructuredGrid")
        fail("a VTK file of type '" + std::string(root.attribute("type").as_string()) + "', not UnstructuredGrid");
    if (std::string_view(root.attribute("byte_order").as_string("LittleEndian")) != "LittleEndian")
        fail("byte order " + std::string(root.attribute("byte_order").as_string()) + ": only LittleEndian files are read");
    const std::string_view header_type = root.attribute("header_type").as_string("UInt32");
    if (header_type == "UInt64") header_bytes_ = 8;
    else if (header_type != "UInt32") fail("header type '" + std::string(header_type) + "' is neither UInt32 nor UInt64");
    const std::string_view compressor = root.attribute("compressor").as_string();
    if (compressor == "vtkZLibDataCompressor") compressed_ = true;
    else if (!compressor.empty()) fail("compressor " + std::string(compressor) + ": only vtkZLibDataCompressor is read");

    const pugi::xml_node grid = root.child("UnstructuredGrid");
    if (!grid) fail("no UnstructuredGrid element");
    const pugi::xml_node piece = grid.child("Piece");
    if (!piece) fail("no Piece element");
    if (piece.next_sibling("Piece")) fail("several Piece elements in one file; tetiso reads one piece per .vtu");
    const std::uint64_t points = count_attribute(piece, "NumberOfPoints");
    const std::uint64_t cells = count_attribute(piece, "NumberOfCells");
    if (points > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()) ||
        cells > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()))
        fail("more points or cells than one domain's 32-bit indices can hold");

    MeshArrays out;
    const pugi::xml_node point_array = piece.child("Points").child("DataArray");
    if (!point_array && points > 0) fail("no Points array");
    if (point_array) {
        if (point_array.attribute("NumberOfComponents").as_int(1) != 3) fail("the points do not have 3 components");
        const auto xyz = read_array<double>(point_array, 3 * points, "the points");
        out.x.resize(points), out.y.resize(points), out.z.resize(points);
        for (std::size_t i = 0; i < points; ++i) {
            out.x[i] = xyz[3 * i], out.y[i] = xyz[3 * i + 1], out.z[i] = xyz[3 * i + 2];
            for (int k = 0; k < 3; ++k)
                if (!(std::abs(xyz[3 * i + static_cast<std::size_t>(k)]) <= std::numeric_limits<float>::max()))
                    fail("the coordinates of point " + std::to_string(i) + " are not finite numbers in float range");
        }
    }

    const pugi::xml_node cell_node = piece.child("Cells");
    if (!cell_node && cells > 0) fail("no Cells element");
    const auto offsets = cells ? read_array<std::int64_t>(find_array(cell_node, "offsets"), cells, "the cell offsets")
                               : std::vector<std::int64_t>{};
    const auto types = cells ? read_array<std::uint8_t>(find_array(cell_node, "types"), cells, "the cell types")
                             : std::vector<std::uint8_t>{};
    const std::int64_t corner_count = cells ? offsets.back() : 0;
    if (corner_count < 0 || static_cast<std::uint64_t>(corner_count) > 1000 * cells)
        fail("the last cell offset " + std::to_string(corner_count) + " is out of range");
    const pugi::xml_node connectivity_node = find_array(cell_node, "connectivity");
    if (cells > 0 && !connectivity_node) fail("no connectivity array");
    // Point indices fit 32 bits (the point count does), whatever the type.
    auto connectivity = cells ? read_array<std::int32_t>(connectivity_node, static_cast<std::uint64_t>(corner_count), "the connectivity")
                              : std::vector<std::int32_t>{};
    std::vector<std::uint8_t> ghost;
    for (const pugi::xml_node a : piece.child("CellData").children("DataArray"))
        if (std::string_view(a.attribute("Name").as_string()) == "vtkGhostType")
            ghost = read_array<std::uint8_t>(a, cells, "cell array vtkGhostType");

    // The common case, a piece of tetrahedra only and no ghosts: the
    // connectivity is the tetrahedra, checked in one pass.
    bool only_tets = cells > 0 && ghost.empty() && static_cast<std::uint64_t>(corner_count) == 4 * cells;
    for (std::size_t c = 0; c < cells && only_tets; ++c)
        only_tets = types[c] == kVtkTetra && offsets[c] == static_cast<std::int64_t>(4 * (c + 1));
    if (only_tets) {
        bool in_range = true, distinct = true;
        const auto n = static_cast<std::int64_t>(points);
        for (std::size_t c = 0; c < cells; ++c) {
            const std::int32_t* v = connectivity.data() + 4 * c;
            for (int k = 0; k < 4; ++k) in_range &= v[k] >= 0 && v[k] < n;
            distinct &= v[0] != v[1] && v[0] != v[2] && v[0] != v[3] && v[1] != v[2] && v[1] != v[3] && v[2] != v[3];
        }
        only_tets = in_range && distinct;
        if (only_tets) out.tets = std::move(connectivity);
        // else: the cell-by-cell pass below names the culprit
    }
    // Which cells are tetrahedra, and which volume cells are not.
    std::vector<std::uint64_t> other(256, 0);
    std::int64_t previous = 0;
    for (std::size_t c = 0; c < cells && !only_tets; ++c) {
        const std::int64_t end = offsets[c];
        if (end < previous || end > corner_count) fail("cell offset " + std::to_string(c) + " is out of order or range");
        const std::int64_t corners = end - previous;
        const int type = types[c];
        if (!ghost.empty() && (ghost[c] & kDuplicateCell)) {
            ++out.ghost_cells;
        } else if (type == kVtkTetra || (type == kVtkLagrangeTetra && corners == 4)) {
            if (corners != 4) fail("cell " + std::to_string(c) + " is a tetrahedron with " + std::to_string(corners) + " corners");
            std::int32_t v[4];
            for (int k = 0; k < 4; ++k) {
                const std::int64_t p = connectivity[static_cast<std::size_t>(previous + k)];
                if (p < 0 || static_cast<std::uint64_t>(p) >= points)
                    fail("cell " + std::to_string(c) + " refers to point " + std::to_string(p) + " of " + std::to_string(points));
                v[k] = static_cast<std::int32_t>(p);
                for (int j = 0; j < k; ++j)
                    if (v[j] == v[k]) fail("cell " + std::to_string(c) + " repeats point " + std::to_string(p));
            }
            out.tets.insert(out.tets.end(), v, v + 4);
        } else if (!lower_dimensional(type)) {
            ++other[static_cast<std::size_t>(type)];
        } else if (fixed_corner_count(type) != 0 && corners != fixed_corner_count(type)) {
            fail("cell " + std::to_string(c) + " is a " + cell_type_name(type) + " with " + std::to_string(corners) +
                 " corners (type " + std::to_string(type) + " has " + std::to_string(fixed_corner_count(type)) + ")");
        }
        previous = end;
    }
    for (int type = 0; type < 256; ++type)
        if (other[static_cast<std::size_t>(type)])
            fail(std::to_string(other[static_cast<std::size_t>(type)]) + " volume cells of type " + std::to_string(type) +
                 " (" + cell_type_name(type) + "); tetiso reads linear tetrahedra (type 10, or 71 with 4 points) only");

    const pugi::xml_node point_data = piece.child("PointData");
    if (!request.array.empty()) {
        const pugi::xml_node a = find_array(point_data, request.array.c_str());
        if (!a) {
            std::string names;
            for (const pugi::xml_node b : point_data.children("DataArray"))
                names += std::string(names.empty() ? "" : ", ") + b.attribute("Name").as_string();
            fail("no point array '" + request.array + "'" + (names.empty() ? " (it has none)" : " (it has: " + names + ")"));
        }
        if (a.attribute("NumberOfComponents").as_int(1) != 1)
            fail("point array '" + request.array + "' has " + a.attribute("NumberOfComponents").as_string() +
                 " components; the field must be a scalar");
        out.f = read_array<double>(a, points, "point array '" + request.array + "'");
        for (std::size_t i = 0; i < points; ++i)
            if (!(std::abs(out.f[i]) <= std::numeric_limits<float>::max()))
                fail("point array '" + request.array + "': the value at point " + std::to_string(i) +
                     " is not a finite number in float range");
    }
    std::string ids_name = request.node_ids;
    if (ids_name.empty()) ids_name = point_data.attribute("GlobalIds").as_string();
    if (ids_name.empty() && find_array(point_data, "GlobalNodeIds")) ids_name = "GlobalNodeIds";
    const pugi::xml_node ids_array = ids_name.empty() ? pugi::xml_node() : find_array(point_data, ids_name.c_str());
    if (ids_array) {
        if (ids_array.attribute("NumberOfComponents").as_int(1) != 1)
            fail("node id array '" + ids_name + "' has more than one component");
        // Read straight into the result (GlobalId is 64-bit), not copied there.
        out.ids = read_array<GlobalId>(ids_array, points, "node id array '" + ids_name + "'");
        for (std::size_t i = 0; i < points; ++i)
            if (out.ids[i] < 0 || out.ids[i] > kMaxGlobalId)
                fail("node id array '" + ids_name + "': id " + std::to_string(out.ids[i]) + " of point " +
                     std::to_string(i) + " is outside [0, 2^32)");
    } else if (!request.node_ids.empty() || request.require_node_ids) {
        std::string names;
        for (const pugi::xml_node b : point_data.children("DataArray")) {
            const auto s = scalar_of(b.attribute("type").as_string());
            if (s && is_integer(*s) && b.attribute("NumberOfComponents").as_int(1) == 1)
                names += std::string(names.empty() ? "" : ", ") + b.attribute("Name").as_string();
        }
        fail((request.node_ids.empty() ? std::string("no global node ids (no array marked GlobalIds, none named GlobalNodeIds)")
                                       : "no point array '" + request.node_ids + "'") +
             "; pieces are matched by node ids, never by coordinates: name one with --node-ids (integer point arrays: " +
             (names.empty() ? std::string("none") : names) + ")");
    }
    return out;
}

} // namespace

MeshArrays parse_vtu(std::string_view bytes, const std::string& name, const VtuRequest& request) {
    return VtuParser(bytes, name).parse(request);
}

MeshArrays read_vtu(const std::filesystem::path& path, const VtuRequest& request) {
    const detail::MappedFile file(path);
    return parse_vtu(file.bytes(), path.string(), request);
}

} // namespace tetiso
