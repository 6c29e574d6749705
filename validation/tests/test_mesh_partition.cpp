// An unstructured mesh split into domains by a domain id per tetrahedron
// (core/src/mesh_partition.cpp) and the job over it: every tetrahedron in
// exactly one domain, the shared edges and their holders as a brute-force
// count over the domains finds them, a merge tree that joins adjacent
// domains, and the job's surface equal to the whole mesh's extraction
// (unreduced) or of its topology (reduced), for partitions made here
// independently of METIS: octants, a 3 x 3 x 3 grid and a scatter in which
// every domain is hundreds of pieces. The same partitions written as one
// file per domain (core/src/mesh_split.cpp) give the same domains and the
// same job surface, bit for bit, and damaged files are refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>

#include "test_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/mesh_partition.hpp"
#include "tetiso/mesh_split.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {
namespace {

const std::filesystem::path kCube = std::filesystem::path(TETISO_MESHES_DIR) / "cube.1";

Domain cube(const Field& field) { return read_tetgen(TetgenSource{kCube, std::nullopt, &field}); }

std::array<double, 3> centroid(const Domain& mesh, std::size_t t) {
    std::array<double, 3> c{};
    for (int k = 0; k < 4; ++k) {
        const auto v = static_cast<std::size_t>(mesh.tets[4 * t + static_cast<std::size_t>(k)]);
        c[0] += mesh.x[v] / 4.0;
        c[1] += mesh.y[v] / 4.0;
        c[2] += mesh.z[v] / 4.0;
    }
    return c;
}

// Domain ids by the cell of a g x g x g grid over [0,5]^3 holding each
// tetrahedron's centroid, numbered against the grid's order so that the
// partition's renumbering has work to do.
std::vector<std::int32_t> grid_partition(const Domain& mesh, int g) {
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) {
        const auto c = centroid(mesh, t);
        int cell = 0;
        for (int axis = 2; axis >= 0; --axis)
            cell = cell * g + std::clamp(static_cast<int>(c[static_cast<std::size_t>(axis)] / 5.0 * g), 0, g - 1);
        part[t] = g * g * g - 1 - cell;
    }
    return part;
}

// Every domain a scatter of single tetrahedra: nearly every edge is shared,
// and each domain's surface is hundreds of open fragments.
std::vector<std::int32_t> scattered_partition(const Domain& mesh, int domains) {
    std::vector<std::int32_t> part(mesh.tet_count());
    for (std::size_t t = 0; t < part.size(); ++t) part[t] = static_cast<std::int32_t>((t * 2654435761u >> 7) % static_cast<std::size_t>(domains));
    return part;
}

struct Case {
    const char* name;
    std::vector<std::int32_t> (*make)(const Domain&);
};

const Case kCases[] = {
    {"octants", [](const Domain& m) { return grid_partition(m, 2); }},
    {"grid27", [](const Domain& m) { return grid_partition(m, 3); }},
    {"scattered5", [](const Domain& m) { return scattered_partition(m, 5); }},
};

void PrintTo(const Case& c, std::ostream* out) { *out << c.name; }

class MeshPartitionCase : public ::testing::TestWithParam<Case> {};

using Tet = std::array<GlobalId, 4>;

Tet sorted_tet(const Domain& d, std::size_t t) {
    Tet out;
    for (int k = 0; k < 4; ++k) out[static_cast<std::size_t>(k)] = d.gid[static_cast<std::size_t>(d.tets[4 * t + static_cast<std::size_t>(k)])];
    std::sort(out.begin(), out.end());
    return out;
}

