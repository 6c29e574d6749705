// A job's work on the GPU against the CPU's, byte for byte: lattice domains
// of every built-in field and of an expression built on the device and
// extracted, or taken from nothing to their reduced piece with its
// interfaces locked and its samples kept; random values; an unstructured
// mesh's domains; the reductions of seams' regions (pieces that carry error
// bounds and raw-vertex samples); whole jobs with their domain tasks on the
// GPU; and bad domains' errors. Skips where there is no GPU. (Extraction of
// domains uploaded from the host: test_extract built for the GPU.)
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "reduce_under_test.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

using test::same_piece;
using test::the_gpu;
using test::error_of;

ReduceOptions domain_options(double spacing, double bound = 0.25) {
    ReduceOptions o;
    o.max_error = bound * spacing;
    o.keep_samples = true;
    return o;
}

// A domain's task on the GPU, extraction and reduction, as the job runs it.
Piece gpu_task(Domain domain, float level, const ReduceOptions& o) {
    DomainTaskOptions task;
    task.level = level;
    task.device = the_gpu();
    task.reduce = o;
    return run_domain_task(std::move(domain), task).piece;
}

Piece gpu_task(const LatticePartition& lattice, int domain, float level, const ReduceOptions& o) {
    DomainTaskOptions task;
    task.level = level;
    task.device = the_gpu();
    task.reduce = o;
    return run_domain_task(lattice, domain, task).piece;
}

struct LatticeCase {
    const char* field;
    std::int64_t n;
    int domains;
    double bound; // in spacings; 0: none
};

void PrintTo(const LatticeCase& c, std::ostream* out) {
    *out << c.field << " N=" << c.n << " D=" << c.domains << " bound " << c.bound;
}

class GpuDomainTask : public ::testing::TestWithParam<LatticeCase> {};

// A domain task as the job runs it: the GPU builds the domain, evaluates a
// built-in field (an expression's values are uploaded), extracts and
// reduces, and only the piece comes back.
TEST_P(GpuDomainTask, IsTheCpuPieceByteForByte) {
    const LatticeCase& c = GetParam();
    const LatticePartition partition(c.n, c.domains, make_field(c.field));
    const Lattice& lattice = partition.lattice();
    const Decomposition& decomposition = partition.decomposition();
    const Field* field = &partition.field();
    const auto level = static_cast<float>(field->default_level());
    const ReduceOptions o = domain_options(lattice.spacing(), c.bound);
    std::size_t locked = 0, reduced = 0;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        const Piece raw = extract(decomposition.make_domain(d, *field), level);
        const Piece cpu = reduce(raw, o);
        locked += static_cast<std::size_t>(std::count(cpu.flags.begin(), cpu.flags.end(), kLocked));
        reduced += raw.triangle_count() - cpu.triangle_count();
        EXPECT_TRUE(same_piece(cpu, gpu_task(partition, d, level, o))) << "domain " << d;
    }
    EXPECT_GT(reduced, 0u);
    if (c.domains > 1) {
        EXPECT_GT(locked, 0u); // the interfaces were crossed and stayed
    }
}

INSTANTIATE_TEST_SUITE_P(Fields, GpuDomainTask,
                         ::testing::Values(LatticeCase{"paper", 60, 8, 0.25}, LatticeCase{"paper", 48, 1, 0.0},
                                           LatticeCase{"gyroid", 50, 27, 0.25}, LatticeCase{"sphere", 41, 8, 0.1},
                                           LatticeCase{"torus", 40, 27, 0.25}, LatticeCase{"x+y-5", 21, 5, 0.25}));

// A lattice domain's extraction alone as a task runs it on the GPU: the
// domain built on the device, a built-in field evaluated there, an
// expression's values uploaded.
Piece gpu_extraction(const LatticePartition& lattice, int domain, float level) {
    DomainTaskOptions task;
    task.level = level;
    task.device = the_gpu();
    return run_domain_task(lattice, domain, task).piece;
}

struct ExtractCase {
    const char* field;
    std::optional<double> level;
    std::int64_t n;
    int domains;
};

void PrintTo(const ExtractCase& c, std::ostream* out) { *out << c.field << " N=" << c.n << " D=" << c.domains; }

class GpuLattice : public ::testing::TestWithParam<ExtractCase> {};

TEST_P(GpuLattice, EveryDomainIsTheCpuPieceBitForBit) {
    const ExtractCase& c = GetParam();
    const LatticePartition partition(c.n, c.domains, make_field(c.field));
    const auto level = static_cast<float>(c.level.value_or(partition.field().default_level()));
    std::size_t triangles = 0;
    for (int d = 0; d < partition.domain_count(); ++d) {
        const Piece cpu = extract(partition.make_domain(d), level);
        triangles += cpu.triangle_count();
        EXPECT_TRUE(same_piece(cpu, gpu_extraction(partition, d, level))) << "domain " << d;
    }
    EXPECT_GT(triangles, 0u); // the case has a surface to compare
}

