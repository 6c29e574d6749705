// Tetrahedra that overlap, refused where a mesh is read (mesh_file.hpp's
// check_tetrahedra, core/inputs/tet_faces.hpp; .pvtu pieces,
// core/inputs/pvtu_overlaps.hpp): tiny meshes built here, each a case of
// what the face pass must tell apart, and pieces that overlap where one
// lies inside the other, found alike for any number of ranks.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "test_support.hpp"
#include "thread_ranks.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/pvtu.hpp"

namespace tetiso {
namespace {

using test::error_of;

// Points: a triangle in z = 0 and a point above it, one below, one higher.
Domain points() {
    Domain d;
    d.x = {0, 1, 0, 0.2f, 0.2f, 0.2f};
    d.y = {0, 0, 1, 0.2f, 0.2f, 0.2f};
    d.z = {0, 0, 0, 1, -1, 2};
    d.f.assign(6, 0);
    d.gid = {0, 1, 2, 3, 4, 5};
    d.interface.assign(6, 0);
    return d;
}

std::string check(std::vector<std::int32_t> tets, const std::vector<std::uint64_t>& numbers = {}) {
    Domain d = points();
    d.tets = std::move(tets);
    return error_of([&] { check_tetrahedra(d, "m.vtu", numbers, "cell"); });
}

TEST(MeshOverlaps, TwoTetrahedraOnOneFaceMustLieOnEitherSide) {
    // Over the face (0, 1, 2): 3 above, 4 below; in either corner order.
    EXPECT_EQ(check({0, 1, 2, 3, 0, 1, 2, 4}), "(no error)");
    EXPECT_EQ(check({0, 2, 1, 3, 0, 1, 2, 4}), "(no error)");
    EXPECT_EQ(check({0, 2, 1, 3, 0, 2, 1, 4}), "(no error)") << "all listed negatively is a convention";
    // 3 and 5 both above: they overlap.
    EXPECT_EQ(check({0, 1, 2, 3, 0, 1, 2, 5}),
              "m.vtu: tetrahedron 0 and tetrahedron 1 lie on the same side of the face they share, so the two "
              "overlap: the mesh is tangled");
    EXPECT_EQ(check({0, 1, 2, 3, 3, 2, 1, 0}),
              "m.vtu: tetrahedron 1 repeats tetrahedron 0: the same four corners, so the two overlap (4 faces of the "
              "mesh clash like this)");
    EXPECT_EQ(check({0, 1, 2, 3, 0, 1, 2, 4, 0, 1, 2, 5}, {7, 9, 12}),
              "m.vtu: tetrahedron 0 (cell 7), tetrahedron 1 (cell 9) and tetrahedron 2 (cell 12) share one face: "
              "at most two tetrahedra can, one on either side, so they overlap");
    // Zero volume: 0, 1, 2 and a point in their plane.
    Domain flat = points();
    flat.x.push_back(1), flat.y.push_back(1), flat.z.push_back(0), flat.f.push_back(0), flat.gid.push_back(6);
    flat.tets = {0, 1, 2, 6};
    EXPECT_NE(error_of([&] { check_tetrahedra(flat, "m.vtu"); }).find("m.vtu: tetrahedron 0 has zero volume"),
              std::string::npos);
}

// A column of cubes, each in six tetrahedra around its diagonal, listed
// positively: then one node moved through its neighbours' faces inverts
// tetrahedra, and the one named is one the move inverted.
TEST(MeshOverlaps, AnInvertedTetrahedronIsNamedAgainstTheMeshsOrientation) {
    Domain d;
    const int n = 4; // nodes per axis
    const auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                d.x.push_back(static_cast<float>(i)), d.y.push_back(static_cast<float>(j)), d.z.push_back(static_cast<float>(k));
                d.gid.push_back(id(i, j, k));
            }
    d.f.assign(d.x.size(), 0);
    d.interface.assign(d.x.size(), 0);
    const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int i = 0; i + 1 < n; ++i)
        for (int j = 0; j + 1 < n; ++j)
            for (int k = 0; k + 1 < n; ++k)
                for (const auto& path : paths) {
                    int c[3] = {i, j, k};
                    std::int32_t corners[4] = {id(i, j, k)};
                    for (int s = 0; s < 3; ++s) ++c[path[s]], corners[s + 1] = id(c[0], c[1], c[2]);
                    d.tets.insert(d.tets.end(), corners, corners + 4);
                }
    Domain listed = d;
    orient_tetrahedra(listed, "lattice"); // every tetrahedron now positive as listed
    {
        Domain copy = listed;
        EXPECT_EQ(error_of([&] { check_tetrahedra(copy, "lattice"); }), "(no error)");
    }
    const auto moved = static_cast<std::size_t>(id(1, 1, 1));
    listed.x[moved] += 1.5f;
    std::vector<std::size_t> inverted;
    for (std::size_t t = 0; t < listed.tet_count(); ++t) {
        const std::int32_t* v = listed.tets.data() + 4 * t;
        if (signed_volume6(listed, v[0], v[1], v[2], v[3]) < 0) inverted.push_back(t);
    }
    ASSERT_FALSE(inverted.empty());
    const std::string what = error_of([&] { check_tetrahedra(listed, "lattice"); });
    const std::size_t at = what.find(" is inverted: negatively oriented where the mesh's tetrahedra are positively");
    ASSERT_NE(at, std::string::npos) << what;
    const std::size_t named = std::stoul(what.substr(what.find("tetrahedron ") + 12));
    EXPECT_NE(std::find(inverted.begin(), inverted.end(), named), inverted.end()) << what;
}