TEST_P(MeshPartitionCase, DomainsCoverTheMeshAndKnowTheirSharedEdges) {
    const auto field = make_field("sphere");
    const Domain whole = cube(*field);
    const std::vector<std::int32_t> part = GetParam().make(whole);
    const MeshPartition partition(whole, part, GetParam().name);
    const int domains = partition.domain_count();
    ASSERT_EQ(domains, *std::max_element(part.begin(), part.end()) + 1);

    // Every tetrahedron in exactly one domain, and the domain's nodes carry
    // the whole mesh's positions and values.
    std::multiset<Tet> all, covered;
    for (std::size_t t = 0; t < whole.tet_count(); ++t) all.insert(sorted_tet(whole, t));
    std::map<EdgeKey, std::set<int>> holders; // brute force: who holds each edge
    std::int64_t tets = 0;
    for (int d = 0; d < domains; ++d) {
        const Domain domain = partition.make_domain(d);
        EXPECT_EQ(static_cast<std::int64_t>(domain.tet_count()), partition.domain_tet_count(d));
        tets += partition.domain_tet_count(d);
        for (std::size_t v = 0; v < domain.node_count(); ++v) {
            const auto g = static_cast<std::size_t>(domain.gid[v]);
            ASSERT_EQ(domain.x[v], whole.x[g]);
            ASSERT_EQ(domain.f[v], whole.f[g]);
        }
        for (std::size_t t = 0; t < domain.tet_count(); ++t) {
            const Tet tet = sorted_tet(domain, t);
            covered.insert(tet);
            for (int a = 0; a < 4; ++a)
                for (int b = a + 1; b < 4; ++b) holders[edge_key(tet[static_cast<std::size_t>(a)], tet[static_cast<std::size_t>(b)])].insert(d);
        }
    }
    EXPECT_EQ(tets, static_cast<std::int64_t>(whole.tet_count()));
    EXPECT_TRUE(all == covered) << "the domains' tetrahedra are not the mesh's";

    // Holders and neighbours as the brute-force count finds them.
    std::vector<std::set<int>> neighbours(static_cast<std::size_t>(domains));
    std::vector<std::vector<EdgeKey>> shared(static_cast<std::size_t>(domains));
    std::size_t wrong = 0;
    for (const auto& [key, set] : holders) {
        const std::vector<int> expected(set.begin(), set.end());
        wrong += partition.domains_of_edge(edge_key_low(key), edge_key_high(key)) == expected ? 0 : 1;
        if (set.size() > 1)
            for (const int d : set) {
                shared[static_cast<std::size_t>(d)].push_back(key);
                for (const int e : set)
                    if (e != d) neighbours[static_cast<std::size_t>(d)].insert(e);
            }
    }
    EXPECT_EQ(wrong, 0u) << "edges whose holders domains_of_edge gets wrong";
    for (int d = 0; d < domains; ++d) {
        const auto& n = partition.neighbours(d);
        EXPECT_EQ(std::set<int>(n.begin(), n.end()), neighbours[static_cast<std::size_t>(d)]) << "domain " << d;
        EXPECT_EQ(partition.make_domain(d).shared_edges, shared[static_cast<std::size_t>(d)]) << "domain " << d;
    }

    // The tree: the root covers every domain, each inner node's children
    // split its range and share an edge.
    const auto& tree = partition.tree();
    ASSERT_EQ(tree.size(), static_cast<std::size_t>(2 * domains - 1));
    EXPECT_EQ(tree[0].first, 0);
    EXPECT_EQ(tree[0].count, domains);
    for (std::size_t i = 0; i < tree.size(); ++i) {
        const DomainTreeNode& n = tree[i];
        if (n.left < 0) {
            EXPECT_EQ(n.count, 1);
            continue;
        }
        ASSERT_GT(n.left, static_cast<int>(i));
        ASSERT_GT(n.right, static_cast<int>(i));
        const DomainTreeNode& l = tree[static_cast<std::size_t>(n.left)];
        const DomainTreeNode& r = tree[static_cast<std::size_t>(n.right)];
        EXPECT_EQ(l.first, n.first);
        EXPECT_EQ(r.first, l.first + l.count);
        EXPECT_EQ(l.count + r.count, n.count);
        bool adjacent = false;
        for (int a = l.first; a < l.first + l.count && !adjacent; ++a)
            for (const int b : partition.neighbours(a)) adjacent = adjacent || (b >= r.first && b < r.first + r.count);
        EXPECT_TRUE(adjacent) << "tree node " << i << " joins domains that share no edge";
    }
}

