// VTK XML unstructured grids (see io_vtu.hpp). The file is split in two
// before parsing: the XML (parsed by pugixml) and, where the file has one,
// the appended block after `<AppendedData ...>_`, which in raw encoding is
// arbitrary bytes that no XML parser accepts. Every DataArray is then read
// by vtu_arrays.cpp, which the file's header type, compressor and appended
// block tell how its bytes are encoded, for the count the piece requires.
#include "tetiso/io_vtu.hpp"

#include <algorithm>
#include <optional>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

#include <pugixml.hpp>

#include "mapped_file.hpp"
#include "vtu_arrays.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

constexpr std::uint8_t kVtkTetra = 10;
// DOLFINx writes its cells as Lagrange cells; one of degree 1 (4 points) is
// a linear tetrahedron.
constexpr std::uint8_t kVtkLagrangeTetra = 71;
// vtkDataSetAttributes::DUPLICATECELL: the cell is a copy of another piece's.
constexpr std::uint8_t kDuplicateCell = 1;


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
    pugi::xml_node find_array(const pugi::xml_node& parent, const char* name) const {
        for (const pugi::xml_node a : parent.children("DataArray"))
            if (std::string_view(a.attribute("Name").as_string()) == name) return a;
        return {};
    }
    std::uint64_t count_attribute(const pugi::xml_node& node, const char* attribute) const;

    std::string_view bytes_;
    std::string name_;
    std::string xml_; // the XML part, closed where the appended block was cut off
    vtu::Encoding encoding_;
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
        encoding_.appended_base64 = true;
    else if (encoding != "raw")
        fail("appended data encoding '" + std::string(encoding) + "' is neither raw nor base64");
    const std::size_t underscore = bytes_.find('_', close);
    if (underscore == std::string_view::npos) fail("the appended data has no '_' marker");
    for (std::size_t i = close + 1; i < underscore; ++i)
        if (!std::isspace(static_cast<unsigned char>(bytes_[i]))) fail("text before the appended data's '_' marker");
    encoding_.appended = bytes_.substr(underscore + 1);
    // The XML before the block, closed again: the root is all that is open.
    xml_.assign(bytes_.substr(0, tag));
    xml_ += "</VTKFile>";
}



std::uint64_t VtuParser::count_attribute(const pugi::xml_node& node, const char* attribute) const {
    const std::string_view text = node.attribute(attribute).as_string();
    std::uint64_t value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
        fail(std::string(node.name()) + "'s " + attribute + " is missing or not a whole number");
    return value;
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
    if (header_type == "UInt64") encoding_.header_bytes = 8;
    else if (header_type != "UInt32") fail("header type '" + std::string(header_type) + "' is neither UInt32 nor UInt64");
    const std::string_view compressor = root.attribute("compressor").as_string();
    if (compressor == "vtkZLibDataCompressor") encoding_.compressed = true;
    else if (!compressor.empty()) fail("compressor " + std::string(compressor) + ": only vtkZLibDataCompressor is read");
    const vtu::ArrayReader arrays(name_, encoding_);

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
        const auto xyz = arrays.read<double>(point_array, 3 * points, "the points");
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
    const auto offsets = cells ? arrays.read<std::int64_t>(find_array(cell_node, "offsets"), cells, "the cell offsets")
                               : std::vector<std::int64_t>{};
    const auto types = cells ? arrays.read<std::uint8_t>(find_array(cell_node, "types"), cells, "the cell types")
                             : std::vector<std::uint8_t>{};
    const std::int64_t corner_count = cells ? offsets.back() : 0;
    if (corner_count < 0 || static_cast<std::uint64_t>(corner_count) > 1000 * cells)
        fail("the last cell offset " + std::to_string(corner_count) + " is out of range");
    const pugi::xml_node connectivity_node = find_array(cell_node, "connectivity");
    if (cells > 0 && !connectivity_node) fail("no connectivity array");
    // Point indices fit 32 bits (the point count does), whatever the type.
    auto connectivity = cells ? arrays.read<std::int32_t>(connectivity_node, static_cast<std::uint64_t>(corner_count), "the connectivity")
                              : std::vector<std::int32_t>{};
    std::vector<std::uint8_t> ghost;
    for (const pugi::xml_node a : piece.child("CellData").children("DataArray"))
        if (std::string_view(a.attribute("Name").as_string()) == "vtkGhostType")
            ghost = arrays.read<std::uint8_t>(a, cells, "cell array vtkGhostType");

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
            out.tet_numbers.push_back(c);
        } else if (!lower_dimensional(type)) {
            ++other[static_cast<std::size_t>(type)];
        } else if (fixed_corner_count(type) != 0 && corners != fixed_corner_count(type)) {
            fail("cell " + std::to_string(c) + " is a " + cell_type_name(type) + " with " + std::to_string(corners) +
                 " corners (type " + std::to_string(type) + " has " + std::to_string(fixed_corner_count(type)) + ")");
        }
        previous = end;
    }
    // Cell indices name tetrahedra in messages only where they differ.
    bool renumbered = false;
    for (std::size_t t = 0; t < out.tet_numbers.size() && !renumbered; ++t)
        renumbered = out.tet_numbers[t] != t;
    if (!renumbered) std::vector<std::uint64_t>().swap(out.tet_numbers);
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
        out.f = arrays.read<double>(a, points, "point array '" + request.array + "'");
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
        out.ids = arrays.read<GlobalId>(ids_array, points, "node id array '" + ids_name + "'");
        for (std::size_t i = 0; i < points; ++i)
            if (out.ids[i] < 0 || out.ids[i] > kMaxGlobalId)
                fail("node id array '" + ids_name + "': id " + std::to_string(out.ids[i]) + " of point " +
                     std::to_string(i) + " is outside [0, 2^32)");
    } else if (!request.node_ids.empty() || request.require_node_ids) {
        std::string names;
        for (const pugi::xml_node b : point_data.children("DataArray")) {
            const auto s = vtu::scalar_of(b.attribute("type").as_string());
            if (s && vtu::is_integer(*s) && b.attribute("NumberOfComponents").as_int(1) == 1)
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