// An ascii piece of tetrahedra over the points of a 4 x 4 x 4 lattice, or
// the six of points() where `small`, node ids their indices (+ id_offset).
std::string piece(const std::vector<std::array<int, 4>>& tets, int id_offset = 0, bool small = false) {
    std::string xyz, ids, f, connectivity, offsets, types;
    const Domain few = points();
    const int count = small ? 6 : 64;
    for (int i = 0; i < count; ++i) {
        const auto at = static_cast<std::size_t>(i);
        xyz += small ? std::to_string(few.x[at]) + " " + std::to_string(few.y[at]) + " " + std::to_string(few.z[at]) + " "
                     : std::to_string(i / 16) + " " + std::to_string(i / 4 % 4) + " " + std::to_string(i % 4) + " ";
        ids += std::to_string(i + id_offset) + " ";
        f += std::to_string(i) + " ";
    }
    for (std::size_t t = 0; t < tets.size(); ++t) {
        for (const int v : tets[t]) connectivity += std::to_string(v) + " ";
        offsets += std::to_string(4 * (t + 1)) + " ", types += "10 ";
    }
    return "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"" + std::to_string(count) +
           "\" NumberOfCells=\"" +
           std::to_string(tets.size()) + "\"><PointData GlobalIds=\"ids\"><DataArray type=\"Float64\" Name=\"f\" format=\"ascii\">" +
           f + "</DataArray><DataArray type=\"Int64\" Name=\"ids\" format=\"ascii\">" + ids +
           "</DataArray></PointData><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">" + xyz +
           "</DataArray></Points><Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" + connectivity +
           "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" + offsets +
           "</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">" + types +
           "</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>";
}

// The 3 x 3 x 3 cubes of that lattice in six tetrahedra each; `keep` picks cubes.
std::vector<std::array<int, 4>> cubes(const std::function<bool(int, int, int)>& keep) {
    std::vector<std::array<int, 4>> tets;
    const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) {
                if (!keep(i, j, k)) continue;
                for (const auto& path : paths) {
                    int c[3] = {i, j, k};
                    std::array<int, 4> t{(i * 4 + j) * 4 + k};
                    for (int s = 0; s < 3; ++s) ++c[path[s]], t[static_cast<std::size_t>(s + 1)] = (c[0] * 4 + c[1]) * 4 + c[2];
                    tets.push_back(t);
                }
            }
    return tets;
}

struct Pieces {
    test::ScratchDirectory scratch{"tetiso_overlaps"};
    MeshSource source(const std::vector<std::pair<std::string, std::string>>& files) const {
        std::string index = "<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid>";
        for (const auto& [name, bytes] : files) {
            std::ofstream(scratch.at(name)) << bytes;
            index += "<Piece Source=\"" + name + "\"/>";
        }
        std::ofstream(scratch.at("all.pvtu")) << index + "</PUnstructuredGrid></VTKFile>";
        MeshSource source;
        source.path = scratch.at("all.pvtu");
        source.array = "f";
        return source;
    }
};

// Each rank's message (or "(no error)") from building the partition.
std::vector<std::string> on_ranks(const MeshSource& source, int size) {
    ThreadRanks ranks(size);
    std::vector<std::string> errors(static_cast<std::size_t>(size));
    std::vector<std::thread> threads;
    for (int r = 0; r < size; ++r)
        threads.emplace_back([&, r] {
            errors[static_cast<std::size_t>(r)] = error_of([&] { PvtuPartition p(source, nullptr, ranks.group(r)); });
        });
    for (std::thread& t : threads) t.join();
    return errors;
}

