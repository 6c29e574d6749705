// Gmsh .msh files (see io_msh.hpp): a cursor over the file's bytes that
// reads whitespace-separated tokens in ascii files and fixed-size values in
// binary ones, section by section. Nothing is sized from a count in the
// file: values are appended as they are read, so a count larger than the
// file ends in "truncated", never in a huge allocation.
#include "tetiso/io_msh.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "io_formats.hpp"
#include "mapped_file.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

constexpr int kGmshTetrahedron = 4;

struct ElementType {
    int nodes;
    int dimension;
    const char* name;
};

// Gmsh's element types, by number (gmsh/src/common/GmshDefines.h).
const ElementType* element_type(int type) {
    static const std::pair<int, ElementType> types[] = {
        {1, {2, 1, "line"}},           {2, {3, 2, "triangle"}},         {3, {4, 2, "quadrangle"}},
        {4, {4, 3, "tetrahedron"}},    {5, {8, 3, "hexahedron"}},       {6, {6, 3, "prism"}},
        {7, {5, 3, "pyramid"}},        {8, {3, 1, "second-order line"}}, {9, {6, 2, "second-order triangle"}},
        {10, {9, 2, "second-order quadrangle"}}, {11, {10, 3, "second-order tetrahedron"}},
        {12, {27, 3, "second-order hexahedron"}}, {13, {18, 3, "second-order prism"}},
        {14, {14, 3, "second-order pyramid"}}, {15, {1, 0, "point"}}, {16, {8, 2, "serendipity quadrangle"}},
        {17, {20, 3, "serendipity hexahedron"}}, {18, {15, 3, "serendipity prism"}},
        {19, {13, 3, "serendipity pyramid"}}, {20, {9, 2, "third-order incomplete triangle"}},
        {21, {10, 2, "third-order triangle"}}, {26, {4, 1, "third-order line"}},
        {29, {20, 3, "third-order tetrahedron"}}, {30, {35, 3, "fourth-order tetrahedron"}},
        {31, {56, 3, "fifth-order tetrahedron"}}, {92, {64, 3, "third-order hexahedron"}},
        {93, {125, 3, "fourth-order hexahedron"}}};
    for (const auto& [number, info] : types)
        if (number == type) return &info;
    return nullptr;
}

class MshParser {
public:
    MshParser(std::string_view bytes, std::string name) : b_(bytes), name_(std::move(name)) {}
    MeshArrays parse(const std::string& view);

private:
    [[noreturn]] void fail(const std::string& what) const { throw Error(name_ + ": " + what); }

