// Solver meshes (core/src/io_vtu.cpp, io_msh.cpp, pvtu.cpp, mesh_file.cpp):
// one mesh written in every VTK XML encoding and every Gmsh format reads to
// the same domain bit for bit; a .pvtu's pieces, with ghost layers, in other
// local orders and with shared points one ulp apart, seam into the surface
// of the whole mesh bit for bit, by node ids alone; and a table of damaged
// files each ends in one tetiso::Error naming the file and what is wrong.
// The fixtures are meshes/solver/*, written by meshes/solver/make_fixtures.py.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <thread>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "thread_ranks.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/io_msh.hpp"
#include "tetiso/io_vtu.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"
#include "tetiso/pvtu.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso {
namespace {

using test::read_bytes;
using test::same_bits;
using test::same_surface;
using test::error_of;

const std::filesystem::path kSolver = std::filesystem::path(TETISO_MESHES_DIR) / "solver";
constexpr float kLevel = 1.5f; // the point array `distance` at 1.5: a sphere

const char* const kVtuEncodings[] = {"ascii",      "binary",  "binary-zlib", "binary-zlib-h64",
                                     "raw",        "raw-h32", "raw-zlib",    "raw-zlib-h64",
                                     "base64",     "base64-zlib-h64"};
const char* const kMshFormats[] = {"4.1", "4.1-binary", "2.2", "2.2-binary"};

Domain read_cube(const std::filesystem::path& path) {
    MeshSource source;
    source.path = path;
    source.array = "distance";
    return read_mesh(source);
}

bool same_domain(const Domain& a, const Domain& b) {
    return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z) && same_bits(a.f, b.f) &&
           a.gid == b.gid && a.tets == b.tets;
}

void expect_sphere(const Piece& surface) {
    const TopologyReport report = check_topology(surface);
    EXPECT_TRUE(report.closed);
    EXPECT_TRUE(report.manifold);
    EXPECT_EQ(report.components, 1);
    EXPECT_EQ(report.euler, 2);
    EXPECT_EQ(report.degenerate_triangles, 0);
    EXPECT_EQ(report.misoriented_edges, 0);
}

TEST(SolverMeshes, EveryEncodingReadsToTheSameDomain) {
    const Domain reference = read_cube(kSolver / "cube-ascii.vtu");
    ASSERT_EQ(reference.node_count(), 343u);
    ASSERT_EQ(reference.tet_count(), 1296u);
    for (std::size_t t = 0; t < reference.tet_count(); ++t) {
        const std::int32_t* v = reference.tets.data() + 4 * t;
        EXPECT_FALSE(negatively_oriented(reference, v[0], v[1], v[2], v[3])) << "tetrahedron " << t;
    }
    for (const char* encoding : kVtuEncodings) {
        SCOPED_TRACE(encoding);
        EXPECT_TRUE(same_domain(reference, read_cube(kSolver / (std::string("cube-") + encoding + ".vtu"))));
    }
    for (const char* format : kMshFormats) {
        SCOPED_TRACE(format);
        EXPECT_TRUE(same_domain(reference, read_cube(kSolver / (std::string("cube-") + format + ".msh"))));
    }
    expect_sphere(extract(reference, kLevel));
}

TEST(SolverMeshes, GmshBoundaryElementsAreNoVolume) {
    // A boundary triangle, a line and a point (Gmsh writes physical groups
    // of those) are skipped; the volume is the same.
    const std::string text = read_bytes(kSolver / "cube-2.2.msh");
    const std::string from = "$Elements\n1296\n";
    ASSERT_NE(text.find(from), std::string::npos);
    std::string with_boundary = text;
    with_boundary.replace(text.find(from), from.size(),
                          "$Elements\n1299\n9001 2 2 0 1 1 2 3\n9002 1 2 0 1 1 2\n9003 15 2 0 1 1\n");
    const Domain reference = read_cube(kSolver / "cube-2.2.msh");
    EXPECT_TRUE(same_domain(reference, domain_from_arrays(parse_msh(with_boundary, "boundary.msh", "distance"), nullptr)));
}

