// The GPU extraction (core/src/extract_gpu.cu) against the CPU's: the same
// piece, array for array and bit for bit (positions, keys, flags, vertex and
// triangle order), on lattice domains of every built-in field, on fields
// that take the level exactly at many nodes, on random values, on the
// unstructured cube mesh split into domains (shared-edge lists, local
// numbering out of global order), and on a node whose 14 edges all cross
// (which sends the CPU through its sorting fallback); and the same errors
// for bad domains. Where there is no CUDA device (CI) these skip, and what
// runs instead checks that asking for the GPU is a clear error.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

#define SKIP_WITHOUT_GPU()                                                        \
    do {                                                                          \
        const GpuInfo info = gpu_info();                                          \
        if (!info.available) GTEST_SKIP() << "no GPU: " << info.description;      \
    } while (false)

// Extraction on one GPU for the whole program: its buffers then serve
// domains of every size in turn, which is how a worker uses it.
struct GpuExtraction {
    Device device = Device::cuda();
    Piece extract(const Domain& domain, float level) const {
        return tetiso::extract(domain, level, ExtractOptions{1, device});
    }
    // A lattice domain as a domain task makes it on the GPU: built on the
    // device, a built-in field evaluated there, an expression's values uploaded.
    Piece extract(const LatticePartition& lattice, int domain, float level) const {
        DomainTaskOptions task;
        task.level = level;
        task.device = device;
        return run_domain_task(lattice, domain, task).piece;
    }
};

const GpuExtraction& gpu() {
    static const GpuExtraction extraction;
    return extraction;
}

template <class T>
std::optional<std::size_t> first_difference(const std::vector<T>& a, const std::vector<T>& b) {
    if (a.size() != b.size()) return std::min(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        if constexpr (std::is_same_v<T, float>) {
            if (std::bit_cast<std::uint32_t>(a[i]) != std::bit_cast<std::uint32_t>(b[i])) return i;
        } else if (a[i] != b[i]) {
            return i;
        }
    }
    return std::nullopt;
}

// Every array equal, in order; the failure names the first difference.
::testing::AssertionResult identical(const Piece& cpu, const Piece& gpu) {
    auto differs = [](const char* what, std::size_t at, std::size_t n_cpu, std::size_t n_gpu) {
        return ::testing::AssertionFailure() << what << " differ at " << at << " (sizes: CPU " << n_cpu << ", GPU "
                                             << n_gpu << ")";
    };
    if (auto at = first_difference(cpu.key, gpu.key)) return differs("keys", *at, cpu.key.size(), gpu.key.size());
    if (auto at = first_difference(cpu.x, gpu.x)) return differs("x", *at, cpu.x.size(), gpu.x.size());
    if (auto at = first_difference(cpu.y, gpu.y)) return differs("y", *at, cpu.y.size(), gpu.y.size());
    if (auto at = first_difference(cpu.z, gpu.z)) return differs("z", *at, cpu.z.size(), gpu.z.size());
    if (auto at = first_difference(cpu.flags, gpu.flags))
        return differs("flags", *at, cpu.flags.size(), gpu.flags.size());
    if (auto at = first_difference(cpu.triangles, gpu.triangles))
        return differs("triangle corners", *at, cpu.triangles.size(), gpu.triangles.size());
    if (cpu.domains != gpu.domains) return ::testing::AssertionFailure() << "domain lists differ";
    return ::testing::AssertionSuccess() << cpu.vertex_count() << " vertices, " << cpu.triangle_count()
                                         << " triangles";
}

struct LatticeCase {
    const char* field;
    std::optional<double> level;
    std::int64_t n;
    int domains;
};

void PrintTo(const LatticeCase& c, std::ostream* out) {
    *out << c.field << " N=" << c.n << " D=" << c.domains;
}

class GpuLattice : public ::testing::TestWithParam<LatticeCase> {};

