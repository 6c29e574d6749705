// PLY surfaces. Writing: binary little-endian with tetiso's vertex key and
// flags as extra properties, and each face's error bound where the piece has
// them. Reading: ascii and binary of either byte order,
// any scalar types, other elements and properties skipped, polygons fanned.
// No count in the header is trusted before the file is known to hold it.
#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {
namespace {

static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian host");

enum class Scalar { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

struct Property {
    std::string name;
    bool is_list = false;
    Scalar count_type = Scalar::uint8;
    Scalar type = Scalar::float32;
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> properties;
};

std::size_t size_of(Scalar s) {
    switch (s) {
    case Scalar::int8:
    case Scalar::uint8: return 1;
    case Scalar::int16:
    case Scalar::uint16: return 2;
    case Scalar::int32:
    case Scalar::uint32:
    case Scalar::float32: return 4;
    case Scalar::float64: return 8;
    }
    return 0;
}

class Reader {
public:
    Reader(std::filesystem::path path) : path_(std::move(path)) {}

    [[noreturn]] void fail(const std::string& what) const { throw Error(path_.string() + ": " + what); }

    Scalar parse_type(const std::string& word) const {
        if (word == "char" || word == "int8") return Scalar::int8;
        if (word == "uchar" || word == "uint8") return Scalar::uint8;
        if (word == "short" || word == "int16") return Scalar::int16;
        if (word == "ushort" || word == "uint16") return Scalar::uint16;
        if (word == "int" || word == "int32") return Scalar::int32;
        if (word == "uint" || word == "uint32") return Scalar::uint32;
        if (word == "float" || word == "float32") return Scalar::float32;
        if (word == "double" || word == "float64") return Scalar::float64;
        fail("unknown PLY property type '" + word + "'");
    }

    Piece read() {
        data_ = read_whole_file(path_);
        parse_header();

        Piece piece;
        bool has_vertices = false;
        for (const Element& element : elements_) {
            if (element.name == "vertex") {
                read_vertices(element, piece);
                has_vertices = true;
            }
            else if (element.name == "face")
                read_faces(element, piece);
            else
                skip_element(element);
        }
        if (!has_vertices) fail("no vertex element");
        return piece;
    }

private:
    void parse_header() {
        std::size_t line_start = 0;
        int line_number = 0;
        bool ended = false;
        while (!ended) {
            const std::size_t end = std::find(data_.begin() + static_cast<std::ptrdiff_t>(line_start), data_.end(), '\n') - data_.begin();
            if (end == data_.size()) fail("header has no end_header line");
            std::string line(data_.data() + line_start, end - line_start);
            if (!line.empty() && line.back() == '\r') line.pop_back();
            line_start = end + 1;
            ++line_number;
            std::istringstream words(line);
            std::string word;
            words >> word;
            if (line_number == 1) {
                if (word != "ply") fail("not a PLY file (no 'ply' magic line)");
                continue;
            }
            if (word.empty() || word == "comment" || word == "obj_info") continue;
            if (word == "format") {
                std::string format;
                words >> format;
                if (format == "ascii")
                    encoding_ = Encoding::ascii;
                else if (format == "binary_little_endian")
                    encoding_ = Encoding::little;
                else if (format == "binary_big_endian")
                    encoding_ = Encoding::big;
                else
                    fail("unknown PLY format '" + format + "'");
            } else if (word == "element") {
                Element element;
                words >> element.name >> element.count;
                if (!words) fail("malformed element line " + std::to_string(line_number));
                elements_.push_back(element);
            } else if (word == "property") {
                if (elements_.empty()) fail("property before any element on line " + std::to_string(line_number));
                Property property;
                std::string type;
                words >> type;
                if (type == "list") {
                    std::string count_type, item_type;
                    words >> count_type >> item_type;
                    property.is_list = true;
                    property.count_type = parse_type(count_type);
                    property.type = parse_type(item_type);
                } else {
                    property.type = parse_type(type);
                }
                words >> property.name;
                if (!words) fail("malformed property line " + std::to_string(line_number));
                elements_.back().properties.push_back(property);
            } else if (word == "end_header") {
                ended = true;
            } else {
                fail("unexpected header line " + std::to_string(line_number) + ": '" + line + "'");
            }
        }
        position_ = line_start;
        // Each record takes at least one byte (binary) or two characters (ascii).
        const std::size_t remaining = data_.size() - position_;
        for (const Element& element : elements_) {
            // An ascii value takes at least a digit and a separator.
            std::size_t smallest = 0;
            for (const Property& p : element.properties)
                smallest += encoding_ == Encoding::ascii ? 2 : size_of(p.is_list ? p.count_type : p.type);
            smallest = std::max<std::size_t>(smallest, 1);
            if (element.count > remaining / smallest)
                fail("header announces " + std::to_string(element.count) + " " + element.name +
                     " records, more than the file can hold");
        }
    }

