// The values of a VTK XML DataArray (see vtu_arrays.hpp): ascii numbers, or
// binary data (inline base64 or appended, raw or base64) behind a header of
// the file's header type, whole or in zlib blocks. Every size a header
// states is checked against the bytes present and against what the piece's
// counts require before anything of that size is allocated; values are
// converted to the type the mesh needs with range checks.
#include "vtu_arrays.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

#include <zlib.h>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso::vtu {
namespace {

// zlib cannot inflate more than about 1032 bytes from one; a block header
// that promises more is damaged (or a bomb).
constexpr std::uint64_t kMaxInflateRatio = 1100;

std::size_t size_of(Scalar s) {
    switch (s) {
    case Scalar::int8: case Scalar::uint8: return 1;
    case Scalar::int16: case Scalar::uint16: return 2;
    case Scalar::int32: case Scalar::uint32: case Scalar::float32: return 4;
    default: return 8;
    }
}


// Length in base64 characters of `bytes` bytes encoded on their own.
std::size_t base64_length(std::uint64_t bytes) { return static_cast<std::size_t>((bytes + 2) / 3 * 4); }

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

} // namespace

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

bool is_integer(Scalar s) { return s != Scalar::float32 && s != Scalar::float64; }

ArrayReader::ArrayReader(std::string name, Encoding encoding) : name_(std::move(name)), encoding_(encoding) {}

void ArrayReader::fail(const std::string& what) const { throw Error(name_ + ": " + what); }

std::uint64_t ArrayReader::read_header_word(const unsigned char* at) const {
    if (encoding_.header_bytes == 4) {
        std::uint32_t v;
        std::memcpy(&v, at, 4);
        return v;
    }
    std::uint64_t v;
    std::memcpy(&v, at, 8);
    return v;
}