TEST(SolverMeshes, TetgenIsNamedByItsBaseOrEitherFile) {
    const std::unique_ptr<Field> field = make_field("sphere");
    MeshSource source;
    source.field = field.get();
    source.path = std::filesystem::path(TETISO_MESHES_DIR) / "cube.1";
    const Domain base = read_mesh(source);
    EXPECT_EQ(base.node_count(), 3711u);
    for (const char* extension : {".node", ".ele"}) {
        source.path = std::filesystem::path(TETISO_MESHES_DIR) / (std::string("cube.1") + extension);
        EXPECT_TRUE(same_domain(base, read_mesh(source))) << extension;
    }
}

TEST(SolverMeshes, PvtuPiecesAreDomainsMatchedByIds) {
    MeshSource source;
    source.path = kSolver / "pieces.pvtu";
    source.array = "distance";
    const PvtuPartition pieces(source);
    ASSERT_EQ(pieces.domain_count(), 3);
    EXPECT_EQ(pieces.node_count(), 343);
    EXPECT_EQ(pieces.tet_count(), 1296) << "ghost cells are skipped: every tetrahedron in one piece";
    std::int64_t tets = 0;
    std::vector<GlobalId> ids;
    for (int d = 0; d < 3; ++d) {
        const Domain domain = pieces.make_domain(d);
        tets += static_cast<std::int64_t>(domain.tet_count());
        EXPECT_TRUE(std::is_sorted(domain.gid.begin(), domain.gid.end()));
        ids.insert(ids.end(), domain.gid.begin(), domain.gid.end());
        EXPECT_FALSE(domain.shared_edges.empty());
        for (const EdgeKey key : domain.shared_edges) {
            const std::vector<int> holders = pieces.domains_of_edge(edge_key_low(key), edge_key_high(key));
            EXPECT_GE(holders.size(), 2u);
            EXPECT_TRUE(std::binary_search(holders.begin(), holders.end(), d));
        }
    }
    EXPECT_EQ(tets, 1296);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    EXPECT_EQ(ids.size(), 343u);
    EXPECT_EQ(ids.front(), 0);
    EXPECT_EQ(ids.back(), 342);
    // Slabs in x: the middle piece touches both others, the outer ones not each other.
    EXPECT_EQ(pieces.neighbours(0).size() + pieces.neighbours(1).size() + pieces.neighbours(2).size(), 4u);
}

JobConfig pvtu_job(bool reduce, const std::string& array = "distance") {
    JobConfig config;
    config.mesh = kSolver / "pieces.pvtu";
    config.domains = 0;
    config.array = array;
    config.field = "sphere";
    config.level = kLevel;
    config.reduce = reduce;
    return config;
}

TEST(SolverMeshes, PvtuJobIsTheWholeMeshsSurface) {
    const Domain whole = read_cube(kSolver / "cube-ascii.vtu");
    const Piece expected = extract(whole, kLevel);
    // Unreduced: the same vertices bit for bit, though the last piece's
    // shared points are one ulp off, and the same triangles.
    EXPECT_TRUE(same_surface(expected, run_local(Job(pvtu_job(false)), {}).surface));
    // The pieces joined into one domain by ids, as extract --mesh reads them.
    MeshSource source;
    source.path = kSolver / "pieces.pvtu";
    source.array = "distance";
    EXPECT_TRUE(same_surface(expected, extract(read_mesh(source), kLevel)));
    // An analytic field, evaluated where the pieces agree the nodes are.
    const std::unique_ptr<Field> sphere = make_field("sphere");
    MeshSource analytic;
    analytic.path = kSolver / "cube-ascii.vtu";
    analytic.field = sphere.get();
    EXPECT_TRUE(same_surface(extract(read_mesh(analytic), kLevel), run_local(Job(pvtu_job(false, "")), {}).surface));
    // Reduced: a sphere still.
    const Piece reduced = run_local(Job(pvtu_job(true)), {}).surface;
    expect_sphere(reduced);
    EXPECT_LT(reduced.triangle_count(), expected.triangle_count());
}

TEST(SolverMeshes, SplitOfAPvtuKeepsItsPieces) {
    MeshSource source;
    source.path = kSolver / "pieces.pvtu";
    source.array = "distance";
    const auto partition = partition_mesh(source, {}, 0);
    EXPECT_EQ(partition->domain_count(), 3);
    EXPECT_EQ(partition->tet_count(), 1296);
}

