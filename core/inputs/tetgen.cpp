// TetGen's .node/.ele files as one Domain (see tetgen.hpp). Lines are read
// whole and split on blanks; '#' starts a comment anywhere. Every count in a
// header is checked against the lines that follow before it sizes anything.
#include "tetiso/tetgen.hpp"

#include "tetiso/mesh_file.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "table_file.hpp"
#include "tet_faces.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

using detail::TableFile;

// Guards against a header that promises far more than any file could hold,
// before anything is allocated from it.
void check_count(const TableFile& file, std::int64_t count, const char* what) {
    if (count < 0) file.fail(std::string("negative number of ") + what);
    if (count > std::numeric_limits<std::int32_t>::max()) file.fail(std::string("more ") + what + " than one domain can hold");
}

} // namespace

Domain read_tetgen(const TetgenSource& source) {
    if (!source.attribute && !source.field) throw Error("read_tetgen: neither a field nor an attribute was given");
    Domain domain;
    domain.id = 0;

    // Nodes: "<count> <dimension> <attributes> <markers>", then
    // "<number> <x> <y> <z> [attributes...] [marker]".
    TableFile node_file(std::filesystem::path(source.base.string() + ".node"));
    if (!node_file.next()) node_file.fail_file("no header line");
    const auto nodes = node_file.get<std::int64_t>(0, "node count");
    check_count(node_file, nodes, "nodes");
    if (node_file.get<int>(1, "dimension") != 3) node_file.fail("dimension is not 3");
    const int attributes = node_file.size() > 2 ? node_file.get<int>(2, "attribute count") : 0;
    if (attributes < 0) node_file.fail("negative attribute count");
    if (source.attribute && (*source.attribute < 0 || *source.attribute >= attributes))
        node_file.fail("the field is attribute " + std::to_string(source.attribute.value_or(0)) +
                       " but the nodes have " + std::to_string(attributes) + " attribute(s)");
    std::vector<double> px, py, pz;
    std::int64_t first_number = 0;
    for (std::int64_t i = 0; i < nodes; ++i) {
        if (!node_file.next()) node_file.fail_file("the header promises " + std::to_string(nodes) + " nodes, the file has " + std::to_string(i));
        const auto number = node_file.get<std::int64_t>(0, "node number");
        if (i == 0) {
            if (number != 0 && number != 1) node_file.fail("node numbers start at neither 0 nor 1");
            first_number = number;
        } else if (number != first_number + i) {
            node_file.fail("node number " + std::to_string(number) + " where " + std::to_string(first_number + i) +
                           " was expected");
        }
        const double x = node_file.get<double>(1, "x"), y = node_file.get<double>(2, "y"),
                     z = node_file.get<double>(3, "z");
        // Stored as float: a finite double beyond float's range would become
        // an infinity there and spoil every crossing near it.
        const auto representable = [](double value) { return std::abs(value) <= std::numeric_limits<float>::max(); };
        if (!representable(x) || !representable(y) || !representable(z))
            node_file.fail("a coordinate is not a finite number in float range");
        px.push_back(x);
        py.push_back(y);
        pz.push_back(z);
        if (source.attribute) {
            const double value = node_file.get<double>(4 + static_cast<std::size_t>(*source.attribute), "attribute");
            if (!representable(value)) node_file.fail("the field value is not a finite number in float range");
            domain.f.push_back(static_cast<float>(value));
        }
    }
    const auto n = static_cast<std::size_t>(nodes);
    domain.x.assign(px.begin(), px.end());
    domain.y.assign(py.begin(), py.end());
    domain.z.assign(pz.begin(), pz.end());
    if (!source.attribute) {
        domain.f.resize(n);
        source.field->evaluate(px.data(), py.data(), pz.data(), n, domain.f.data());
    }
    domain.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) domain.gid[i] = static_cast<GlobalId>(i);
    domain.interface.assign(n, 0);

    // Tetrahedra: "<count> <nodes per tet> <region attribute>", then
    // "<number> <n0> <n1> <n2> <n3> [...]".
    TableFile ele_file(std::filesystem::path(source.base.string() + ".ele"));
    if (!ele_file.next()) ele_file.fail_file("no header line");
    const auto tets = ele_file.get<std::int64_t>(0, "tetrahedron count");
    check_count(ele_file, tets, "tetrahedra");
    const int corners = ele_file.get<int>(1, "nodes per tetrahedron");
    if (corners != 4 && corners != 10) ele_file.fail("nodes per tetrahedron is " + std::to_string(corners) + ", not 4 or 10");
    std::vector<std::uint8_t> listed_negative;
    for (std::int64_t t = 0; t < tets; ++t) {
        if (!ele_file.next())
            ele_file.fail_file("the header promises " + std::to_string(tets) + " tetrahedra, the file has " + std::to_string(t));
        std::int32_t v[4];
        for (int k = 0; k < 4; ++k) {
            const auto number = ele_file.get<std::int64_t>(1 + static_cast<std::size_t>(k), "node number");
            if (number < first_number || number >= first_number + nodes)
                ele_file.fail("tetrahedron refers to node " + std::to_string(number) + ", which does not exist");
            v[k] = static_cast<std::int32_t>(number - first_number);
            for (int j = 0; j < k; ++j)
                if (v[j] == v[k]) ele_file.fail("tetrahedron repeats node " + std::to_string(number));
        }
        // Extraction orients triangles from a positively oriented reference
        // tetrahedron; TetGen's own order is not that, so fix it here.
        const double volume = signed_volume6(domain, v[0], v[1], v[2], v[3]);
        if (volume == 0) ele_file.fail("tetrahedron " + std::to_string(t) + " has zero volume (its corners, as stored in float, are coplanar)");
        if (volume < 0) std::swap(v[2], v[3]);
        listed_negative.push_back(volume < 0);
        domain.tets.insert(domain.tets.end(), v, v + 4);
    }
    // Tetrahedra that overlap across a face (check_tetrahedra in mesh_file.hpp).
    const detail::FaceClash clash =
        detail::face_pass(domain.tets, n, [](std::int32_t, std::int32_t, std::int32_t, std::size_t) {});
    detail::refuse_clash(clash, listed_negative, source.base.string() + ".ele", {});
    return domain;
}

} // namespace tetiso