INSTANTIATE_TEST_SUITE_P(Fields, GpuLattice,
                         ::testing::Values(ExtractCase{"sphere", std::nullopt, 41, 8},
                                           ExtractCase{"torus", std::nullopt, 40, 27},
                                           ExtractCase{"gyroid", std::nullopt, 50, 8},
                                           ExtractCase{"paper", std::nullopt, 60, 27},
                                           ExtractCase{"paper", std::nullopt, 100, 1},
                                           // The level taken exactly at every node of a plane.
                                           ExtractCase{"x-2.5", 0.0, 11, 8}, ExtractCase{"x+y-5", 0.0, 21, 5}));

TEST(GpuPipeline, BadLatticeValuesGiveTheCpuErrors) {
    // Infinite on the plane x = 2.5, which holds lattice nodes.
    const LatticePartition four(11, 4, make_field("1/(x-2.5)"));
    for (int d = 0; d < four.domain_count(); ++d) {
        const std::string cpu = error_of([&] { extract(four.make_domain(d), 0.5f); });
        EXPECT_EQ(cpu, error_of([&] { gpu_extraction(four, d, 0.5f); })) << d;
    }
}

// Random values, a tenth of them exactly at the level: needles, zero-length
// edges and clusters the reducer must clean up, on both devices alike.
TEST(GpuPipeline, RandomValuesGiveTheCpuPiece) {
    const Lattice lattice(20);
    const Decomposition two(lattice, 2);
    Domain domain = two.make_domain(1, *make_field("paper"));
    for (unsigned seed = 1; seed <= 4; ++seed) {
        std::mt19937 random(seed);
        std::uniform_real_distribution<float> value(-1.0f, 1.0f);
        const float level = seed == 1 ? 0.0f : value(random) * 0.5f;
        for (float& f : domain.f) f = random() % 10 == 0 ? level : value(random);
        const ReduceOptions o = domain_options(lattice.spacing());
        EXPECT_TRUE(same_piece(reduce(extract(domain, level), o), gpu_task(domain, level, o)))
            << "seed " << seed;
    }
}

// The unstructured cube mesh by the octant of each tetrahedron: shared-edge
// lists lock the interfaces, and local numbering is not global.
TEST(GpuPipeline, UnstructuredDomainsGiveTheCpuPieces) {
    const auto field = make_field("sphere");
    Domain mesh =
        read_tetgen(TetgenSource{std::filesystem::path(TETISO_MESHES_DIR) / "cube.1", std::nullopt, field.get()});
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) {
        double centre = 0.0;
        for (int k = 0; k < 4; ++k) centre += mesh.x[static_cast<std::size_t>(mesh.tets[4 * t + static_cast<std::size_t>(k)])];
        part[t] = centre / 4 > 2.5 ? 1 : 0;
    }
    const double spacing = mean_edge_length(mesh);
    const MeshPartition partition(std::move(mesh), part, "halves");
    const ReduceOptions o = domain_options(spacing);
    for (int d = 0; d < partition.domain_count(); ++d) {
        const Domain domain = partition.make_domain(d);
        std::string cpu_error;
        Piece cpu;
        try {
            cpu = reduce(extract(domain, 1.5f), o);
        } catch (const Error& e) {
            cpu_error = e.what();
        }
        Piece gpu;
        const std::string gpu_error = error_of([&] { gpu = gpu_task(domain, 1.5f, o); });
        EXPECT_EQ(cpu_error.empty() ? "(no error)" : cpu_error, gpu_error) << "domain " << d;
        if (cpu_error.empty()) {
            EXPECT_TRUE(same_piece(cpu, gpu)) << "domain " << d;
        }
    }
}

// Seams: each region a seam reduces (error bounds, the raw vertices the
// pieces kept, a locked rim) reduced on both devices.
TEST(GpuPipeline, SeamRegionsGiveTheCpuPieces) {
    const Lattice lattice(50);
    const Decomposition decomposition(lattice, 8);
    const auto field = make_field("gyroid");
    const auto level = static_cast<float>(field->default_level());
    const ReduceOptions o = domain_options(lattice.spacing());
    std::vector<Piece> pieces;
    for (int d = 0; d < decomposition.domain_count(); ++d) {
        Piece piece = reduce(extract(decomposition.make_domain(d, *field), level), o);
        keep_samples_near_locked(piece, 1);
        pieces.push_back(std::move(piece));
    }
    int regions = 0;
    std::size_t carried = 0;
    SeamOptions options;
    options.reduce_options = o;
    options.reducer = [&](const Piece& region, const ReduceOptions& ro, ReduceReport* report) {
        ++regions;
        carried += region.sample_count();
        return test::reduce_under_test(region, ro, report); // the GPU's checked against the CPU's
    };
    const auto domains_of_edge = [&](GlobalId a, GlobalId b) { return decomposition.domains_of_edge(a, b); };
    // Along the bisection tree: every seam joins two adjacent pieces.
    std::function<Piece(int)> seam_node = [&](int node) -> Piece {
        const DomainTreeNode& n = decomposition.tree()[static_cast<std::size_t>(node)];
        if (n.left < 0) return pieces[static_cast<std::size_t>(n.first)];
        return seam(seam_node(n.left), seam_node(n.right), domains_of_edge, options);
    };
    const Piece whole = seam_node(0);
    EXPECT_EQ(regions, 7);
    EXPECT_GT(carried, 0u); // the regions carried raw vertices to measure again
    EXPECT_GT(whole.triangle_count(), 0u);
}