// A copy of the fixtures in a scratch directory, to damage.
class Scratch {
public:
    Scratch() : dir_(std::filesystem::temp_directory_path() / ("tetiso_solver_" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
        for (const auto& entry : std::filesystem::directory_iterator(kSolver))
            std::filesystem::copy_file(entry.path(), dir_ / entry.path().filename());
    }
    ~Scratch() { std::filesystem::remove_all(dir_); }
    std::filesystem::path path(const std::string& name) const { return dir_ / name; }
    std::string text(const std::string& name) const { return read_bytes(path(name)); }
    void write(const std::string& name, const std::string& bytes) const {
        std::ofstream(path(name), std::ios::binary | std::ios::trunc) << bytes;
    }

private:
    std::filesystem::path dir_;
};

std::string replace_first(std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

struct BadInput {
    const char* name;
    const char* file;                         // fixture to start from
    std::function<std::string(std::string)> damage;
    const char* expected;                     // part of the message
};

TEST(SolverMeshes, BadInputsAreOneErrorNamingTheFile) {
    const Scratch scratch;
    const BadInput table[] = {
        {"truncated ascii", "cube-ascii.vtu", [](std::string s) { return s.substr(0, s.size() / 2); }, "not well-formed XML"},
        {"truncated raw", "cube-raw.vtu", [](std::string s) { return s.substr(0, s.size() - 3000); }, "truncated"},
        {"truncated zlib", "cube-raw-zlib.vtu", [](std::string s) { return s.substr(0, s.size() - 2000); }, "past the appended data"},
        {"huge point count", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "NumberOfPoints=\"343\"", "NumberOfPoints=\"99999999999\""); }, "more points or cells"},
        {"point count above the data", "cube-raw.vtu", [](std::string s) { return replace_first(s, "NumberOfPoints=\"343\"", "NumberOfPoints=\"3430000\""); }, "bytes, where"},
        {"cell count above the data", "cube-binary.vtu", [](std::string s) { return replace_first(s, "NumberOfCells=\"1296\"", "NumberOfCells=\"1297\""); }, "bytes, where"},
        {"index out of range", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "format=\"ascii\">\n0 49 56 57", "format=\"ascii\">\n0 49 56 343"); }, "refers to point 343"},
        {"negative index", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "format=\"ascii\">\n0 49 56 57", "format=\"ascii\">\n0 -1 56 57"); }, "refers to point -1"},
        {"NaN coordinate", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "NumberOfComponents=\"3\" format=\"ascii\">\n0.0", "NumberOfComponents=\"3\" format=\"ascii\">\nnan"); }, "not finite"},
        {"infinite value", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "Name=\"distance\" NumberOfComponents=\"1\" format=\"ascii\">\n", "Name=\"distance\" NumberOfComponents=\"1\" format=\"ascii\">\ninf "); }, "more than the 343 values"},
        {"float connectivity", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "type=\"Int64\" Name=\"connectivity\"", "type=\"Float32\" Name=\"connectivity\""); }, "where integers are expected"},
        {"unknown type", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "type=\"Int64\" Name=\"connectivity\"", "type=\"Int128\" Name=\"connectivity\""); }, "unknown type 'Int128'"},
        {"missing array", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "Name=\"distance\"", "Name=\"pressure\""); }, "no point array 'distance' (it has: pressure)"},
        {"hexahedra", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "Name=\"types\" NumberOfComponents=\"1\" format=\"ascii\">\n10", "Name=\"types\" NumberOfComponents=\"1\" format=\"ascii\">\n12"); }, "1 volume cells of type 12 (hexahedron)"},
        {"damaged zlib block", "cube-raw-zlib.vtu", [](std::string s) { const std::size_t at = s.find("_", s.find("<AppendedData")) + 200; s[at] = static_cast<char>(s[at] ^ 0x5a); return s; }, "damaged"},
        {"bad base64", "cube-base64.vtu", [](std::string s) { const std::size_t at = s.find("_", s.find("<AppendedData")) + 50; s[at] = '*'; return s; }, "invalid character in base64"},
        {"big endian", "cube-raw.vtu", [](std::string s) { return replace_first(s, "LittleEndian", "BigEndian"); }, "only LittleEndian"},
        {"not a grid", "cube-ascii.vtu", [](std::string s) { return replace_first(s, "type=\"UnstructuredGrid\"", "type=\"PolyData\""); }, "not UnstructuredGrid"},
        {"msh truncated", "cube-4.1.msh", [](std::string s) { return s.substr(0, s.size() / 2); }, "truncated"},
        {"msh binary truncated", "cube-4.1-binary.msh", [](std::string s) { return s.substr(0, s.size() / 2); }, "truncated"},
        {"msh 2.2 binary truncated", "cube-2.2-binary.msh", [](std::string s) { return s.substr(0, s.size() / 3); }, "truncated"},
        {"msh huge node count", "cube-2.2.msh", [](std::string s) { return replace_first(s, "$Nodes\n343\n", "$Nodes\n99999999999999\n"); }, "a node tag"},
        {"msh node tag out of range", "cube-2.2.msh", [](std::string s) { return replace_first(s, "$Elements\n1296\n1 4 2 0 1 1 ", "$Elements\n1296\n1 4 2 0 1 999 "); }, "node tag 999, which does not exist"},
        {"msh NaN", "cube-2.2.msh", [](std::string s) { return replace_first(s, "$Nodes\n343\n1 0 ", "$Nodes\n343\n1 nan "); }, "not a finite number"},
        {"msh missing view", "cube-4.1.msh", [](std::string s) { return replace_first(s, "\"distance\"", "\"pressure\""); }, "no $NodeData view 'distance' (it has: 'pressure')"},
        {"msh hexahedra", "cube-2.2.msh", [](std::string s) { return replace_first(s, "$Elements\n1296\n1 4 2 0 1 1 50 57 58", "$Elements\n1296\n1 5 2 0 1 1 50 57 58 2 3 4 5"); }, "1 volume elements of type 5 (hexahedron)"},
        {"msh version", "cube-4.1.msh", [](std::string s) { return replace_first(s, "4.1 0 8", "3.0 0 8"); }, "format version 3.0"},
    };
    for (const BadInput& bad : table) {
        SCOPED_TRACE(bad.name);
        const std::string damaged = bad.damage(scratch.text(bad.file));
        scratch.write("damaged", damaged);
        const std::filesystem::path path = scratch.path(std::string("damaged") + std::filesystem::path(bad.file).extension().string());
        std::filesystem::rename(scratch.path("damaged"), path);
        const std::string what = error_of([&] { read_cube(path); });
        EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
        EXPECT_NE(what.find(bad.expected), std::string::npos) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
}