JobConfig mesh_job(const std::string& field, bool reduce, int threads = 1) {
    JobConfig config;
    config.mesh = kCube;
    config.field = field;
    config.reduce = reduce;
    config.threads = threads;
    return config;
}

// A partition file in a scratch directory, removed with the object.
struct PartitionFile {
    std::filesystem::path path;
    PartitionFile(const std::vector<std::int32_t>& part, const std::string& name)
        : path(std::filesystem::temp_directory_path() /
               ("tetiso_partition_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" + name)) {
        std::ofstream out(path);
        for (const std::int32_t p : part) out << p << '\n';
    }
    ~PartitionFile() { std::filesystem::remove(path); }
};

// Unreduced, the seamed pieces are the whole mesh's surface: the same
// vertices, bit for bit, no lock left, the same triangles.
TEST_P(MeshPartitionCase, SeamedUnreducedSurfaceIsTheWholeMeshsExtraction) {
    for (const char* field : {"sphere", "torus", "gyroid"}) {
        SCOPED_TRACE(field);
        const auto f = make_field(field);
        const Domain whole = cube(*f);
        const Piece expected = extract(whole, static_cast<float>(f->default_level()));
        const PartitionFile file(GetParam().make(whole), GetParam().name);
        JobConfig config = mesh_job(field, false);
        config.partition = file.path;
        config.domains = 0;
        const Piece out = run_local(Job(config), {}).surface;
        ASSERT_GT(out.triangle_count(), 100u);
        EXPECT_TRUE(test::same_surface(out, expected));
    }
}

// Reduced, the surface keeps the whole mesh's topology, within half a
// spacing, and comes out the same for one thread and two.
TEST_P(MeshPartitionCase, ReducedSurfaceKeepsTheTopologyForAnyThreadCount) {
    for (const char* field : {"sphere", "torus", "gyroid"}) {
        SCOPED_TRACE(field);
        const auto f = make_field(field);
        const Domain whole = cube(*f);
        const Piece raw = extract(whole, static_cast<float>(f->default_level()));
        const PartitionFile file(GetParam().make(whole), GetParam().name);
        JobConfig config = mesh_job(field, true);
        config.partition = file.path;
        config.domains = 0;
        const Job job(config);
        const Piece out = run_local(job, {}).surface;
        config.threads = 2;
        const Piece two = run_local(Job(config), {}).surface;
        EXPECT_TRUE(out.key == two.key && test::same_bits(out.x, two.x) && out.triangles == two.triangles)
            << "1 and 2 threads differ";

        const TopologyReport before = check_topology(raw), after = check_topology(out);
        EXPECT_TRUE(same_signatures(before, after));
        EXPECT_TRUE(after.manifold);
        EXPECT_TRUE(after.oriented);
        // The gyroid meets the cube's edges at nodes, where extraction makes
        // zero-area triangles (79 on this mesh); none may survive, in the
        // domains or at the seams.
        EXPECT_EQ(after.degenerate_triangles, 0);
        EXPECT_LT(out.triangle_count(), raw.triangle_count());
        EXPECT_TRUE(std::none_of(out.flags.begin(), out.flags.end(), [](std::uint8_t f) { return f & kLocked; }));
        const double h = job.partition().spacing();
        EXPECT_NEAR(h, mean_edge_length(whole), 1e-12);
        EXPECT_LE(hausdorff(raw, out).symmetric, 0.5 * h);
    }
}