TEST_P(GpuLattice, EveryDomainIsTheCpuPieceBitForBit) {
    SKIP_WITHOUT_GPU();
    const LatticeCase& c = GetParam();
    const LatticePartition partition(c.n, c.domains, make_field(c.field));
    const Decomposition& decomposition = partition.decomposition();
    const Field* field = &partition.field();
    const auto level = static_cast<float>(c.level.value_or(field->default_level()));
    std::size_t triangles = 0;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const Domain domain = decomposition.make_domain(d, *field);
        const Piece cpu = extract(domain, level);
        triangles += cpu.triangle_count();
        EXPECT_TRUE(identical(cpu, gpu().extract(domain, level))) << "domain " << d;
        // The lattice path: the domain built on the device, a built-in field
        // evaluated there, an expression's values uploaded.
        EXPECT_TRUE(identical(cpu, gpu().extract(partition, d, level)))
            << "domain " << d << ", built on the device";
    }
    EXPECT_GT(triangles, 0u); // the case has a surface to compare
}

INSTANTIATE_TEST_SUITE_P(Fields, GpuLattice,
                         ::testing::Values(LatticeCase{"sphere", std::nullopt, 41, 8},
                                           LatticeCase{"torus", std::nullopt, 40, 27},
                                           LatticeCase{"gyroid", std::nullopt, 50, 8},
                                           LatticeCase{"paper", std::nullopt, 60, 27},
                                           LatticeCase{"paper", std::nullopt, 100, 1},
                                           // The level taken exactly at every node of a plane.
                                           LatticeCase{"x-2.5", 0.0, 11, 8},
                                           LatticeCase{"x+y-5", 0.0, 21, 5}));

// The lattice's connectivity with random values, a tenth of them exactly at
// the level: every case pattern and every tie.
TEST(Gpu, RandomValuesGiveTheCpuPiece) {
    SKIP_WITHOUT_GPU();
    const Lattice lattice(24);
    const Decomposition one(lattice, 1);
    Domain domain = one.make_domain(0, *make_field("paper"));
    for (unsigned seed = 1; seed <= 5; ++seed) {
        std::mt19937 random(seed);
        std::uniform_real_distribution<float> value(-1.0f, 1.0f);
        const float level = seed == 1 ? 0.0f : value(random) * 0.5f;
        for (float& f : domain.f) f = random() % 10 == 0 ? level : value(random);
        EXPECT_TRUE(identical(extract(domain, level), gpu().extract(domain, level))) << "seed " << seed;
    }
}

// Local numbering out of global order, as a general mesh has: the GPU must
// reorder by key as the CPU does, and take the CPU's fallback's numbering
// where one node has more crossing neighbours than a bucket holds.
TEST(Gpu, NodesInAnyOrderGiveTheCpuPiece) {
    SKIP_WITHOUT_GPU();
    const Lattice lattice(16);
    const Decomposition one(lattice, 1);
    const Domain gyroid = one.make_domain(0, *make_field("gyroid"));
    std::vector<std::int32_t> order(gyroid.node_count());
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 random(7);
    std::shuffle(order.begin(), order.end(), random);
    const Domain shuffled = test::renumbered(gyroid, order);
    EXPECT_TRUE(identical(extract(shuffled, 0.0f), gpu().extract(shuffled, 0.0f)));

    // A tiny sphere around one node, numbered first: its 14 edges all cross.
    const Domain dot = one.make_domain(0, *make_field("sqrt((x-2)^2+(y-2)^2+(z-2)^2)"));
    const auto level = static_cast<float>(0.5 * lattice.spacing());
    std::iota(order.begin(), order.end(), 0);
    std::swap(order[0], order[static_cast<std::size_t>(std::min_element(dot.f.begin(), dot.f.end()) - dot.f.begin())]);
    const Domain crowded = test::renumbered(dot, order);
    const Piece cpu = extract(crowded, level);
    EXPECT_EQ(cpu.vertex_count(), 14u);
    EXPECT_TRUE(identical(cpu, gpu().extract(crowded, level)));
}