// What building the partition of `source` throws, or "(no error)".
std::string pvtu_error(const MeshSource& source) {
    return error_of([&] { PvtuPartition pieces(source); });
}

TEST(SolverMeshes, InconsistentPiecesAreRefusedByName) {
    const Scratch scratch;
    const auto pvtu_message = [&](const std::string& node_ids = "") {
        MeshSource source;
        source.path = scratch.path("pieces.pvtu");
        source.array = "distance";
        source.node_ids = node_ids;
        return pvtu_error(source);
    };
    EXPECT_EQ(pvtu_message(), "(no error)");
    // No ids: the message names the integer arrays there are.
    const std::string pvtu = scratch.text("pieces.pvtu");
    scratch.write("pieces.pvtu", replace_first(pvtu, " GlobalIds=\"GlobalNodeIds\"", ""));
    for (int p = 0; p < 3; ++p) {
        const std::string name = "pieces_" + std::to_string(p) + ".vtu";
        scratch.write(name, replace_first(scratch.text(name), " GlobalIds=\"GlobalNodeIds\"", ""));
        const std::string bytes = scratch.text(name);
        scratch.write(name, replace_first(bytes, "Name=\"GlobalNodeIds\"", "Name=\"ranks_ids\""));
    }
    std::string what = pvtu_message();
    EXPECT_NE(what.find("pieces_0.vtu: no global node ids"), std::string::npos) << what;
    EXPECT_NE(what.find("integer point arrays: ranks_ids"), std::string::npos) << what;
    EXPECT_EQ(pvtu_message("ranks_ids"), "(no error)") << "--node-ids names them";
    EXPECT_NE(pvtu_message("nothing").find("no point array 'nothing'"), std::string::npos);
    // A piece missing.
    std::filesystem::remove(scratch.path("pieces_2.vtu"));
    what = pvtu_message("ranks_ids");
    EXPECT_NE(what.find("pieces_2.vtu"), std::string::npos) << what;
}