// Written as one file per domain and read back, a partition is the same in
// everything a job reads, and the job over the split comes out bit for bit
// as the job over the whole mesh.
TEST_P(MeshPartitionCase, SplitIntoFilesIsTheSamePartitionAndJob) {
    const test::ScratchDirectory scratch("tetiso_split");
    const auto field = make_field("torus");
    const Domain whole = cube(*field);
    const std::vector<std::int32_t> part = GetParam().make(whole);
    const MeshPartition partition(whole, part, GetParam().name);
    const std::filesystem::path dir = scratch.at("split");
    write_mesh_split(partition, field->default_level(), dir);
    const SplitMeshPartition split(dir);

    ASSERT_EQ(split.domain_count(), partition.domain_count());
    EXPECT_EQ(split.node_count(), partition.node_count());
    EXPECT_EQ(split.tet_count(), partition.tet_count());
    EXPECT_EQ(split.spacing(), partition.spacing());
    EXPECT_EQ(split.fingerprint(), partition.fingerprint());
    EXPECT_EQ(split.default_level(), field->default_level());
    ASSERT_EQ(split.tree().size(), partition.tree().size());
    for (std::size_t i = 0; i < split.tree().size(); ++i) {
        const DomainTreeNode &a = split.tree()[i], &b = partition.tree()[i];
        EXPECT_TRUE(a.first == b.first && a.count == b.count && a.left == b.left && a.right == b.right) << "tree node " << i;
    }
    std::size_t shared = 0;
    for (int d = 0; d < split.domain_count(); ++d) {
        SCOPED_TRACE(d);
        EXPECT_EQ(split.neighbours(d), partition.neighbours(d));
        EXPECT_EQ(split.domain_name(d), partition.domain_name(d));
        const Domain a = split.make_domain(d), b = partition.make_domain(d);
        EXPECT_EQ(a.id, b.id);
        EXPECT_TRUE(test::same_bits(a.x, b.x) && test::same_bits(a.y, b.y) && test::same_bits(a.z, b.z) &&
                    test::same_bits(a.f, b.f));
        EXPECT_EQ(a.gid, b.gid);
        EXPECT_EQ(a.interface, b.interface);
        EXPECT_EQ(a.shared_edges, b.shared_edges);
        EXPECT_EQ(a.tets, b.tets);
        // What a seam of this domain alone, of it and the next, and of every
        // domain reads: each the whole mesh's holders.
        const EdgeDomains own = split.edge_domains(d, 1);
        const EdgeDomains pair = split.edge_domains(std::min(d, split.domain_count() - 2), 2);
        for (const EdgeKey key : a.shared_edges) {
            const GlobalId low = edge_key_low(key), high = edge_key_high(key);
            const auto holders = partition.domains_of_edge(low, high);
            ASSERT_GE(holders.size(), 2u);
            ASSERT_EQ(own(low, high), holders);
            ASSERT_EQ(pair(low, high), holders);
            ASSERT_EQ(split.domains_of_edge(low, high), holders);
        }
        shared += a.shared_edges.size();
    }
    EXPECT_GT(shared, 0u);

    const PartitionFile file(part, GetParam().name);
    JobConfig over_mesh = mesh_job("torus", true);
    over_mesh.partition = file.path;
    over_mesh.domains = 0;
    JobConfig over_split;
    over_split.split = dir;
    over_split.domains = 0;
    const Piece expected = run_local(Job(over_mesh), {}).surface;
    const Piece out = run_local(Job(over_split), {}).surface;
    ASSERT_GT(out.triangle_count(), 50u);
    EXPECT_EQ(out.key, expected.key);
    EXPECT_TRUE(test::same_bits(out.x, expected.x) && test::same_bits(out.y, expected.y) &&
                test::same_bits(out.z, expected.z));
    EXPECT_EQ(out.flags, expected.flags);
    EXPECT_EQ(out.triangles, expected.triangles);
}