    [[noreturn]] void truncated(const Element& element, std::uint64_t record) const {
        fail("file ends inside " + element.name + " " + std::to_string(record) + " of " +
             std::to_string(element.count));
    }

    // Reads one value, as double (exact for every PLY integer type).
    bool next(Scalar type, double& value) {
        if (encoding_ == Encoding::ascii) {
            while (position_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[position_]))) ++position_;
            const char* first = data_.data() + position_;
            const char* last = data_.data() + data_.size();
            const auto [end, error] = std::from_chars(past_plus(first, last), last, value);
            if (error != std::errc()) return false;
            position_ += static_cast<std::size_t>(end - first);
            return true;
        }
        const std::size_t size = size_of(type);
        if (position_ + size > data_.size()) return false;
        unsigned char bytes[8];
        std::memcpy(bytes, data_.data() + position_, size);
        if (encoding_ == Encoding::big) std::reverse(bytes, bytes + size);
        position_ += size;
        switch (type) {
        case Scalar::int8: value = static_cast<std::int8_t>(bytes[0]); break;
        case Scalar::uint8: value = bytes[0]; break;
        case Scalar::int16: value = load<std::int16_t>(bytes); break;
        case Scalar::uint16: value = load<std::uint16_t>(bytes); break;
        case Scalar::int32: value = load<std::int32_t>(bytes); break;
        case Scalar::uint32: value = load<std::uint32_t>(bytes); break;
        case Scalar::float32: value = load<float>(bytes); break;
        case Scalar::float64: value = load<double>(bytes); break;
        }
        return true;
    }

    template <class T>
    static T load(const unsigned char* bytes) {
        T value;
        std::memcpy(&value, bytes, sizeof(T));
        return value;
    }

    void read_vertices(const Element& element, Piece& piece) {
        int x = -1, y = -1, z = -1, key_hi = -1, key_lo = -1, flags = -1;
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const std::string& name = element.properties[p].name;
            const int index = static_cast<int>(p);
            if (name == "x") x = index;
            if (name == "y") y = index;
            if (name == "z") z = index;
            if (name == kKeyHighName) key_hi = index;
            if (name == kKeyLowName) key_lo = index;
            if (name == kFlagsName) flags = index;
        }
        if (x < 0 || y < 0 || z < 0) fail("vertex element lacks x, y or z");
        const bool keyed = key_hi >= 0 && key_lo >= 0;
        const auto n = static_cast<std::size_t>(element.count);
        piece.x.resize(n);
        piece.y.resize(n);
        piece.z.resize(n);
        piece.key.resize(n);
        piece.flags.assign(n, 0);
        std::vector<double> values(element.properties.size());
        // Keys and flags must be whole numbers of their width; a float
        // property or an ascii "2.5" or "nan" there is an error, not a guess.
        auto integer = [&](std::size_t v, int property, double limit) {
            const double value = values[static_cast<std::size_t>(property)];
            if (!whole_below(value, limit))
                fail("vertex " + std::to_string(v) + " has " + element.properties[static_cast<std::size_t>(property)].name +
                     " " + std::to_string(value) + ", not a whole number below " +
                     std::to_string(static_cast<std::uint64_t>(limit)));
            return value;
        };
        for (std::size_t v = 0; v < n; ++v) {
            for (std::size_t p = 0; p < element.properties.size(); ++p) read_property(element, v, p, values[p]);
            piece.x[v] = static_cast<float>(values[static_cast<std::size_t>(x)]);
            piece.y[v] = static_cast<float>(values[static_cast<std::size_t>(y)]);
            piece.z[v] = static_cast<float>(values[static_cast<std::size_t>(z)]);
            piece.key[v] = keyed ? (static_cast<EdgeKey>(integer(v, key_hi, 0x1p32)) << 32) |
                                       static_cast<EdgeKey>(integer(v, key_lo, 0x1p32))
                                 : static_cast<EdgeKey>(v);
            if (flags >= 0) piece.flags[v] = static_cast<std::uint8_t>(integer(v, flags, 256));
        }
    }

    // Reads property p of record `record`; a list's items are skipped and its
    // value is its length.
    void read_property(const Element& element, std::uint64_t record, std::size_t p, double& value) {
        const Property& property = element.properties[p];
        if (!property.is_list) {
            if (!next(property.type, value)) truncated(element, record);
            return;
        }
        double count = 0, ignored = 0;
        if (!next(property.count_type, count)) truncated(element, record);
        if (!whole_below(count, 0x1p32))
            fail(element.name + " " + std::to_string(record) + " has a list length that is not a count");
        for (double k = 0; k < count; ++k)
            if (!next(property.type, ignored)) truncated(element, record);
        value = count;
    }

    void read_faces(const Element& element, Piece& piece) {
        int indices = -1, bound = -1;
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            if (element.properties[p].is_list &&
                (element.properties[p].name == "vertex_indices" || element.properties[p].name == "vertex_index"))
                indices = static_cast<int>(p);
            if (!element.properties[p].is_list && element.properties[p].name == kErrorBoundName)
                bound = static_cast<int>(p);
        }
        if (indices < 0) fail("face element has no vertex_indices list");
        piece.triangles.reserve(static_cast<std::size_t>(element.count) * 3);
        std::vector<std::int64_t> polygon;
        for (std::uint64_t f = 0; f < element.count; ++f) {
            double face_bound = 0;
            for (std::size_t p = 0; p < element.properties.size(); ++p) {
                const Property& property = element.properties[p];
                if (static_cast<int>(p) == bound) {
                    read_property(element, f, p, face_bound);
                    if (!(face_bound >= 0 && face_bound <= std::numeric_limits<float>::max()))
                        fail("face " + std::to_string(f) + " has " + kErrorBoundName + " " +
                             std::to_string(face_bound) + ", not a finite non-negative float");
                    continue;
                }
                if (static_cast<int>(p) != indices) {
                    double ignored;
                    read_property(element, f, p, ignored);
                    continue;
                }
                double count = 0;
                if (!next(property.count_type, count)) truncated(element, f);
                if (!whole_below(count, 0x1p32) || count < 3)
                    fail("face " + std::to_string(f) + " has " + std::to_string(count) +
                         " vertices, not a whole number of at least 3");
                polygon.clear();
                for (double k = 0; k < count; ++k) {
                    double index = 0;
                    if (!next(property.type, index)) truncated(element, f);
                    if (!whole_below(index, 0x1p31))
                        fail("face " + std::to_string(f) + " has vertex index " + std::to_string(index) +
                             ", not a whole number in 32-bit range");
                    polygon.push_back(static_cast<std::int64_t>(index));
                }
                for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
                    piece.triangles.push_back(static_cast<std::int32_t>(polygon[0]));
                    piece.triangles.push_back(static_cast<std::int32_t>(polygon[k]));
                    piece.triangles.push_back(static_cast<std::int32_t>(polygon[k + 1]));
                }
            }
            // A polygon's bound holds for every triangle it is cut into.
            if (bound >= 0) piece.error.resize(piece.triangle_count(), static_cast<float>(face_bound));
        }
    }

    void skip_element(const Element& element) {
        double ignored;
        for (std::uint64_t r = 0; r < element.count; ++r)
            for (std::size_t p = 0; p < element.properties.size(); ++p) read_property(element, r, p, ignored);
    }

    enum class Encoding { ascii, little, big };
    std::filesystem::path path_;
    std::string data_;
    std::size_t position_ = 0;
    Encoding encoding_ = Encoding::ascii;
    std::vector<Element> elements_;
};

} // namespace