// An ascii piece of tetrahedra over the given points, ids and values.
std::string ascii_piece(const std::vector<std::array<double, 3>>& points, const std::vector<std::int64_t>& ids,
                        const std::vector<double>& values, const std::vector<int>& tets, int type = 10) {
    std::string xyz, id, value, connectivity, offsets, types;
    for (const auto& p : points) xyz += std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + " ";
    for (const std::int64_t i : ids) id += std::to_string(i) + " ";
    for (const double v : values) value += std::to_string(v) + " ";
    for (const int v : tets) connectivity += std::to_string(v) + " ";
    for (std::size_t t = 1; t <= tets.size() / 4; ++t) offsets += std::to_string(4 * t) + " ", types += std::to_string(type) + " ";
    return "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"" + std::to_string(points.size()) +
           "\" NumberOfCells=\"" + std::to_string(tets.size() / 4) + "\"><PointData GlobalIds=\"ids\">" +
           "<DataArray type=\"Float64\" Name=\"f\" format=\"ascii\">" + value + "</DataArray>" +
           "<DataArray type=\"Int64\" Name=\"ids\" format=\"ascii\">" + id + "</DataArray></PointData>" +
           "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">" + xyz +
           "</DataArray></Points><Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" +
           connectivity + "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" + offsets +
           "</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" + types +
           "</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>";
}

// A rank whose part of the mesh is empty writes a piece of no points and no
// cells, every array present but empty, and a piece may hold points but no
// cells. Both read as an empty domain, in ascii and in binary, including the
// arrays whose stored type is the one read (copied whole, not converted).
TEST(SolverMeshes, PiecesWithoutCellsReadAsEmpty) {
    for (const std::string format : {"ascii", "binary"}) {
        for (const bool with_points : {false, true}) {
            SCOPED_TRACE(format + (with_points ? ", one point" : ", no point"));
            // binary: a UInt32 byte count, then the bytes, base64-encoded.
            const std::string empty = format == "ascii" ? "" : "AAAAAA==";
            const auto data = [&](const char* ascii, const char* binary) {
                return with_points ? std::string(format == "ascii" ? ascii : binary) : empty;
            };
            const auto array = [&](const char* type, const char* name, const std::string& values, int components = 1) {
                return "<DataArray type=\"" + std::string(type) + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
                       std::to_string(components) + "\" format=\"" + format + "\">" + values + "</DataArray>";
            };
            const std::string file =
                "<VTKFile type=\"UnstructuredGrid\" header_type=\"UInt32\"><UnstructuredGrid><Piece NumberOfPoints=\"" +
                std::string(with_points ? "1" : "0") + "\" NumberOfCells=\"0\"><PointData GlobalIds=\"ids\">" +
                array("Float64", "f", data("2.5", "CAAAAA==AAAAAAAABEA=")) + array("Int64", "ids", data("7", "CAAAAA==BwAAAAAAAAA=")) +
                "</PointData><CellData>" + array("UInt8", "vtkGhostType", empty) + "</CellData><Points>" +
                array("Float64", "Points", data("1 2 3", "GAAAAA==AAAAAAAA8D8AAAAAAAAAQAAAAAAAAAhA"), 3) + "</Points><Cells>" +
                array("Int32", "connectivity", empty) + array("Int32", "offsets", empty) + array("UInt8", "types", empty) +
                "</Cells></Piece></UnstructuredGrid></VTKFile>";
            VtuRequest request;
            request.array = "f";
            request.require_node_ids = true;
            const MeshArrays piece = parse_vtu(file, "empty.vtu", request);
            EXPECT_TRUE(piece.tets.empty());
            EXPECT_EQ(piece.ghost_cells, 0u);
            if (with_points) {
                EXPECT_EQ(piece.f, std::vector<double>{2.5});
                EXPECT_EQ(piece.ids, std::vector<GlobalId>{7});
                EXPECT_EQ(piece.x, std::vector<double>{1});
                EXPECT_EQ(piece.y, std::vector<double>{2});
                EXPECT_EQ(piece.z, std::vector<double>{3});
            } else {
                EXPECT_TRUE(piece.f.empty() && piece.ids.empty() && piece.x.empty());
            }
        }
    }
}

