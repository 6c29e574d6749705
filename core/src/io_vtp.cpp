// VTK XML PolyData (.vtp), the format ParaView opens natively. Written with
// raw appended binary data (no base64, no compression): the fastest form to
// write and read, and still a standard VTK file. The reader accepts that form
// with any of VTK's header and index widths; other encodings get a clear
// error rather than a guess.
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {
namespace {

struct Block {
    const void* data;
    std::size_t bytes;
};

// One XML start tag's attributes.
using Attributes = std::map<std::string, std::string>;

Attributes parse_attributes(const std::string& tag) {
    Attributes attributes;
    std::size_t i = tag.find(' ');
    while (i != std::string::npos && i < tag.size()) {
        const std::size_t equals = tag.find('=', i);
        if (equals == std::string::npos) break;
        const std::size_t open = tag.find('"', equals);
        const std::size_t close = open == std::string::npos ? open : tag.find('"', open + 1);
        if (close == std::string::npos) break;
        std::string name = tag.substr(i, equals - i);
        name.erase(0, name.find_first_not_of(" \t\r\n"));
        name.erase(name.find_last_not_of(" \t\r\n") + 1);
        attributes[name] = tag.substr(open + 1, close - open - 1);
        i = close + 1;
    }
    return attributes;
}

} // namespace

void write_vtp(const Piece& piece, const std::filesystem::path& path) {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    if (!file) throw Error(path.string() + ": cannot open for writing: " + std::strerror(errno));
    const std::size_t n = piece.vertex_count(), m = piece.triangle_count();

    std::vector<float> points(3 * n);
    for (std::size_t v = 0; v < n; ++v) {
        points[3 * v] = piece.x[v];
        points[3 * v + 1] = piece.y[v];
        points[3 * v + 2] = piece.z[v];
    }
    std::vector<std::int64_t> offsets(m);
    for (std::size_t t = 0; t < m; ++t) offsets[t] = static_cast<std::int64_t>(3 * (t + 1));

    // The error bounds go last, and only when the piece has them.
    const bool bounds = !piece.error.empty();
    const Block blocks[] = {{piece.key.data(), n * sizeof(EdgeKey)},
                            {piece.flags.data(), n},
                            {points.data(), points.size() * sizeof(float)},
                            {piece.triangles.data(), piece.triangles.size() * sizeof(std::int32_t)},
                            {offsets.data(), offsets.size() * sizeof(std::int64_t)},
                            {piece.error.data(), piece.error.size() * sizeof(float)}};
    const int block_count = bounds ? 6 : 5;
    std::size_t offset[6];
    std::size_t running = 0;
    for (int b = 0; b < block_count; ++b) {
        offset[b] = running;
        running += sizeof(std::uint64_t) + blocks[b].bytes;
    }
    file << "<?xml version=\"1.0\"?>\n"
         << "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
         << "  <PolyData>\n"
         << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
         << "NumberOfPolys=\"" << m << "\">\n"
         << "      <PointData>\n"
         << "        <DataArray type=\"UInt64\" Name=\"" << kKeyName << "\" NumberOfComponents=\"1\" format=\"appended\" offset=\""
         << offset[0] << "\"/>\n"
         << "        <DataArray type=\"UInt8\" Name=\"" << kFlagsName << "\" NumberOfComponents=\"1\" format=\"appended\" offset=\""
         << offset[1] << "\"/>\n"
         << "      </PointData>\n";
    if (bounds)
        file << "      <CellData>\n"
             << "        <DataArray type=\"Float32\" Name=\"" << kErrorBoundName
             << "\" NumberOfComponents=\"1\" format=\"appended\" offset=\"" << offset[5] << "\"/>\n"
             << "      </CellData>\n";
    file << "      <Points>\n"
         << "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\""
         << offset[2] << "\"/>\n"
         << "      </Points>\n"
         << "      <Polys>\n"
         << "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"" << offset[3]
         << "\"/>\n"
         << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" << offset[4] << "\"/>\n"
         << "      </Polys>\n"
         << "    </Piece>\n"
         << "  </PolyData>\n"
         << "  <AppendedData encoding=\"raw\">\n   _";
    for (int b = 0; b < block_count; ++b) {
        const Block& block = blocks[b];
        const std::uint64_t bytes = block.bytes;
        file.write(reinterpret_cast<const char*>(&bytes), sizeof bytes);
        if (block.bytes > 0) file.write(static_cast<const char*>(block.data), static_cast<std::streamsize>(block.bytes));
    }
    file << "\n  </AppendedData>\n</VTKFile>\n";
    file.close();
    if (!file) throw Error(path.string() + ": cannot write: " + std::strerror(errno));
}

Piece read_vtp(const std::filesystem::path& path) {
    auto fail = [&](const std::string& what) -> Error { return Error(path.string() + ": " + what); };
    const std::string text = read_whole_file(path);

    const std::size_t appended = text.find("<AppendedData");
    const std::string header = text.substr(0, appended);
    if (header.find("<VTKFile") == std::string::npos || header.find("type=\"PolyData\"") == std::string::npos)
        throw fail("not a VTK XML PolyData file");
    const Attributes file_attributes = parse_attributes(header.substr(header.find("<VTKFile"), header.find('>', header.find("<VTKFile")) - header.find("<VTKFile")));
    if (file_attributes.count("compressor"))
        throw fail("compressed VTP is not supported; save it uncompressed with raw appended data");
    if (file_attributes.count("byte_order") && file_attributes.at("byte_order") != "LittleEndian")
        throw fail("big-endian VTP is not supported");
    const bool wide_header = file_attributes.count("header_type") && file_attributes.at("header_type") == "UInt64";
    if (appended == std::string::npos) throw fail("no appended data; only raw appended VTP files are supported");
    const std::size_t underscore = text.find('_', text.find('>', appended));
    if (underscore == std::string::npos) throw fail("appended data has no '_' marker");
    if (text.substr(appended, text.find('>', appended) - appended).find("encoding=\"raw\"") == std::string::npos)
        throw fail("only raw appended data is supported (not base64)");
    const std::size_t base = underscore + 1;

    const std::size_t piece_tag = header.find("<Piece ");
    if (piece_tag == std::string::npos) throw fail("no Piece element");
    if (header.find("<Piece ", piece_tag + 1) != std::string::npos)
        throw fail("more than one Piece; merge them before reading");
    const Attributes piece_attributes = parse_attributes(header.substr(piece_tag, header.find('>', piece_tag) - piece_tag));
    // Counts and offsets are whole numbers that fit in 64 bits; anything
    // else (a sign, a fraction, digits beyond 2^64) is an error, never a
    // wrapped or truncated value.
    auto parse_count = [&](const std::string& text, const std::string& what) -> std::size_t {
        std::uint64_t value = 0;
        const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (error != std::errc{} || end != text.data() + text.size())
            throw fail(what + " is not a count: \"" + text + "\"");
        return static_cast<std::size_t>(value);
    };
    auto count_of = [&](const char* name) -> std::size_t {
        const auto it = piece_attributes.find(name);
        return it == piece_attributes.end() ? 0 : parse_count(it->second, std::string("attribute ") + name);
    };
    const std::size_t n = count_of("NumberOfPoints"), m = count_of("NumberOfPolys");

    // Locates each appended DataArray by its section and name.
    struct Array {
        std::string type;
        std::size_t offset;
    };
    std::map<std::string, Array> arrays;
    std::string section;
    for (std::size_t at = header.find('<'); at != std::string::npos; at = header.find('<', at + 1)) {
        const std::size_t end = header.find('>', at);
        const std::string tag = header.substr(at, end - at);
        for (const char* s : {"PointData", "Points", "Polys", "Verts", "Lines", "Strips", "CellData"})
            if (tag.rfind(std::string("<") + s, 0) == 0 && (tag.size() == std::strlen(s) + 1 || tag[std::strlen(s) + 1] == ' '))
                section = s;
        if (tag.rfind("<DataArray", 0) != 0) continue;
        const Attributes a = parse_attributes(tag);
        if (!a.count("format") || a.at("format") != "appended")
            throw fail("DataArray in " + section + " is not in appended format");
        const std::string name = section == "Points" ? "Points" : a.count("Name") ? a.at("Name") : "";
        const std::string where = section + "/" + name;
        const std::size_t components =
            a.count("NumberOfComponents") ? parse_count(a.at("NumberOfComponents"), where + " NumberOfComponents") : 1;
        if (components != (section == "Points" ? 3u : 1u))
            throw fail(where + " has " + std::to_string(components) + " components, expected " +
                       (section == "Points" ? "3" : "1"));
        arrays[where] = Array{a.count("type") ? a.at("type") : "",
                              a.count("offset") ? parse_count(a.at("offset"), where + " offset") : 0};
    }
    if (count_of("NumberOfStrips") || count_of("NumberOfLines") || count_of("NumberOfVerts"))
        throw fail("has strips, lines or vertices; only polygons are read");

    // Reads a whole array as doubles (exact for every type VTK writes here
    // except 64-bit integers above 2^53, which keys use: they go through
    // read_u64).
    auto block = [&](const Array& array, std::size_t& bytes) -> const char* {
        // Compared by what is left of the file, so that no offset or size
        // read from it can wrap the sum around.
        const std::size_t header_size = wide_header ? 8 : 4;
        if (array.offset > text.size() - base || header_size > text.size() - base - array.offset)
            throw fail("appended data is shorter than its offsets say");
        const std::size_t at = base + array.offset;
        std::uint64_t size = 0;
        std::memcpy(&size, text.data() + at, header_size);
        if (size > text.size() - at - header_size) throw fail("appended data is shorter than its sizes say");
        bytes = static_cast<std::size_t>(size);
        return text.data() + at + header_size;
    };
    auto values_of = [&](const std::string& where, std::size_t expected) {
        const auto it = arrays.find(where);
        if (it == arrays.end()) throw fail("no " + where + " array");
        std::size_t bytes = 0;
        const char* data = block(it->second, bytes);
        const std::string& type = it->second.type;
        const std::size_t width = type == "Float64" || type == "Int64" || type == "UInt64" ? 8
                                  : type == "Float32" || type == "Int32" || type == "UInt32" ? 4
                                  : type == "Int16" || type == "UInt16" ? 2 : 1;
        // Divided rather than multiplied: `expected` comes from the file.
        if (bytes % width != 0 || bytes / width != expected)
            throw fail(where + " holds " + std::to_string(bytes / width) + " values, expected " + std::to_string(expected));
        std::vector<double> out(expected);
        for (std::size_t i = 0; i < expected; ++i) {
            const char* p = data + i * width;
            auto get = [&](auto v) { std::memcpy(&v, p, sizeof v); return static_cast<double>(v); };
            if (type == "Float32") out[i] = get(float{});
            else if (type == "Float64") out[i] = get(double{});
            else if (type == "Int32") out[i] = get(std::int32_t{});
            else if (type == "UInt32") out[i] = get(std::uint32_t{});
            else if (type == "Int64") out[i] = get(std::int64_t{});
            else if (type == "UInt64") out[i] = get(std::uint64_t{});
            else if (type == "Int16") out[i] = get(std::int16_t{});
            else if (type == "UInt16") out[i] = get(std::uint16_t{});
            else if (type == "Int8") out[i] = get(std::int8_t{});
            else if (type == "UInt8") out[i] = get(std::uint8_t{});
            else throw fail(where + " has unsupported type " + type);
        }
        return out;
    };

    // The counts bound what is allocated: a point takes at least 3 bytes and
    // a polygon at least 4 (its offset and three corners) of the file.
    if (n > text.size() / 3 || m > text.size() / 4) throw fail("NumberOfPoints or NumberOfPolys is more than the file can hold");
    if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
        throw fail("more points than 32-bit vertex indices can hold");

    Piece piece;
    const std::vector<double> points = values_of("Points/Points", 3 * n);
    piece.x.resize(n);
    piece.y.resize(n);
    piece.z.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        piece.x[v] = static_cast<float>(points[3 * v]);
        piece.y[v] = static_cast<float>(points[3 * v + 1]);
        piece.z[v] = static_cast<float>(points[3 * v + 2]);
    }
    piece.key.resize(n);
    // tetiso's arrays, by the names write_vtp gives them.
    const std::string key_path = std::string("PointData/") + kKeyName;
    const std::string flags_path = std::string("PointData/") + kFlagsName;
    const std::string bound_path = std::string("CellData/") + kErrorBoundName;
    if (const auto it = arrays.find(key_path); it != arrays.end()) {
        // Keys are exact 64-bit integers: any other type would round them.
        if (it->second.type != "UInt64")
            throw fail(std::string(kKeyName) + " array is " + it->second.type + ", not UInt64");
        std::size_t bytes = 0;
        const char* data = block(it->second, bytes);
        if (bytes != n * 8) throw fail(std::string(kKeyName) + " array has the wrong length");
        if (bytes > 0) std::memcpy(piece.key.data(), data, bytes); // an empty vector's data() may be null
    } else {
        for (std::size_t v = 0; v < n; ++v) piece.key[v] = v;
    }
    piece.flags.assign(n, 0);
    if (arrays.count(flags_path)) {
        const std::vector<double> flags = values_of(flags_path, n);
        for (std::size_t v = 0; v < n; ++v) {
            if (!whole_below(flags[v], 256)) throw fail(std::string(kFlagsName) + " of vertex " + std::to_string(v) + " is not a byte");
            piece.flags[v] = static_cast<std::uint8_t>(flags[v]);
        }
    }
    const std::vector<double> offsets = values_of("Polys/offsets", m);
    if (m > 0 && !whole_below(offsets.back(), static_cast<double>(text.size())))
        throw fail("Polys/offsets ends at " + std::to_string(offsets.back()) + ", not a corner count the file can hold");
    const std::size_t corners = m == 0 ? 0 : static_cast<std::size_t>(offsets.back());
    const std::vector<double> connectivity = values_of("Polys/connectivity", corners);
    // The checks every reader applies (validate_and_order) see int32
    // indices; here a corner must first be a whole number that fits one.
    for (std::size_t c = 0; c < corners; ++c)
        if (!whole_below(connectivity[c], static_cast<double>(n)))
            throw fail("Polys/connectivity " + std::to_string(c) + " is " + std::to_string(connectivity[c]) +
                       ", not a vertex index below " + std::to_string(n));
    // A polygon's error bound holds for every triangle it is cut into.
    std::vector<double> bounds;
    if (arrays.count(bound_path)) {
        bounds = values_of(bound_path, m);
        for (std::size_t f = 0; f < m; ++f)
            if (!(bounds[f] >= 0 && bounds[f] <= std::numeric_limits<float>::max()))
                throw fail(std::string(kErrorBoundName) + " of polygon " + std::to_string(f) +
                           " is not a finite non-negative float");
    }
    std::size_t start = 0;
    for (std::size_t f = 0; f < m; ++f) {
        if (!whole_below(offsets[f], static_cast<double>(corners + 1)) || offsets[f] < static_cast<double>(start + 3))
            throw fail("polygon " + std::to_string(f) + " has fewer than 3 vertices or bad offsets");
        const auto end = static_cast<std::size_t>(offsets[f]);
        for (std::size_t k = start + 1; k + 1 < end; ++k) {
            piece.triangles.push_back(static_cast<std::int32_t>(connectivity[start]));
            piece.triangles.push_back(static_cast<std::int32_t>(connectivity[k]));
            piece.triangles.push_back(static_cast<std::int32_t>(connectivity[k + 1]));
            if (!bounds.empty()) piece.error.push_back(static_cast<float>(bounds[f]));
        }
        start = end;
    }
    return piece;
}

} // namespace tetiso::detail