INSTANTIATE_TEST_SUITE_P(Partitions, MeshPartitionCase, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(MeshPartition, MetisSplitsTheMeshOrItsAbsenceIsAClearError) {
    const auto field = make_field("torus");
    const Domain whole = cube(*field);
    if (!have_metis()) {
        EXPECT_THROW(partition_with_metis(whole, 6), Error);
        return;
    }
    const std::vector<std::int32_t> part = partition_with_metis(whole, 6);
    EXPECT_EQ(part, partition_with_metis(whole, 6)) << "METIS's parts differ between two calls";
    const MeshPartition partition(whole, part, "METIS");
    ASSERT_EQ(partition.domain_count(), 6);
    for (int d = 0; d < 6; ++d) EXPECT_GT(partition.domain_tet_count(d), 0);

    JobConfig config = mesh_job("torus", true);
    config.domains = 6;
    const Piece out = run_local(Job(config), {}).surface;
    const Piece raw = extract(whole, static_cast<float>(field->default_level()));
    EXPECT_TRUE(same_signatures(check_topology(raw), check_topology(out)));
    EXPECT_THROW(partition_with_metis(whole, static_cast<int>(whole.tet_count()) + 1), Error);
}

TEST(MeshPartition, BadPartitionsAreClearErrors) {
    const auto field = make_field("sphere");
    const Domain whole = cube(*field);
    const std::size_t tets = whole.tet_count();
    const auto message = [&](const std::string& text) -> std::string {
        const std::filesystem::path path = std::filesystem::temp_directory_path() / "tetiso_bad_partition";
        std::ofstream(path) << text;
        try {
            read_partition(path, tets);
        } catch (const Error& e) {
            std::filesystem::remove(path);
            return e.what();
        }
        std::filesystem::remove(path);
        return "";
    };
    std::string ids;
    for (std::size_t t = 0; t < tets; ++t) ids += "0\n";
    EXPECT_EQ(message(ids), "");
    EXPECT_NE(message(ids.substr(2)).find("16250 domain ids for the mesh's 16251"), std::string::npos);
    EXPECT_NE(message(ids + "0\n").find("more domain ids than"), std::string::npos);
    EXPECT_NE(message("-1\n" + ids.substr(2)).find("outside [0, 2^31)"), std::string::npos);
    EXPECT_NE(message("0 1\n" + ids.substr(2)).find("2 fields"), std::string::npos);
    EXPECT_NE(message("1.5\n" + ids.substr(2)).find(":1: domain id '1.5'"), std::string::npos);
    EXPECT_EQ(message("# written by a solver\n" + ids), ""); // comments are no ids
    // An id at or above the tetrahedron count leaves a domain empty: refused
    // by the reader, naming the line, before a counter per id is allocated
    // (2^31 - 1 overflowed the count of domains; 10^9 allocated 8 GB first).
    for (const char* huge : {"2147483647", "1000000000", "16251"})
        EXPECT_NE(message(ids.substr(2) + huge + "\n").find(":16251: domain id " + std::string(huge) + " for a mesh of 16251"),
                  std::string::npos)
            << huge;

    // The same ids handed to the partition directly.
    for (const std::int32_t huge : {std::numeric_limits<std::int32_t>::max(), 1000000000}) {
        std::vector<std::int32_t> part(tets, 0);
        part[5] = huge;
        try {
            MeshPartition(whole, part, "huge.part");
            ADD_FAILURE() << "a partition with id " << huge << " was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("huge.part: domain id " + std::to_string(huge)), std::string::npos)
                << e.what();
        }
    }

    // Ids with a gap leave a domain empty.
    std::vector<std::int32_t> gap(tets, 0);
    gap[0] = 2;
    try {
        MeshPartition(whole, gap, "gap.part");
        ADD_FAILURE() << "a partition with an empty domain was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("gap.part: domain 1 has no tetrahedra"), std::string::npos) << e.what();
    }

    // A domain count that the file contradicts, and a partition for the lattice.
    const PartitionFile file(grid_partition(whole, 2), "eight");
    JobConfig config = mesh_job("sphere", false);
    config.partition = file.path;
    config.domains = 4;
    EXPECT_THROW(Job{config}, Error);
    config.domains = 8;
    EXPECT_NO_THROW(Job{config});
    JobConfig lattice;
    lattice.lattice = 10;
    lattice.partition = file.path;
    EXPECT_THROW(Job{lattice}, Error);
}

// One domain shares no edge: its split holds empty arrays, which the reader
// once copied from with memcpy(null, ..., 0) (UBSan's report, fatal in the
// sanitised build). The job over it is the job over the mesh.
TEST(MeshSplit, OneDomainSplitReadsBackAndRuns) {
    const test::ScratchDirectory scratch("tetiso_split_one");
    const auto field = make_field("sphere");
    const MeshPartition partition(cube(*field), std::vector<std::int32_t>(cube(*field).tet_count(), 0), "one");
    const std::filesystem::path dir = scratch.at("split");
    write_mesh_split(partition, field->default_level(), dir);
    const SplitMeshPartition split(dir);
    ASSERT_EQ(split.domain_count(), 1);
    EXPECT_TRUE(split.make_domain(0).shared_edges.empty());
    EXPECT_TRUE(split.edge_domains(0, 1)(0, 1).empty());
    JobConfig over_split;
    over_split.split = dir;
    over_split.domains = 0;
    over_split.reduce = false;
    const PartitionFile file(std::vector<std::int32_t>(partition.tet_count(), 0), "one");
    JobConfig over_mesh = mesh_job("sphere", false);
    over_mesh.partition = file.path;
    const Piece a = run_local(Job(over_split), {}).surface, b = run_local(Job(over_mesh), {}).surface;
    EXPECT_GT(a.triangle_count(), 0u);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.key, b.key);
}