void write_ply(const Piece& piece, const std::filesystem::path& path) {
    const bool bounds = !piece.error.empty();
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    if (!file) throw Error(path.string() + ": cannot open for writing: " + std::strerror(errno));
    file << "ply\nformat binary_little_endian 1.0\ncomment written by tetiso\n"
         << "element vertex " << piece.vertex_count() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property uint " << kKeyHighName << "\nproperty uint " << kKeyLowName << "\nproperty uchar " << kFlagsName
         << "\n"
         << "element face " << piece.triangle_count() << "\n"
         << "property list uchar int vertex_indices\n"
         << (bounds ? std::string("property float ") + kErrorBoundName + "\n" : std::string())
         << "end_header\n";

    constexpr std::size_t kVertexBytes = 3 * 4 + 2 * 4 + 1;
    constexpr std::size_t kFaceBytes = 1 + 3 * 4;
    std::vector<char> buffer;
    buffer.reserve(1 << 20);
    auto put = [&](const void* bytes, std::size_t size) {
        const char* p = static_cast<const char*>(bytes);
        buffer.insert(buffer.end(), p, p + size);
    };
    auto flush_if_full = [&] {
        if (buffer.size() >= (1u << 20)) {
            file.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            buffer.clear();
        }
    };
    for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
        const std::uint32_t hi = static_cast<std::uint32_t>(piece.key[v] >> 32);
        const std::uint32_t lo = static_cast<std::uint32_t>(piece.key[v]);
        put(&piece.x[v], 4);
        put(&piece.y[v], 4);
        put(&piece.z[v], 4);
        put(&hi, 4);
        put(&lo, 4);
        put(&piece.flags[v], 1);
        static_assert(kVertexBytes == 21);
        flush_if_full();
    }
    const std::uint8_t three = 3;
    for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
        put(&three, 1);
        put(&piece.triangles[3 * t], 12);
        if (bounds) put(&piece.error[t], 4);
        static_assert(kFaceBytes == 13);
        flush_if_full();
    }
    file.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    file.close();
    if (!file) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
}

Piece read_ply(const std::filesystem::path& path) { return Reader(path).read(); }

} // namespace tetiso::detail