std::string ArrayReader::decode_base64(std::string_view text, const std::string& what) const {
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

std::string ArrayReader::inflate(std::string_view header, std::string_view blocks, std::uint64_t expected,
                               const std::string& what) const {
    const auto* h = reinterpret_cast<const unsigned char*>(header.data());
    const std::uint64_t count = read_header_word(h), block_size = read_header_word(h + encoding_.header_bytes),
                        last_size = read_header_word(h + 2 * encoding_.header_bytes);
    if (header.size() != (3 + count) * encoding_.header_bytes) fail(what + ": compressed block header is truncated");
    std::uint64_t total = 0, compressed = 0;
    for (std::uint64_t b = 0; b < count; ++b) {
        const std::uint64_t size = b + 1 < count || last_size == 0 ? block_size : last_size;
        if (size > block_size) fail(what + ": a compressed block is larger than the block size");
        total += size;
        const std::uint64_t c = read_header_word(h + (3 + b) * encoding_.header_bytes);
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
        const std::uint64_t c = read_header_word(h + (3 + b) * encoding_.header_bytes);
        uLongf got = static_cast<uLongf>(size);
        const int status = uncompress(reinterpret_cast<Bytef*>(out.data() + out_at), &got,
                                      reinterpret_cast<const Bytef*>(blocks.data() + in_at), static_cast<uLong>(c));
        if (status != Z_OK || got != size) fail(what + ": compressed block " + std::to_string(b) + " is damaged");
        in_at += c;
        out_at += size;
    }
    return out;
}

std::string_view ArrayReader::binary_payload(const pugi::xml_node& array, std::uint64_t count, Scalar scalar,
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
        const std::size_t first = base64_length(encoding_.header_bytes * (encoding_.compressed ? 3 : 1));
        if (text.size() < first) fail(what + ": binary data is shorter than its header");
        if (!encoding_.compressed) {
            header = decode_base64(std::string_view(text).substr(0, first), what);
            data = decode_base64(std::string_view(text).substr(first), what);
        } else {
            const std::string start = decode_base64(std::string_view(text).substr(0, first), what);
            const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(start.data()));
            if (blocks > text.size()) fail(what + ": compressed block count exceeds the data");
            const std::size_t length = base64_length(encoding_.header_bytes * (3 + blocks));
            if (text.size() < length) fail(what + ": binary data is shorter than its header");
            header = decode_base64(std::string_view(text).substr(0, length), what);
            data = decode_base64(std::string_view(text).substr(length), what);
        }
    } else if (format == "appended") {
        if (encoding_.appended.empty()) fail(what + ": format is appended but the file has no appended data");
        const std::string_view offset_text = array.attribute("offset").as_string();
        std::uint64_t offset = 0;
        const auto [end, ec] = std::from_chars(offset_text.data(), offset_text.data() + offset_text.size(), offset);
        if (ec != std::errc() || end != offset_text.data() + offset_text.size()) fail(what + ": missing or malformed offset");
        if (offset >= encoding_.appended.size()) fail(what + ": offset " + std::to_string(offset) + " is past the appended data");
        const std::string_view rest = encoding_.appended.substr(static_cast<std::size_t>(offset));
        if (!encoding_.appended_base64) {
            if (rest.size() < encoding_.header_bytes * (encoding_.compressed ? 3 : 1)) fail(what + ": appended data is truncated");
            std::uint64_t length = 0;
            if (!encoding_.compressed) {
                header.assign(rest.substr(0, encoding_.header_bytes));
                length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
            } else {
                const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(rest.data()));
                if (blocks > rest.size() / encoding_.header_bytes) fail(what + ": appended data is truncated");
                header.assign(rest.substr(0, static_cast<std::size_t>(encoding_.header_bytes * (3 + blocks))));
                if (header.size() != encoding_.header_bytes * (3 + blocks)) fail(what + ": appended data is truncated");
                for (std::uint64_t b = 0; b < blocks; ++b)
                    length += read_header_word(reinterpret_cast<const unsigned char*>(header.data()) + (3 + b) * encoding_.header_bytes);
            }
            if (length > rest.size() - header.size()) fail(what + ": appended data is truncated");
            if (!encoding_.compressed) { // the common large case: no copy
                if (length != expected)
                    fail(what + ": " + std::to_string(length) + " bytes, where " + std::to_string(count) +
                         " values need " + std::to_string(expected));
                return rest.substr(header.size(), static_cast<std::size_t>(length));
            }
            data.assign(rest.substr(header.size(), static_cast<std::size_t>(length)));
        } else {
            const std::size_t first = base64_length(encoding_.header_bytes * (encoding_.compressed ? 3 : 1));
            if (rest.size() < first) fail(what + ": appended data is truncated");
            std::string start = decode_base64(rest.substr(0, first), what);
            std::uint64_t length = 0;
            std::size_t header_chars = first;
            if (!encoding_.compressed) {
                header = start;
                length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
            } else {
                const std::uint64_t blocks = read_header_word(reinterpret_cast<const unsigned char*>(start.data()));
                if (blocks > rest.size()) fail(what + ": appended data is truncated");
                header_chars = base64_length(encoding_.header_bytes * (3 + blocks));
                if (rest.size() < header_chars) fail(what + ": appended data is truncated");
                header = decode_base64(rest.substr(0, header_chars), what);
                for (std::uint64_t b = 0; b < blocks; ++b)
                    length += read_header_word(reinterpret_cast<const unsigned char*>(header.data()) + (3 + b) * encoding_.header_bytes);
            }
            if (length > rest.size()) fail(what + ": appended data is truncated");
            const std::size_t chars = base64_length(length);
            if (chars > rest.size() - header_chars) fail(what + ": appended data is truncated");
            data = decode_base64(rest.substr(header_chars, chars), what);
        }
    } else {
        fail(what + ": unknown format '" + std::string(format) + "'");
    }
    if (encoding_.compressed) {
        storage = inflate(header, data, expected, what);
        return storage;
    }
    if (header.size() != encoding_.header_bytes) fail(what + ": binary data is shorter than its header");
    const std::uint64_t length = read_header_word(reinterpret_cast<const unsigned char*>(header.data()));
    if (length != expected)
        fail(what + ": " + std::to_string(length) + " bytes, where " + std::to_string(count) + " values need " +
             std::to_string(expected));
    if (data.size() < expected) fail(what + ": data is truncated");
    data.resize(static_cast<std::size_t>(expected));
    storage = std::move(data);
    return storage;
}

template <class T>
std::vector<T> ArrayReader::read(const pugi::xml_node& array, std::uint64_t count, const std::string& what) const {
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

template std::vector<double> ArrayReader::read(const pugi::xml_node&, std::uint64_t, const std::string&) const;
template std::vector<std::int64_t> ArrayReader::read(const pugi::xml_node&, std::uint64_t, const std::string&) const;
template std::vector<std::int32_t> ArrayReader::read(const pugi::xml_node&, std::uint64_t, const std::string&) const;
template std::vector<std::uint8_t> ArrayReader::read(const pugi::xml_node&, std::uint64_t, const std::string&) const;

} // namespace tetiso::vtu