// The unstructured cube mesh in 8 domains by the octant of each
// tetrahedron's centroid: interface vertices are locked through the shared
// edge lists, and local numbering is not global.
TEST(Gpu, UnstructuredDomainsGiveTheCpuPieces) {
    SKIP_WITHOUT_GPU();
    const auto field = make_field("sphere");
    Domain mesh = read_tetgen(TetgenSource{std::filesystem::path(TETISO_MESHES_DIR) / "cube.1", std::nullopt,
                                           field.get()});
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) {
        int octant = 0;
        for (int axis = 0; axis < 3; ++axis) {
            double centre = 0.0;
            for (int k = 0; k < 4; ++k) {
                const auto v = static_cast<std::size_t>(mesh.tets[4 * t + static_cast<std::size_t>(k)]);
                centre += axis == 0 ? mesh.x[v] : (axis == 1 ? mesh.y[v] : mesh.z[v]);
            }
            octant |= (centre / 4 > 2.5 ? 1 : 0) << axis;
        }
        part[t] = octant;
    }
    const MeshPartition partition(std::move(mesh), part, "octants");
    std::size_t locked = 0;
    for (const float level : {2.0f, 1.0f}) {
        for (int d = 0; d < partition.domain_count(); ++d) {
            const Domain domain = partition.make_domain(d);
            const Piece cpu = extract(domain, level);
            locked += static_cast<std::size_t>(std::count(cpu.flags.begin(), cpu.flags.end(), kLocked));
            EXPECT_TRUE(identical(cpu, gpu().extract(domain, level))) << "domain " << d << ", level " << level;
        }
    }
    EXPECT_GT(locked, 0u); // the interfaces were crossed
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(Gpu, BadDomainsGiveTheCpuErrors) {
    SKIP_WITHOUT_GPU();
    const Lattice lattice(6);
    const Decomposition two(lattice, 2);
    const Domain domain = two.make_domain(1, *make_field("paper"));
    Domain nan = domain;
    nan.f[5] = std::numeric_limits<float>::quiet_NaN();
    nan.f[9] = std::numeric_limits<float>::infinity();
    Domain dangling = domain;
    dangling.tets[4 * 30 + 2] = static_cast<std::int32_t>(domain.node_count());
    dangling.tets[4 * 77 + 1] = -3;
    Domain ragged = domain;
    ragged.f.pop_back();
    for (const Domain* bad : {&nan, &dangling, &ragged}) {
        const std::string cpu = error_of([&] { extract(*bad, 0.5f); });
        EXPECT_NE(cpu, "(no error)");
        EXPECT_EQ(cpu, error_of([&] { gpu().extract(*bad, 0.5f); }));
    }
    EXPECT_EQ(error_of([&] { extract(domain, std::numeric_limits<float>::infinity()); }),
              error_of([&] { gpu().extract(domain, std::numeric_limits<float>::infinity()); }));
    // A failed call leaves the extractor usable.
    EXPECT_TRUE(identical(extract(domain, 0.5f), gpu().extract(domain, 0.5f)));
}

TEST(Gpu, BadLatticeValuesGiveTheCpuErrors) {
    SKIP_WITHOUT_GPU();
    // Infinite on the plane x = 2.5, which holds lattice nodes.
    const LatticePartition four(11, 4, make_field("1/(x-2.5)"));
    for (int d = 0; d < four.domain_count(); ++d) {
        const std::string cpu = error_of([&] { extract(four.make_domain(d), 0.5f); });
        EXPECT_EQ(cpu, error_of([&] { gpu().extract(four, d, 0.5f); })) << d;
    }
}

TEST(Gpu, EmptyDomainsAndLevelsOutsideTheRangeGiveEmptyPieces) {
    SKIP_WITHOUT_GPU();
    const Lattice lattice(8);
    const Decomposition one(lattice, 1);
    const Domain domain = one.make_domain(0, *make_field("sphere"));
    const Piece outside = gpu().extract(domain, 100.0f);
    EXPECT_EQ(outside.vertex_count(), 0u);
    EXPECT_EQ(outside.triangle_count(), 0u);
    Domain no_tets = domain;
    no_tets.tets.clear();
    EXPECT_TRUE(identical(extract(no_tets, 2.0f), gpu().extract(no_tets, 2.0f)));
    Domain nothing;
    EXPECT_TRUE(identical(extract(nothing, 2.0f), gpu().extract(nothing, 2.0f)));
}

// What CI sees: no device, and a clear error for whoever asks for one.
TEST(Gpu, WithoutADeviceAskingForOneIsAClearError) {
    const GpuInfo info = gpu_info();
    if (info.available) GTEST_SKIP() << "a GPU is present: " << info.description;
    EXPECT_FALSE(info.description.empty());
    const std::string message = error_of([] { Device::cuda(); });
    EXPECT_EQ(message.rfind("GPU: ", 0), 0u) << message;
}

} // namespace
} // namespace tetiso