// A .pvtu of the pieces a.vtu and b.vtu in `scratch`, read with the field f.
MeshSource two_pieces(const Scratch& scratch) {
    scratch.write("two.pvtu", "<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid><Piece Source=\"a.vtu\"/>"
                              "<Piece Source=\"b.vtu\"/></PUnstructuredGrid></VTKFile>");
    MeshSource source;
    source.path = scratch.path("two.pvtu");
    source.array = "f";
    return source;
}

// The copies of a shared node may differ by float rounding (a value) or by
// a small fraction of an edge (a position): the node takes the smallest
// copy whatever the pieces' order, so both orders give the same domains.
// Copies farther apart are refused, both printed in full, in either order.
TEST(SolverMeshes, SharedNodesAgreeWithinATolerance) {
    const Scratch scratch;
    const std::vector<std::array<double, 3>> face = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    auto a_points = face, b_points = face;
    a_points.push_back({0, 0, 1});
    b_points[1] = {1.000001, 0, 0};
    b_points.push_back({0, 0, -1});
    scratch.write("a.vtu", ascii_piece(a_points, {0, 1, 2, 3}, {0, 1, 4, 3}, {0, 1, 2, 3}));
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 4}, {0, 1, 4.000001, 4}, {0, 1, 2, 3}));
    const MeshSource source = two_pieces(scratch);
    scratch.write("reversed.pvtu", "<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid><Piece Source=\"b.vtu\"/>"
                                   "<Piece Source=\"a.vtu\"/></PUnstructuredGrid></VTKFile>");
    MeshSource reversed = source;
    reversed.path = scratch.path("reversed.pvtu");
    {
        const PvtuPartition forward(source), backward(reversed);
        for (int d = 0; d < 2; ++d) {
            int e = 0;
            while (backward.piece_path(e) != forward.piece_path(d)) ++e;
            const Domain one = forward.make_domain(d), other = backward.make_domain(e);
            EXPECT_EQ(one.gid, other.gid);
            EXPECT_TRUE(test::same_bits(one.x, other.x) && test::same_bits(one.y, other.y) &&
                        test::same_bits(one.z, other.z) && test::same_bits(one.f, other.f))
                << forward.piece_path(d) << " depends on the pieces' order";
            for (std::size_t v = 0; v < one.node_count(); ++v) {
                if (one.gid[v] == 1) {
                    EXPECT_EQ(one.x[v], 1.0f) << "the smaller copy";
                }
                if (one.gid[v] == 2) {
                    EXPECT_EQ(one.f[v], 4.0f) << "the smaller copy";
                }
            }
        }
    }
    b_points[1] = {2, 0, 0};
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 4}, {0, 1, 4, 4}, {0, 1, 2, 3}));
    for (const MeshSource& order : {source, reversed}) {
        const std::string what = pvtu_error(order);
        EXPECT_NE(what.find(scratch.path("b.vtu").string() + ": node id 1 is at (2, 0, 0), where " +
                            scratch.path("a.vtu").string() + " puts it at (1, 0, 0)"),
                  std::string::npos)
            << what;
    }
}

TEST(SolverMeshes, PiecesThatDisagreeOnAValueAreRefused) {
    const Scratch scratch;
    // Two tetrahedra sharing the face of ids 0, 1, 2, one per piece.
    const std::vector<std::array<double, 3>> face = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    auto a_points = face, b_points = face;
    a_points.push_back({0, 0, 1});
    b_points.push_back({0, 0, -1});
    scratch.write("a.vtu", ascii_piece(a_points, {0, 1, 2, 3}, {0, 1, 2, 3}, {0, 1, 2, 3}));
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 4}, {0, 1, 2, 4}, {0, 1, 2, 3}));
    MeshSource source = two_pieces(scratch);
    {
        const PvtuPartition pieces(source);
        EXPECT_EQ(pieces.node_count(), 5);
        EXPECT_EQ(pieces.domains_of_edge(0, 1), (std::vector<int>{0, 1}));
        EXPECT_TRUE(pieces.domains_of_edge(0, 3).empty());
    }
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 4}, {0, 1.5, 2, 4}, {0, 1, 2, 3}));
    const std::string what = pvtu_error(source);
    EXPECT_NE(what.find(scratch.path("b.vtu").string() + ": node id 1 has value 1.5"), std::string::npos) << what;
    EXPECT_NE(what.find("a.vtu gives it 1"), std::string::npos) << what;
    // DOLFINx's cells: Lagrange tetrahedra (type 71) of 4 points are linear
    // ones; its NAME.pvtu is a time series, which stands for its last step.
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 4}, {0, 1, 2, 4}, {0, 1, 2, 3}, 71));
    scratch.write("series.pvtu", "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"0\" file=\"none.pvtu\"/>"
                                 "<DataSet timestep=\"1\" file=\"two.pvtu\"/></Collection></VTKFile>");
    source.path = scratch.path("series.pvtu");
    EXPECT_EQ(PvtuPartition(source).tet_count(), 2);
    source.path = scratch.path("two.pvtu");
    // A node id given to two points of one piece.
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, 1}, {0, 1, 2, 4}, {0, 1, 2, 3}));
    EXPECT_NE(pvtu_error(source).find("node id 1 is given to points"), std::string::npos);
    // Ids beyond 32 bits.
    scratch.write("b.vtu", ascii_piece(b_points, {0, 1, 2, -4}, {0, 1, 2, 4}, {0, 1, 2, 3}));
    EXPECT_NE(pvtu_error(source).find("outside [0, 2^32)"), std::string::npos);
}