    void skip_space() {
        while (at_ < b_.size() && std::isspace(static_cast<unsigned char>(b_[at_]))) ++at_;
    }
    std::string_view token(const char* what) {
        skip_space();
        const std::size_t start = at_;
        while (at_ < b_.size() && !std::isspace(static_cast<unsigned char>(b_[at_]))) ++at_;
        if (at_ == start) fail(std::string("truncated: ") + what + " expected");
        return b_.substr(start, at_ - start);
    }
    template <class T>
    T text_number(const char* what) {
        const std::string_view t = token(what);
        T value{};
        const auto [end, ec] = std::from_chars(detail::past_plus(t.data(), t.data() + t.size()), t.data() + t.size(), value);
        if (ec != std::errc() || end != t.data() + t.size())
            fail(std::string(what) + " '" + std::string(t.substr(0, 40)) + "' is not a number of the expected kind");
        return value;
    }
    template <class T>
    T raw(const char* what) {
        if (b_.size() - at_ < sizeof(T)) fail(std::string("truncated in ") + what);
        T value;
        std::memcpy(&value, b_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    // An integer that is a size_t in binary files (the header's data size).
    std::uint64_t size_value(const char* what) {
        if (!binary_) return text_number<std::uint64_t>(what);
        return size_bytes_ == 8 ? raw<std::uint64_t>(what) : raw<std::uint32_t>(what);
    }
    std::int64_t int_value(const char* what) { return binary_ ? raw<std::int32_t>(what) : text_number<std::int64_t>(what); }
    double real_value(const char* what) {
        const double v = binary_ ? raw<double>(what) : text_number<double>(what);
        return v;
    }
    void expect_end(std::string_view section) {
        // Binary data ends with a newline before the $End line.
        const std::string_view t = token("the section's end");
        if (t.substr(0, 4) != "$End" || t.substr(4) != section) {
            std::string what = "$";
            what.append(section).append(" does not end where its counts say ('").append(t.substr(0, 40)).append("')");
            fail(what);
        }
    }

    // Binary data starts right after the line that precedes it.
    void skip_line_end();
    void read_format();
    void read_nodes();
    void read_elements();
    void read_node_data(const std::string& view);
    void add_node(std::uint64_t tag, double x, double y, double z);
    void add_element(int type, const std::uint64_t* nodes, std::uint64_t tag);

    std::string_view b_;
    std::string name_;
    std::size_t at_ = 0;
    bool binary_ = false;
    int version_ = 0; // 22 or 41
    std::size_t size_bytes_ = 8;
    std::vector<std::uint64_t> tags_;
    std::vector<double> xyz_;
    std::vector<std::uint64_t> tet_tags_;
    std::vector<std::uint64_t> tet_elements_; // each tetrahedron's element tag
    std::vector<std::uint64_t> other_count_ = std::vector<std::uint64_t>(128, 0);
    std::vector<std::pair<std::uint64_t, double>> values_;
    bool have_view_ = false;
    std::int64_t view_step_ = 0; // the time step of the view read
    std::vector<std::string> views_;
};

void MshParser::read_format() {
    const std::string_view version = token("the format version");
    if (version == "4.1") version_ = 41;
    else if (version == "2.2") version_ = 22;
    else fail("format version " + std::string(version.substr(0, 20)) + "; tetiso reads 4.1 and 2.2");
    const int file_type = text_number<int>("the file type");
    const int data_size = text_number<int>("the data size");
    if (file_type != 0 && file_type != 1) fail("file type " + std::to_string(file_type) + " is neither ascii (0) nor binary (1)");
    if (data_size != 4 && data_size != 8) fail("data size " + std::to_string(data_size) + " is neither 4 nor 8");
    binary_ = file_type == 1;
    size_bytes_ = static_cast<std::size_t>(data_size);
    if (binary_) {
        if (at_ < b_.size() && b_[at_] == '\r') ++at_;
        if (at_ >= b_.size() || b_[at_] != '\n') fail("truncated after the format line");
        ++at_;
        if (raw<std::int32_t>("the byte order mark") != 1) fail("written with another byte order; tetiso reads little-endian files");
    }
    expect_end("MeshFormat");
}

void MshParser::add_node(std::uint64_t tag, double x, double y, double z) {
    for (const double c : {x, y, z})
        if (!(std::abs(c) <= std::numeric_limits<float>::max()))
            fail("node " + std::to_string(tag) + " has a coordinate that is not a finite number in float range");
    if (tags_.size() >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) fail("more nodes than one domain can hold");
    tags_.push_back(tag);
    xyz_.insert(xyz_.end(), {x, y, z});
}

void MshParser::add_element(int type, const std::uint64_t* nodes, std::uint64_t tag) {
    const ElementType* info = element_type(type);
    if (!info) fail("element " + std::to_string(tag) + " has unknown type " + std::to_string(type));
    if (type == kGmshTetrahedron) {
        if (tet_tags_.size() / 4 >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) fail("more tetrahedra than one domain can hold");
        tet_tags_.insert(tet_tags_.end(), nodes, nodes + 4);
        tet_elements_.push_back(tag);
    } else if (info->dimension == 3) {
        ++other_count_[static_cast<std::size_t>(type)];
    }
}

void MshParser::skip_line_end() {
    if (at_ < b_.size() && b_[at_] == '\r') ++at_;
    if (at_ < b_.size() && b_[at_] == '\n') ++at_;
}

void MshParser::read_nodes() {
    if (version_ == 41) {
        if (binary_) skip_line_end();
        const std::uint64_t blocks = size_value("the node block count");
        const std::uint64_t total = size_value("the node count");
        size_value("the smallest node tag");
        size_value("the largest node tag");
        const std::size_t before = tags_.size();
        for (std::uint64_t k = 0; k < blocks; ++k) {
            const std::int64_t dimension = int_value("an entity dimension");
            int_value("an entity tag");
            const std::int64_t parametric = int_value("the parametric flag");
            const std::uint64_t count = size_value("a block's node count");
            if (dimension < 0 || dimension > 3) fail("node block " + std::to_string(k) + " has dimension " + std::to_string(dimension));
            if (count > b_.size() - at_) fail("node block " + std::to_string(k) + " promises more nodes than the file holds");
            std::vector<std::uint64_t> block_tags;
            for (std::uint64_t i = 0; i < count; ++i) block_tags.push_back(size_value("a node tag"));
            const int extra = parametric ? static_cast<int>(dimension) : 0;
            for (std::uint64_t i = 0; i < count; ++i) {
                const double x = real_value("a coordinate"), y = real_value("a coordinate"), z = real_value("a coordinate");
                for (int e = 0; e < extra; ++e) real_value("a parametric coordinate");
                add_node(block_tags[i], x, y, z);
            }
        }
        if (tags_.size() - before != total)
            fail("$Nodes promises " + std::to_string(total) + " nodes, its blocks hold " + std::to_string(tags_.size() - before));
    } else {
        const std::uint64_t count = text_number<std::uint64_t>("the node count");
        if (binary_) skip_line_end();
        for (std::uint64_t i = 0; i < count; ++i) {
            const std::int64_t tag = int_value("a node tag");
            if (tag < 0) fail("negative node tag " + std::to_string(tag));
            const double x = real_value("a coordinate"), y = real_value("a coordinate"), z = real_value("a coordinate");
            add_node(static_cast<std::uint64_t>(tag), x, y, z);
        }
    }
    expect_end("Nodes");
}

void MshParser::read_elements() {
    std::uint64_t nodes[128];
    const auto read_nodes_of = [&](int type, std::uint64_t tag) {
        const ElementType* info = element_type(type);
        if (!info) fail("element " + std::to_string(tag) + " has unknown type " + std::to_string(type));
        for (int k = 0; k < info->nodes; ++k) {
            const std::int64_t v = version_ == 41 ? static_cast<std::int64_t>(size_value("a node tag")) : int_value("a node tag");
            if (v < 0) fail("element " + std::to_string(tag) + " refers to negative node tag " + std::to_string(v));
            nodes[k] = static_cast<std::uint64_t>(v);
        }
        add_element(type, nodes, tag);
    };
    if (version_ == 41) {
        if (binary_) skip_line_end();
        const std::uint64_t blocks = size_value("the element block count");
        const std::uint64_t total = size_value("the element count");
        size_value("the smallest element tag");
        size_value("the largest element tag");
        std::uint64_t seen = 0;
        for (std::uint64_t k = 0; k < blocks; ++k) {
            int_value("an entity dimension");
            int_value("an entity tag");
            const std::int64_t type = int_value("an element type");
            const std::uint64_t count = size_value("a block's element count");
            if (type < 0 || type > 127 || !element_type(static_cast<int>(type)))
                fail("element block " + std::to_string(k) + " has unknown element type " + std::to_string(type));
            if (count > b_.size() - at_) fail("element block " + std::to_string(k) + " promises more elements than the file holds");
            for (std::uint64_t i = 0; i < count; ++i) read_nodes_of(static_cast<int>(type), size_value("an element tag"));
            seen += count;
        }
        if (seen != total) fail("$Elements promises " + std::to_string(total) + " elements, its blocks hold " + std::to_string(seen));
    } else if (!binary_) {
        const std::uint64_t count = text_number<std::uint64_t>("the element count");
        for (std::uint64_t i = 0; i < count; ++i) {
            const auto tag = text_number<std::uint64_t>("an element tag");
            const int type = text_number<int>("an element type");
            const int tag_count = text_number<int>("a tag count");
            if (tag_count < 0 || tag_count > 64) fail("element " + std::to_string(tag) + " has " + std::to_string(tag_count) + " tags");
            for (int t = 0; t < tag_count; ++t) text_number<std::int64_t>("an element tag");
            read_nodes_of(type, tag);
        }
    } else {
        const std::uint64_t count = text_number<std::uint64_t>("the element count");
        skip_line_end();
        std::uint64_t seen = 0;
        while (seen < count) {
            const std::int32_t type = raw<std::int32_t>("an element header");
            const std::int32_t of_type = raw<std::int32_t>("an element header");
            const std::int32_t tag_count = raw<std::int32_t>("an element header");
            if (of_type <= 0 || static_cast<std::uint64_t>(of_type) > count - seen || tag_count < 0 || tag_count > 64)
                fail("element header " + std::to_string(type) + " " + std::to_string(of_type) + " " + std::to_string(tag_count) + " is malformed");
            for (std::int32_t i = 0; i < of_type; ++i) {
                const std::int32_t tag = raw<std::int32_t>("an element");
                for (std::int32_t t = 0; t < tag_count; ++t) raw<std::int32_t>("an element's tags");
                read_nodes_of(type, static_cast<std::uint64_t>(tag < 0 ? 0 : tag));
            }
            seen += static_cast<std::uint64_t>(of_type);
        }
    }
    expect_end("Elements");
}

void MshParser::read_node_data(const std::string& view) {
    const int strings = text_number<int>("the string tag count");
    if (strings < 0 || strings > 64) fail("$NodeData has " + std::to_string(strings) + " string tags");
    std::string name;
    for (int s = 0; s < strings; ++s) {
        skip_space();
        if (at_ >= b_.size() || b_[at_] != '"') fail("$NodeData string tag is not quoted");
        const std::size_t close = b_.find('"', at_ + 1);
        if (close == std::string_view::npos) fail("$NodeData string tag is not closed");
        if (s == 0) name.assign(b_.substr(at_ + 1, close - at_ - 1));
        at_ = close + 1;
    }
    views_.push_back(name);
    const int reals = text_number<int>("the real tag count");
    if (reals < 0 || reals > 64) fail("$NodeData has " + std::to_string(reals) + " real tags");
    for (int r = 0; r < reals; ++r) text_number<double>("a real tag");
    const int integers = text_number<int>("the integer tag count");
    if (integers < 3 || integers > 64) fail("$NodeData has " + std::to_string(integers) + " integer tags, fewer than 3");
    std::int64_t tagv[3] = {0, 0, 0};
    for (int i = 0; i < integers; ++i) {
        const auto v = text_number<std::int64_t>("an integer tag");
        if (i < 3) tagv[i] = v;
    }
    const std::int64_t components = tagv[1], entries = tagv[2];
    if (components < 1 || components > 9) fail("$NodeData '" + name + "' has " + std::to_string(components) + " components");
    if (entries < 0) fail("$NodeData '" + name + "' has a negative entry count");
    const bool wanted = name == view;
    if (wanted && components != 1)
        fail("$NodeData '" + name + "' has " + std::to_string(components) + " components; the field must be a scalar");
    // A view is a time series when its $NodeData differ in time step (the
    // first integer tag): the latest step is read. Two of one step would
    // each claim to be the field.
    const std::int64_t step = tagv[0];
    if (wanted && have_view_ && step == view_step_)
        fail("$NodeData '" + name + "' appears twice for time step " + std::to_string(step));
    const bool taken = wanted && (!have_view_ || step > view_step_);
    if (taken) values_.clear(), have_view_ = true, view_step_ = step;
    if (binary_) skip_line_end();
    for (std::int64_t e = 0; e < entries; ++e) {
        const std::int64_t tag = binary_ ? raw<std::int32_t>("a value's node tag") : text_number<std::int64_t>("a value's node tag");
        double value = 0;
        for (std::int64_t c = 0; c < components; ++c) value = real_value("a value");
        if (!taken) continue;
        if (tag < 0) fail("$NodeData '" + name + "' gives a value to negative node tag " + std::to_string(tag));
        if (!(std::abs(value) <= std::numeric_limits<float>::max()))
            fail("$NodeData '" + name + "': the value of node " + std::to_string(tag) + " is not a finite number in float range");
        values_.push_back({static_cast<std::uint64_t>(tag), value});
    }
    expect_end("NodeData");
}

MeshArrays MshParser::parse(const std::string& view) {
    bool have_format = false, have_nodes = false, have_elements = false;
    while (true) {
        skip_space();
        if (at_ >= b_.size()) break;
        const std::string_view section = token("a section");
        if (section.size() < 2 || section[0] != '$') fail("'" + std::string(section.substr(0, 40)) + "' where a section ($Name) was expected");
        const std::string_view name = section.substr(1);
        if (!have_format && name != "MeshFormat") fail("does not start with $MeshFormat: not a Gmsh mesh");
        if (name == "MeshFormat") {
            if (have_format) fail("two $MeshFormat sections");
            read_format();
            have_format = true;
        } else if (name == "Nodes") {
            if (have_nodes) fail("two $Nodes sections");
            read_nodes();
            have_nodes = true;
        } else if (name == "Elements") {
            if (have_elements) fail("two $Elements sections");
            read_elements();
            have_elements = true;
        } else if (name == "NodeData") {
            read_node_data(view);
        } else {
            const std::string end = "$End" + std::string(name);
            const std::size_t found = b_.find(end, at_);
            if (found == std::string_view::npos) fail("section $" + std::string(name.substr(0, 40)) + " has no " + end.substr(0, 44));
            at_ = found + end.size();
        }
    }
    if (!have_format) fail("empty: not a Gmsh mesh");
    if (!have_nodes || !have_elements) fail("no $Nodes or no $Elements section");
    for (int type = 0; type < 128; ++type)
        if (other_count_[static_cast<std::size_t>(type)])
            fail(std::to_string(other_count_[static_cast<std::size_t>(type)]) + " volume elements of type " + std::to_string(type) +
                 " (" + element_type(type)->name + "); tetiso reads linear tetrahedra (type 4) only");
    if (!view.empty() && !have_view_) {
        std::string names;
        for (const std::string& v : views_) {
            if (!names.empty()) names += ", ";
            names.append(1, '\'').append(v).append(1, '\'');
        }
        fail("no $NodeData view '" + view + "'" + (names.empty() ? " (it has none)" : " (it has: " + names + ")"));
    }

    // Nodes in tag order; only those that tetrahedra use are kept.
    std::vector<std::int32_t> order(tags_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::int32_t>(i);
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) { return tags_[static_cast<std::size_t>(a)] < tags_[static_cast<std::size_t>(b)]; });
    std::vector<std::uint64_t> sorted(tags_.size());
    for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = tags_[static_cast<std::size_t>(order[i])];
    for (std::size_t i = 1; i < sorted.size(); ++i)
        if (sorted[i] == sorted[i - 1]) fail("node tag " + std::to_string(sorted[i]) + " is given twice");
    const auto index_of = [&](std::uint64_t tag) -> std::int64_t {
        const auto it = std::lower_bound(sorted.begin(), sorted.end(), tag);
        return it == sorted.end() || *it != tag ? -1 : it - sorted.begin();
    };
    std::vector<std::int32_t> kept(sorted.size(), -1);
    std::vector<std::int64_t> corner(tet_tags_.size());
    for (std::size_t i = 0; i < tet_tags_.size(); ++i) {
        corner[i] = index_of(tet_tags_[i]);
        if (corner[i] < 0) fail("tetrahedron " + std::to_string(i / 4) + " refers to node tag " + std::to_string(tet_tags_[i]) + ", which does not exist");
        kept[static_cast<std::size_t>(corner[i])] = 0;
        for (std::size_t j = i / 4 * 4; j < i; ++j)
            if (corner[j] == corner[i]) fail("tetrahedron " + std::to_string(i / 4) + " repeats node tag " + std::to_string(tet_tags_[i]));
    }
    MeshArrays out;
    for (std::size_t i = 0; i < sorted.size(); ++i) {
        if (kept[i] < 0) continue;
        kept[i] = static_cast<std::int32_t>(out.x.size());
        const auto at = 3 * static_cast<std::size_t>(order[i]);
        out.x.push_back(xyz_[at]), out.y.push_back(xyz_[at + 1]), out.z.push_back(xyz_[at + 2]);
    }
    out.tets.resize(corner.size());
    for (std::size_t i = 0; i < corner.size(); ++i) out.tets[i] = kept[static_cast<std::size_t>(corner[i])];
    out.tet_numbers = std::move(tet_elements_);
    out.number_word = "element";
    if (!view.empty()) {
        const double unset = std::numeric_limits<double>::quiet_NaN();
        out.f.assign(out.x.size(), unset);
        for (const auto& [tag, value] : values_) {
            const std::int64_t i = index_of(tag);
            if (i < 0) fail("$NodeData '" + view + "' gives a value to node tag " + std::to_string(tag) + ", which does not exist");
            if (kept[static_cast<std::size_t>(i)] >= 0) out.f[static_cast<std::size_t>(kept[static_cast<std::size_t>(i)])] = value;
        }
        for (std::size_t v = 0; v < out.f.size(); ++v)
            if (std::isnan(out.f[v]))
                fail("$NodeData '" + view + "' gives no value to node tag " + std::to_string(sorted[static_cast<std::size_t>(std::find(kept.begin(), kept.end(), static_cast<std::int32_t>(v)) - kept.begin())]));
    }
    return out;
}

} // namespace

MeshArrays parse_msh(std::string_view bytes, const std::string& name, const std::string& view) {
    return MshParser(bytes, name).parse(view);
}

MeshArrays read_msh(const std::filesystem::path& path, const std::string& view) {
    // Mapped, as read_vtu's pieces are: the parser only scans the bytes, and
    // a copy of a large binary mesh costs as much as parsing it.
    const detail::MappedFile file(path);
    return parse_msh(file.bytes(), path.string(), view);
}

} // namespace tetiso