// A seam task given a GPU (rank 0 gives its last seams one) reduces its
// region there: each is the seam the cores make, byte for byte.
TEST(GpuPipeline, SeamTasksOnTheGpuGiveTheCpuSeams) {
    JobConfig config;
    config.lattice = 48;
    config.domains = 8;
    config.field = "gyroid";
    const Job job(config);
    std::vector<std::optional<Piece>> pieces(static_cast<std::size_t>(job.task_count()));
    TaskQueue queue(job);
    int seams = 0;
    while (!queue.finished()) {
        const int t = queue.pop();
        const TaskNode& n = job.node(t);
        const Piece* left = n.left >= 0 ? &*pieces[static_cast<std::size_t>(n.left)] : nullptr;
        const Piece* right = n.right >= 0 ? &*pieces[static_cast<std::size_t>(n.right)] : nullptr;
        TaskRecord record;
        Piece cpu = job.execute(t, left, right, record, TaskThreads{2, {}, -1});
        if (job.kind(t) == TaskKind::seam) {
            TaskRecord on_gpu;
            const Piece gpu = job.execute(t, left, right, on_gpu, TaskThreads{2, {}, 0});
            EXPECT_TRUE(same_piece(cpu, gpu)) << job.describe(t);
            EXPECT_EQ(on_gpu.stages.gpu, 0);
            EXPECT_EQ(record.stages.gpu, -1);
            ++seams;
        }
        pieces[static_cast<std::size_t>(t)] = std::move(cpu);
        queue.complete(t);
    }
    EXPECT_EQ(seams, 7);
}

// The job with its domain tasks on the GPU, its grants on one stream or
// several, writes the CPU job's surface.
TEST(GpuPipeline, JobsOnTheGpuGiveTheCpuSurface) {
    for (const auto& [field, n, domains] : {std::tuple{"paper", 60, 8}, std::tuple{"torus", 44, 27}}) {
        JobConfig config;
        config.lattice = n;
        config.domains = domains;
        config.field = field;
        const JobResult cpu = run_local(Job(config), {});
        config.device = JobConfig::Device::gpu;
        for (const int streams : {1, 3}) {
            config.gpu_streams = streams;
            const JobResult gpu = run_local(Job(config), {});
            EXPECT_TRUE(same_piece(cpu.surface, gpu.surface)) << field << ", " << streams << " streams";
            std::size_t on_gpu = 0;
            for (const TaskRecord& t : gpu.tasks) on_gpu += t.stages.gpu >= 0;
            EXPECT_EQ(on_gpu, static_cast<std::size_t>(domains)) << "every domain task, no seam, ran on the GPU";
        }
    }
}

// A domain whose node has no finite position: extracted, then refused by the
// reduction's input check, with the CPU's message.
TEST(GpuPipeline, BadDomainGivesTheCpuError) {
    const Lattice lattice(12);
    const Decomposition one(lattice, 1);
    const auto field = make_field("sphere");
    Domain domain = one.make_domain(0, *field);
    // A node next to the sphere, so that its edges cross.
    std::size_t near = 0;
    for (std::size_t v = 0; v < domain.f.size(); ++v)
        if (std::abs(domain.f[v] - 2.0f) < std::abs(domain.f[near] - 2.0f)) near = v;
    domain.x[near] = std::numeric_limits<float>::infinity();
    const ReduceOptions o = domain_options(lattice.spacing());
    const std::string cpu = error_of([&] { reduce(extract(domain, 2.0f), o); });
    EXPECT_NE(cpu, "(no error)");
    EXPECT_EQ(cpu, error_of([&] { gpu_task(domain, 2.0f, o); }));
    // The GPU stays usable.
    const Domain good = one.make_domain(0, *field);
    EXPECT_TRUE(same_piece(reduce(extract(good, 2.0f), o), gpu_task(good, 2.0f, o)));
}

} // namespace
} // namespace tetiso