// What a reader of a split meets when its files are not what the index
// says: each a tetiso::Error naming the file, never a crash or a domain
// quietly built from the wrong bytes; and a split is never written over
// another directory's contents.
TEST(MeshSplit, DamagedOrMismatchedFilesAreClearErrors) {
    const test::ScratchDirectory scratch("tetiso_split_damaged");
    const auto field = make_field("sphere");
    const Domain whole = cube(*field);
    const MeshPartition partition(whole, grid_partition(whole, 2), "octants");
    const std::filesystem::path dir = scratch.at("split");
    write_mesh_split(partition, field->default_level(), dir);
    const auto message = [](const auto& action) -> std::string {
        try {
            action();
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    };
    const auto write_bytes = [](const std::filesystem::path& path, const std::string& bytes) {
        std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    };
    const std::filesystem::path index = split_index_file(dir), domain1 = split_domain_file(dir, 1);
    const std::string index_bytes = test::read_bytes(index), domain1_bytes = test::read_bytes(domain1);
    const SplitMeshPartition split(dir);

    // One bit flipped anywhere in a domain file.
    for (const std::size_t at : {std::size_t{3}, std::size_t{40}, domain1_bytes.size() / 2, domain1_bytes.size() - 1}) {
        std::string damaged = domain1_bytes;
        damaged[at] = static_cast<char>(damaged[at] ^ 0x10);
        write_bytes(domain1, damaged);
        const std::string text = message([&] { split.make_domain(1); });
        EXPECT_NE(text.find(domain1.string()), std::string::npos) << at << ": " << text;
        EXPECT_TRUE(text.find("damaged") != std::string::npos || text.find("not a tetiso") != std::string::npos) << text;
    }
    // Another domain's file, sound in itself, in its place; then none.
    std::filesystem::copy_file(split_domain_file(dir, 2), domain1, std::filesystem::copy_options::overwrite_existing);
    EXPECT_NE(message([&] { split.make_domain(1); }).find("not the file that"), std::string::npos);
    std::filesystem::remove(domain1);
    EXPECT_NE(message([&] { split.make_domain(1); }).find(domain1.string() + ": cannot open"), std::string::npos);
    write_bytes(domain1, domain1_bytes);
    EXPECT_NO_THROW(split.make_domain(1));

    // A seam's edge file damaged: the seam, and the job, name it.
    const std::filesystem::path edges1 = split_edges_file(dir, 1);
    const std::string edges1_bytes = test::read_bytes(edges1);
    std::string damaged_edges = edges1_bytes;
    damaged_edges[damaged_edges.size() / 2] = static_cast<char>(damaged_edges[damaged_edges.size() / 2] ^ 0x01);
    write_bytes(edges1, damaged_edges);
    EXPECT_NE(message([&] { split.edge_domains(1, 1); }).find(edges1.string() + ": damaged"), std::string::npos);
    EXPECT_NE(message([&] { split.edge_domains(0, 8); }).find(edges1.string() + ": damaged"), std::string::npos);
    EXPECT_NO_THROW(split.edge_domains(2, 6));
    JobConfig damaged_job;
    damaged_job.split = dir;
    damaged_job.domains = 0;
    EXPECT_NE(message([&] { run_local(Job(damaged_job), {}); }).find(edges1.string() + ": damaged"), std::string::npos);
    std::filesystem::copy_file(split_edges_file(dir, 2), edges1, std::filesystem::copy_options::overwrite_existing);
    EXPECT_NE(message([&] { split.edge_domains(1, 1); }).find("not the file that"), std::string::npos);
    write_bytes(edges1, edges1_bytes);

    // The index truncated, or of another format version (its digest made to
    // fit, so that the version check itself is what answers).
    write_bytes(index, index_bytes.substr(0, index_bytes.size() / 2));
    EXPECT_NE(message([&] { SplitMeshPartition{dir}; }).find(index.string() + ": damaged"), std::string::npos);
    std::string other_version = index_bytes.substr(0, index_bytes.size() - 8);
    other_version[8] = 2;
    const std::uint64_t digest = split_digest(other_version.data(), other_version.size());
    other_version.append(reinterpret_cast<const char*>(&digest), sizeof(digest));
    write_bytes(index, other_version);
    EXPECT_NE(message([&] { SplitMeshPartition{dir}; }).find("format version 2"), std::string::npos);
    // Found by fuzz_split: the root's children with counts whose sum
    // overflows an int (UBSan), checked before the children themselves.
    std::string huge_counts = index_bytes.substr(0, index_bytes.size() - 8);
    constexpr std::size_t kTreeNodes = 8 + 4 + 4 + 8 + 8 + 8 + 8 + 8 + 8; // magic .. fingerprint, then the node count
    for (const std::size_t node : {std::size_t{1}, std::size_t{2}}) {
        const std::int32_t count = -1869574000;
        std::memcpy(huge_counts.data() + kTreeNodes + node * sizeof(DomainTreeNode) + offsetof(DomainTreeNode, count), &count, 4);
    }
    const std::uint64_t huge_digest = split_digest(huge_counts.data(), huge_counts.size());
    huge_counts.append(reinterpret_cast<const char*>(&huge_digest), sizeof(huge_digest));
    write_bytes(index, huge_counts);
    EXPECT_NE(message([&] { SplitMeshPartition{dir}; }).find("merge tree node 0 is malformed"), std::string::npos);
    write_bytes(index, index_bytes);

    // A split goes only to a new or empty directory; the old one is left as it was.
    EXPECT_NE(message([&] { write_mesh_split(partition, 0.0, dir); }).find("not an empty directory"), std::string::npos);
    EXPECT_EQ(test::read_bytes(index), index_bytes);

    // A job over a split takes no partition file, field attribute or other count.
    JobConfig config;
    config.split = dir;
    config.domains = 7;
    EXPECT_NE(message([&] { Job{config}; }).find("8 domains, where 7"), std::string::npos);
    config.domains = 0;
    config.attribute = 0;
    EXPECT_THROW(Job{config}, Error);
    config.attribute.reset();
    config.lattice = 10;
    EXPECT_THROW(Job{config}, Error);
    config.lattice = 0;
    EXPECT_EQ(Job{config}.level(), static_cast<float>(field->default_level()));
}

} // namespace
} // namespace tetiso