TEST(SolverMeshes, RanksShareTheScanAndAgree) {
    MeshSource source;
    source.path = kSolver / "pieces.pvtu";
    source.array = "distance";
    const PvtuPartition alone(source);
    for (const int size : {2, 3, 5}) {
        ThreadRanks ranks(size);
        std::vector<std::unique_ptr<PvtuPartition>> built(static_cast<std::size_t>(size));
        std::vector<std::thread> threads;
        for (int r = 0; r < size; ++r)
            threads.emplace_back([&, r] { built[static_cast<std::size_t>(r)] = std::make_unique<PvtuPartition>(source, nullptr, ranks.group(r)); });
        for (std::thread& t : threads) t.join();
        for (const auto& partition : built) {
            EXPECT_EQ(partition->fingerprint(), alone.fingerprint()) << size;
            EXPECT_EQ(partition->spacing(), alone.spacing()) << size;
            EXPECT_TRUE(same_domain(partition->make_domain(1), alone.make_domain(1))) << size;
        }
    }
    // A piece one rank cannot read: every rank gives its error, none waits.
    const Scratch scratch;
    std::filesystem::remove(scratch.path("pieces_2.vtu"));
    source.path = scratch.path("pieces.pvtu");
    ThreadRanks ranks(2);
    std::vector<std::string> errors(2);
    std::vector<std::thread> threads;
    for (int r = 0; r < 2; ++r)
        threads.emplace_back([&, r] { errors[static_cast<std::size_t>(r)] = error_of([&] { PvtuPartition p(source, nullptr, ranks.group(r)); }); });
    for (std::thread& t : threads) t.join();
    for (const std::string& e : errors) EXPECT_NE(e.find("pieces_2.vtu: cannot open"), std::string::npos) << e;
}

TEST(SolverMeshes, SparseIdsSurviveASplit) {
    const Scratch scratch;
    const std::vector<std::array<double, 3>> a_points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const std::vector<std::array<double, 3>> b_points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}};
    scratch.write("a.vtu", ascii_piece(a_points, {10, 2000, 5, 4000000000}, {0, 1, 2, 3}, {0, 1, 2, 3}));
    scratch.write("b.vtu", ascii_piece(b_points, {10, 2000, 5, 7}, {0, 1, 2, 4}, {0, 1, 2, 3}));
    const MeshSource source = two_pieces(scratch);
    const PvtuPartition pieces(source);
    EXPECT_EQ(pieces.node_count(), 5);
    EXPECT_EQ(pieces.domains_of_edge(10, 2000), (std::vector<int>{0, 1}));
    const std::filesystem::path dir = scratch.path("split");
    write_mesh_split(pieces, 0.0, dir);
    const SplitMeshPartition split(dir);
    for (int d = 0; d < 2; ++d) {
        const Domain from_pieces = pieces.make_domain(d), from_split = split.make_domain(d);
        EXPECT_TRUE(same_domain(from_pieces, from_split)) << d;
        EXPECT_EQ(from_pieces.shared_edges, from_split.shared_edges) << d;
    }
    EXPECT_EQ(pieces.make_domain(0).gid, (std::vector<GlobalId>{5, 10, 2000, 4000000000}));
}

} // namespace
} // namespace tetiso
