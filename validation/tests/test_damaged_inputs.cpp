// Files damaged at random: every reader either returns something the next
// stage can take or throws tetiso::Error. The readers here: PLY, VTP, TetGen
// meshes, and split meshes (index, domain and edge files). A valid file is cut short, has bytes
// overwritten, inserted or dropped, or has one of its numbers replaced by a
// value chosen to break arithmetic on counts and sizes (0, -1, 2^31, 2^32 - 1,
// 10^20, 1e308, nan). What reads is then checked and, where it is a manifold,
// reduced: the reducer must keep its topology or refuse it with an Error.
//
// Any other exception fails the case and names the format, seed and case
// number that reproduce it; a crash or, in a sanitizer build, an invalid read
// ends the program. The cases are few enough for CI (about a second in a
// Release build); TETISO_DAMAGE_CASES raises the count for a longer hunt.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>

#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/io.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

namespace fs = std::filesystem;

void spill(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

int case_count() {
    const char* text = std::getenv("TETISO_DAMAGE_CASES");
    const int n = text ? std::atoi(text) : 0;
    return n > 0 ? n : 400;
}

// Where the numbers of a file are: runs of digits (with a sign or a point)
// in its text part, the header of a binary file.
std::vector<std::pair<std::size_t, std::size_t>> numbers_in(const std::string& bytes, std::size_t text_end) {
    std::vector<std::pair<std::size_t, std::size_t>> spans;
    const auto numeric = [](char c) { return (c >= '0' && c <= '9') || c == '-' || c == '.' || c == '+'; };
    for (std::size_t i = 0; i < text_end;) {
        if (!numeric(bytes[i])) {
            ++i;
            continue;
        }
        std::size_t j = i;
        while (j < text_end && numeric(bytes[j])) ++j;
        spans.emplace_back(i, j - i);
        i = j;
    }
    return spans;
}

// One random damage to `bytes`; text_end bounds the part where numbers are
// looked for (the whole file for text formats).
std::string damage(std::string bytes, std::size_t text_end, std::mt19937_64& rng) {
    auto pick = [&](std::size_t n) { return n == 0 ? std::size_t{0} : static_cast<std::size_t>(rng() % n); };
    static const char* const kHostile[] = {"0", "-1", "2147483648", "4294967295", "100000000000000000000",
                                           "1e308", "nan", "3", "-2147483649"};
    switch (rng() % 5) {
    case 0: // cut short
        bytes.resize(pick(bytes.size()));
        break;
    case 1: // bytes overwritten
        for (std::size_t k = 1 + pick(8); k-- > 0 && !bytes.empty();) bytes[pick(bytes.size())] = static_cast<char>(rng());
        break;
    case 2: { // bytes inserted
        std::string extra(1 + pick(16), '\0');
        for (char& c : extra) c = static_cast<char>(rng());
        bytes.insert(pick(bytes.size() + 1), extra);
        break;
    }
    case 3: { // a run of bytes dropped
        const std::size_t at = pick(bytes.size());
        bytes.erase(at, 1 + pick(64));
        break;
    }
    default: { // a number replaced by a hostile one
        const auto spans = numbers_in(bytes, std::min(text_end, bytes.size()));
        if (spans.empty()) break;
        const auto [at, length] = spans[pick(spans.size())];
        bytes.replace(at, length, kHostile[pick(std::size(kHostile))]);
        break;
    }
    }
    return bytes;
}

class DamagedInputs : public ::testing::Test {
protected:
    fs::path at(const std::string& name) const { return scratch_.at(name); }

    // Runs `read` on `cases` damaged copies of the files in `originals`
    // (one of them damaged per case, written under the same names) and
    // counts how each case ended.
    // seal, if given, makes a damaged file whole again in the format's own
    // terms (a digest recomputed), so that the checks behind it are reached.
    void run(const std::string& format, const std::vector<std::pair<std::string, std::string>>& originals,
             const std::function<std::size_t(const std::string&)>& text_end, const std::function<void()>& read,
             const std::function<std::string(std::string, std::mt19937_64&)>& seal = {}) {
        std::mt19937_64 rng(0x7e7150);
        int refused = 0, accepted = 0;
        for (int c = 0; c < case_count(); ++c) {
            const std::size_t target = static_cast<std::size_t>(rng() % originals.size());
            for (std::size_t i = 0; i < originals.size(); ++i) {
                const auto& [name, bytes] = originals[i];
                std::string damaged = i == target ? damage(bytes, text_end(bytes), rng) : bytes;
                if (i == target && seal) damaged = seal(std::move(damaged), rng);
                spill(at(name), damaged);
            }
            try {
                read();
                ++accepted;
            } catch (const Error&) {
                ++refused;
            } catch (const std::exception& e) {
                ADD_FAILURE() << format << " case " << c << " (seed 0x7e7150): " << typeid(e).name() << ": " << e.what();
            }
        }
        std::printf("%s: %d damaged files, %d refused, %d read\n", format.c_str(), case_count(), refused, accepted);
        // Damage that no reader notices would make this test vacuous; damage
        // that every reader refuses would leave the accepted path untested.
        EXPECT_GT(refused, case_count() / 10) << format;
        EXPECT_GT(accepted, 0) << format;
    }

    test::ScratchDirectory scratch_{"tetiso_damage"};
};

// What every surface that reads must survive: the checker, and, for a
// manifold, a reduction that keeps each component's topology.
void check_and_reduce(const Piece& piece) {
    const TopologyReport before = check_topology(piece);
    if (!before.manifold || !before.oriented || before.non_manifold_vertices > 0) return;
    ReduceOptions options;
    options.max_error = 0.05;
    const Piece reduced = reduce(piece, options);
    const TopologyReport after = check_topology(reduced);
    EXPECT_TRUE(after.manifold && after.oriented);
    EXPECT_TRUE(same_signatures(before, after));
}

// A lattice surface of two domains, reduced so that its files carry each
// triangle's error bound (a PLY face property, a VTP cell array) for the
// damage to reach.
Piece bounded_surface(std::int64_t n, const std::string& field) {
    ReduceOptions options;
    options.max_error = 0.05;
    return reduce(test::lattice_surface(n, 2, field), options);
}

std::size_t ply_header_end(const std::string& bytes) {
    const std::size_t end = bytes.find("end_header");
    return end == std::string::npos ? bytes.size() : end;
}

TEST_F(DamagedInputs, PlyFilesAreReadOrRefused) {
    const Piece sphere = bounded_surface(8, "sphere");
    ASSERT_EQ(sphere.error.size(), sphere.triangle_count());
    write_piece(sphere, at("s.ply"));
    const std::string binary = test::read_bytes(at("s.ply"));
    run("binary PLY", {{"s.ply", binary}}, ply_header_end, [&] { check_and_reduce(read_piece(at("s.ply"))); });

    // ASCII, double coordinates, quads: the paths other tools' files take.
    std::string ascii = "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
                        "property double z\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n";
    for (int v = 0; v < 8; ++v) {
        const char corner[] = {static_cast<char>('0' + (v & 1)), ' ', static_cast<char>('0' + (v >> 1 & 1)), ' ',
                               static_cast<char>('0' + (v >> 2)), '\n', '\0'};
        ascii += corner;
    }
    ascii += "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n";
    spill(at("cube.ply"), ascii);
    ASSERT_EQ(check_topology(read_piece(at("cube.ply"))).per_component.size(), 1u);
    run("ascii PLY", {{"cube.ply", ascii}}, [](const std::string& b) { return b.size(); },
        [&] { check_and_reduce(read_piece(at("cube.ply"))); });
}

TEST_F(DamagedInputs, VtpFilesAreReadOrRefused) {
    const Piece torus = bounded_surface(10, "torus");
    ASSERT_EQ(torus.error.size(), torus.triangle_count());
    write_piece(torus, at("t.vtp"));
    const std::string bytes = test::read_bytes(at("t.vtp"));
    run("VTP", {{"t.vtp", bytes}},
        [](const std::string& b) {
            const std::size_t end = b.find("<AppendedData");
            return end == std::string::npos ? b.size() : end;
        },
        [&] { check_and_reduce(read_piece(at("t.vtp"))); });
}

TEST_F(DamagedInputs, TetgenMeshesAreReadOrRefused) {
    // A 6x6x6-node lattice written as TetGen files (numbered from 1, one
    // attribute), small enough for hundreds of cases.
    const Lattice lattice(6);
    const Decomposition one(lattice, 1);
    const auto field = make_field("sphere");
    const Domain domain = one.make_domain(0, *field);
    std::ostringstream node, ele;
    node << domain.node_count() << " 3 1 0\n";
    for (std::size_t v = 0; v < domain.node_count(); ++v)
        node << v + 1 << ' ' << domain.x[v] << ' ' << domain.y[v] << ' ' << domain.z[v] << ' ' << domain.f[v] << '\n';
    ele << domain.tet_count() << " 4 0\n";
    for (std::size_t t = 0; t < domain.tet_count(); ++t) {
        ele << t + 1;
        for (std::size_t k = 0; k < 4; ++k) ele << ' ' << domain.tets[4 * t + k] + 1;
        ele << '\n';
    }
    run("TetGen", {{"m.node", node.str()}, {"m.ele", ele.str()}}, [](const std::string& b) { return b.size(); }, [&] {
        TetgenSource source;
        source.base = at("m");
        source.attribute = 0;
        check_and_reduce(extract(read_tetgen(source), static_cast<float>(field->default_level())));
    });
}

// A split mesh: one of its files damaged, and, in half the cases, its digest
// made to fit again, as a writer with a bug would leave it, so that the
// counts, ranges and the merge tree are what must refuse it. What reads is
// then run as a job, unreduced, which every domain and seam goes through.
TEST_F(DamagedInputs, SplitMeshesAreReadOrRefused) {
    const Lattice lattice(6);
    const Decomposition one(lattice, 1);
    const auto field = make_field("sphere");
    Domain mesh = one.make_domain(0, *field);
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) part[t] = static_cast<std::int32_t>(t * 3 / part.size());
    const MeshPartition partition(std::move(mesh), part, "thirds");
    const fs::path made = at("made");
    write_mesh_split(partition, field->default_level(), made);
    std::vector<std::pair<std::string, std::string>> originals;
    for (const auto& entry : fs::directory_iterator(made))
        originals.emplace_back("split/" + entry.path().filename().string(), test::read_bytes(entry.path()));
    std::sort(originals.begin(), originals.end());
    ASSERT_EQ(originals.size(), 7u); // the index, three domain files, three edge files
    fs::create_directories(at("split"));
    const auto seal = [](std::string bytes, std::mt19937_64& rng) {
        if (rng() % 2 == 0 || bytes.size() < 8) return bytes;
        const std::uint64_t digest = split_digest(bytes.data(), bytes.size() - 8);
        std::memcpy(bytes.data() + bytes.size() - 8, &digest, 8);
        return bytes;
    };
    run("split mesh", originals, [](const std::string&) { return std::size_t{0}; }, [&] {
        JobConfig config;
        config.split = at("split");
        config.domains = 0;
        config.reduce = false;
        const Piece surface = run_local(Job(config), {}).surface;
        check_topology(surface);
    }, seal);
}

} // namespace
} // namespace tetiso