TEST(MeshOverlaps, APieceInsideAnotherIsRefusedOnEveryRank) {
    const Pieces pieces;
    const auto all = [](int, int, int) { return true; };
    const auto low = [](int i, int, int) { return i == 0; };
    const auto high = [](int i, int, int) { return i > 0; };
    // The halves: no overlap; the same for any number of ranks.
    const MeshSource halves = pieces.source({{"low.vtu", piece(cubes(low))}, {"high.vtu", piece(cubes(high))}});
    for (const int size : {1, 2, 3})
        for (const std::string& e : on_ranks(halves, size)) EXPECT_EQ(e, "(no error)") << size;
    // The whole lattice, and its centre cube, whose corners lie on no face
    // of the whole one's boundary: the second piece's tetrahedra are the
    // first's inside, on no boundary but their own. Whichever rank scans
    // which piece, all name the same.
    const auto centre = [](int i, int j, int k) { return i == 1 && j == 1 && k == 1; };
    const MeshSource inside = pieces.source({{"whole.vtu", piece(cubes(all))}, {"centre.vtu", piece(cubes(centre))}});
    const std::string expected = pieces.scratch.at("centre.vtu").string() + ": the tetrahedron of node ids";
    for (const int size : {1, 2, 3}) {
        const std::vector<std::string> errors = on_ranks(inside, size);
        for (const std::string& e : errors) {
            EXPECT_EQ(e, errors[0]) << size;
            EXPECT_EQ(e.rfind(expected, 0), 0u) << e;
            EXPECT_NE(e.find("reaches inside " + pieces.scratch.at("whole.vtu").string() + ": node id 21 lies on no face"),
                      std::string::npos)
                << e;
        }
    }
    // Two tetrahedra over the face (0, 1, 2), one above and one below, and
    // a piece of one more above it: no node lies inside the first piece, but
    // the face does, between its two tetrahedra.
    const MeshSource face = pieces.source({{"pair.vtu", piece({{0, 1, 2, 3}, {0, 1, 2, 4}}, 0, true)},
                                           {"above.vtu", piece({{0, 1, 2, 5}}, 0, true)}});
    for (const int size : {1, 2}) {
        const std::vector<std::string> errors = on_ranks(face, size);
        for (const std::string& e : errors)
            EXPECT_NE(e.find("above.vtu: the tetrahedron of node ids 0, 1, 2, 5 (cell 0) reaches inside " +
                             pieces.scratch.at("pair.vtu").string() +
                             ": its face of node ids 0, 1, 2 lies between two tetrahedra of that piece"),
                      std::string::npos)
                << e;
    }
}

// A tangle across the boundary between pieces: each piece is sound alone,
// but the tetrahedra on either side of the face they share lie on one side.
TEST(MeshOverlaps, PiecesThatFoldOverEachOtherAreRefused) {
    const Pieces pieces;
    for (const int size : {1, 2})
        for (const std::string& e : on_ranks(pieces.source({{"a.vtu", piece({{0, 1, 2, 3}}, 0, true)},
                                                             {"b.vtu", piece({{0, 2, 1, 4}}, 0, true)}}),
                                              size))
            EXPECT_EQ(e, "(no error)");
    const std::string what = error_of([&] {
        PvtuPartition p(pieces.source({{"a.vtu", piece({{0, 1, 2, 3}}, 0, true)}, {"b.vtu", piece({{0, 2, 1, 5}}, 0, true)}}));
    });
    EXPECT_EQ(what, pieces.scratch.at("b.vtu").string() + ": cell 0 lies on the same side of the face of node ids 0, 1, 2 as cell 0 of " +
                        pieces.scratch.at("a.vtu").string() +
                        ", its neighbour across it, so the two overlap: the mesh is tangled where it crosses from one piece into the other");
}

TEST(MeshOverlaps, PiecesThatShareNoNodeIdAreNoted) {
    const Pieces pieces;
    const auto low = [](int i, int, int) { return i == 0; };
    const auto high = [](int i, int, int) { return i > 0; };
    EXPECT_TRUE(PvtuPartition(pieces.source({{"low.vtu", piece(cubes(low))}, {"high.vtu", piece(cubes(high))}})).notes().empty());
    const PvtuPartition apart(pieces.source({{"low.vtu", piece(cubes(low))}, {"high.vtu", piece(cubes(high), 100)}}));
    ASSERT_EQ(apart.notes().size(), 1u);
    EXPECT_NE(apart.notes()[0].find("the pieces fall into 2 groups that share no node id (piece 0 ("), std::string::npos)
        << apart.notes()[0];
    EXPECT_TRUE(PvtuPartition(pieces.source({{"low.vtu", piece(cubes(low))}})).notes().empty()) << "one piece";
}

} // namespace
} // namespace tetiso
