// Unstructured meshes from TetGen (core/src/tetgen.cpp): surfaces of known
// topology extracted from meshes/cube.1, a reduction that leaves no face
// through its neighbours, a field given as a node attribute
// giving the same surface as the analytic one, tetrahedra in either
// orientation giving the same surface, and clear errors for malformed files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

const std::filesystem::path kCube = std::filesystem::path(TETISO_MESHES_DIR) / "cube.1";

Domain cube(const Field& field) { return read_tetgen(TetgenSource{kCube, std::nullopt, &field}); }

// A scratch copy of the cube mesh whose files the test may rewrite.
struct Scratch {
    std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                ("tetiso_tetgen_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                 "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    Scratch() {
        std::filesystem::create_directories(dir);
        for (const char* ext : {".node", ".ele"})
            std::filesystem::copy_file(kCube.string() + ext, base().string() + ext,
                                       std::filesystem::copy_options::overwrite_existing);
    }
    ~Scratch() { std::filesystem::remove_all(dir); }
    std::filesystem::path base() const { return dir / "mesh"; }
    std::string read(const char* ext) const {
        std::ifstream in(base().string() + ext);
        std::stringstream text;
        text << in.rdbuf();
        return text.str();
    }
    void write(const char* ext, const std::string& text) const { std::ofstream(base().string() + ext) << text; }
};

TEST(Tetgen, ReadsTheCubeMesh) {
    const auto field = make_field("sphere");
    const Domain d = cube(*field);
    EXPECT_EQ(d.node_count(), 3711u);
    EXPECT_EQ(d.tet_count(), 16251u);
    // Every tetrahedron positively oriented, as extraction requires.
    for (std::size_t t = 0; t < d.tet_count(); ++t) {
        double p[4][3];
        for (int k = 0; k < 4; ++k) {
            const auto v = static_cast<std::size_t>(d.tets[4 * t + static_cast<std::size_t>(k)]);
            p[k][0] = d.x[v];
            p[k][1] = d.y[v];
            p[k][2] = d.z[v];
        }
        double u[3], v[3], w[3];
        for (int a = 0; a < 3; ++a) {
            u[a] = p[1][a] - p[0][a];
            v[a] = p[2][a] - p[0][a];
            w[a] = p[3][a] - p[0][a];
        }
        const double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                           u[2] * (v[0] * w[1] - v[1] * w[0]);
        ASSERT_GT(det, 0.0) << "tetrahedron " << t;
    }
}

TEST(Tetgen, SphereAndTorusHaveTheirTopology) {
    struct Case {
        const char* field;
        std::int64_t euler;
    };
    for (const Case c : {Case{"sphere", 2}, Case{"torus", 0}}) {
        SCOPED_TRACE(c.field);
        const auto field = make_field(c.field);
        const Domain d = cube(*field);
        const Piece s = extract(d, static_cast<float>(field->default_level()));
        const TopologyReport t = check_topology(s);
        EXPECT_EQ(t.components, 1);
        EXPECT_EQ(t.euler, c.euler);
        EXPECT_TRUE(t.closed);
        EXPECT_TRUE(t.manifold);
        EXPECT_TRUE(t.oriented);
        // Normals towards increasing field: outwards for a distance field.
        EXPECT_GT(test::signed_volume(s), 0.0);
        // Every vertex on its mesh edge, where the linear field takes the level.
        const float level = static_cast<float>(field->default_level());
        for (std::size_t v = 0; v < s.vertex_count(); ++v) {
            const auto a = static_cast<std::size_t>(edge_key_low(s.key[v]));
            const auto b = static_cast<std::size_t>(edge_key_high(s.key[v]));
            const double ex = d.x[b] - d.x[a], ey = d.y[b] - d.y[a], ez = d.z[b] - d.z[a];
            const double len2 = ex * ex + ey * ey + ez * ez;
            const double t01 = ((s.x[v] - d.x[a]) * ex + (s.y[v] - d.y[a]) * ey + (s.z[v] - d.z[a]) * ez) / len2;
            ASSERT_GE(t01, -1e-6);
            ASSERT_LE(t01, 1 + 1e-6);
            const double off = std::hypot(s.x[v] - (d.x[a] + t01 * ex), s.y[v] - (d.y[a] + t01 * ey),
                                          s.z[v] - (d.z[a] + t01 * ez));
            ASSERT_LT(off, 1e-5);
            const double f = d.f[a] + t01 * (d.f[b] - d.f[a]);
            ASSERT_NEAR(f, level, 1e-4 * (std::abs(d.f[b] - d.f[a]) + 1));
        }
        // Reduction keeps the topology here too.
        ReduceOptions o;
        o.max_error = 0.05;
        const Piece r = reduce(s, o);
        const TopologyReport rt = check_topology(r);
        EXPECT_TRUE(same_signatures(t, rt));
        EXPECT_TRUE(rt.manifold);
        EXPECT_TRUE(rt.oriented);
        EXPECT_EQ(rt.degenerate_triangles, 0);
        EXPECT_LT(r.triangle_count(), s.triangle_count());
    }
}

// The paper field on this mesh passes close to mesh nodes where its sheets
// nearly touch: before collapses were tested against the faces around their
// outer corners (reduce.cpp, Cones), its reduction had 4 self-intersections,
// all between faces sharing a corner, at each bound tried here.
TEST(Tetgen, ReductionPushesNoFaceThroughItsNeighbours) {
    if (!have_self_intersections()) GTEST_SKIP() << "built without CGAL: self-intersections cannot be counted";
    const auto field = make_field("paper");
    const Domain d = cube(*field);
    const Piece s = extract(d, 0.5f);
    ASSERT_EQ(count_self_intersections(s), std::optional<std::size_t>(0));
    for (const double spacings : {0.1, 0.25, 0.4}) {
        SCOPED_TRACE(spacings);
        ReduceOptions o;
        o.max_error = spacings * mean_edge_length(d);
        const Piece r = reduce(s, o);
        EXPECT_LT(r.triangle_count(), s.triangle_count());
        EXPECT_TRUE(same_signatures(check_topology(s), check_topology(r)));
        EXPECT_EQ(count_self_intersections(r), std::optional<std::size_t>(0));
    }
}

TEST(Tetgen, AttributeFieldGivesTheAnalyticSurface) {
    // The sphere field written as the nodes' only attribute, with enough
    // digits that each float value survives the text round trip.
    const auto field = make_field("sphere");
    const Domain analytic = cube(*field);
    const Scratch scratch;
    std::ostringstream node;
    node << analytic.node_count() << " 3 1 0\n";
    std::istringstream original(scratch.read(".node"));
    std::string line;
    std::getline(original, line); // header
    for (std::size_t i = 0; i < analytic.node_count(); ++i) {
        std::getline(original, line);
        char value[32];
        std::snprintf(value, sizeof value, " %.9g", static_cast<double>(analytic.f[i]));
        node << line << value << '\n';
    }
    scratch.write(".node", node.str());
    const Domain from_attribute = read_tetgen(TetgenSource{scratch.base(), 0, nullptr});
    ASSERT_EQ(from_attribute.f.size(), analytic.f.size());
    EXPECT_TRUE(test::same_bits(from_attribute.f, analytic.f));
    EXPECT_TRUE(test::same_surface(extract(from_attribute, 2.0f), extract(analytic, 2.0f)));
}

TEST(Tetgen, TetrahedraInEitherOrientationGiveTheSameSurface) {
    const auto field = make_field("torus");
    const Scratch scratch;
    std::istringstream original(scratch.read(".ele"));
    std::ostringstream flipped;
    std::string line;
    std::getline(original, line);
    flipped << line << '\n';
    while (std::getline(original, line)) {
        std::istringstream fields(line);
        long number, a, b, c, d;
        if (!(fields >> number >> a >> b >> c >> d)) {
            flipped << line << '\n';
            continue;
        }
        flipped << number << ' ' << b << ' ' << a << ' ' << c << ' ' << d << '\n';
    }
    scratch.write(".ele", flipped.str());
    const Piece a = extract(cube(*field), 0.6f);
    const Piece b = extract(read_tetgen(TetgenSource{scratch.base(), std::nullopt, field.get()}), 0.6f);
    EXPECT_TRUE(test::same_surface(a, b));
}

TEST(Tetgen, MalformedFilesAreNamedWithTheirLine) {
    const auto field = make_field("sphere");
    struct Case {
        const char* ext;
        const char* find;
        const char* replace;
        const char* message;
    };
    // Each case rewrites the first occurrence of `find` in one file.
    for (const Case c : {Case{".node", "3711  3  0  0", "3712  3  0  0", "promises 3712 nodes"},
                         Case{".node", "\n   2 ", "\n   3 ", "node number 3 where 2 was expected"},
                         Case{".node", "3711  3  0  0", "3711  2  0  0", "dimension is not 3"},
                         Case{".ele", "16251  4  0", "16251  5  0", "not 4 or 10"},
                         Case{".ele", "16251  4  0", "99999  4  0", "promises 99999 tetrahedra"},
                         Case{".ele", "16251  4  0", "16251  4  0\n1 1 2 3 9999", "node 9999, which does not exist"},
                         Case{".ele", "16251  4  0", "16251  4  0\n1 1 2 2 3", "repeats node 2"},
                         Case{".node", "\n   1 ", "\n   1 nan", "not a finite number"},
                         Case{".node", "\n   1 ", "\n   1 1e300 ", "not a finite number in float range"}}) {
        SCOPED_TRACE(c.message);
        const Scratch scratch;
        std::string text = scratch.read(c.ext);
        const auto at = text.find(c.find);
        ASSERT_NE(at, std::string::npos) << c.find;
        text.replace(at, std::strlen(c.find), c.replace);
        scratch.write(c.ext, text);
        try {
            read_tetgen(TetgenSource{scratch.base(), std::nullopt, field.get()});
            ADD_FAILURE() << "no error";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(scratch.base().string() + c.ext), std::string::npos) << what;
            EXPECT_NE(what.find(c.message), std::string::npos) << what;
        }
    }
    EXPECT_THROW(read_tetgen(TetgenSource{"/nonexistent/mesh", std::nullopt, field.get()}), Error);
    EXPECT_THROW(read_tetgen(TetgenSource{kCube, 2, nullptr}), Error) << "the cube's nodes have no attribute";
}

} // namespace
} // namespace tetiso
