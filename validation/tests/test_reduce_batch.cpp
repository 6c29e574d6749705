// Batched reduction (reduce_batch, core/src/reduce/batch.hpp): pieces of
// different sizes reduced side by side, each of which must come out byte
// for byte as reduce() gives it alone, whatever else is in the batch, where
// each piece stops (round 0, a later round, max_rounds), whether it carries
// error bounds and samples, and how many threads run. (Every case of the
// reduction suite is batched too: reduce_under_test.hpp.) Built again into
// test_reduce_gpu, where the batches also run on the GPU.

#include <gtest/gtest.h>

#include <numeric>
#include <set>

#include "reduce_cases.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/error.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"

namespace tetiso {
namespace {

using namespace reduce_cases;
using test::one_triangle;
using test::same_piece;

// Pieces that stop at different rounds alone: a triangle (round 0), small
// and larger closed surfaces, a flat grid with a border, a torus, an empty
// piece, a lattice surface with locked interfaces, and one piece twice (the
// same keys in one batch).
std::vector<Piece> mixed_pieces() {
    const Piece lattice = test::lattice_surface(20, 1, "gyroid");
    return {icosphere(3), one_triangle(), grid(8, 0.3), Piece{}, torus(24, 12, 2.0, 0.6), lattice, icosphere(1),
            icosphere(3)};
}

// Each piece of the batch against the piece alone on the host; in the GPU
// build the batch runs on the GPU too. Returns each piece's report alone.
std::vector<ReduceReport> expect_batch_is_alone(const std::vector<Piece>& pieces, const ReduceOptions& o) {
    std::vector<ReduceReport> reports(pieces.size());
    std::vector<std::size_t> rounds;
    std::vector<Piece> alone;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        alone.push_back(reduce(pieces[i], o, &reports[i]));
        rounds.push_back(reports[i].rounds.size());
    }
    std::vector<ReduceOptions> where{o};
#ifdef TETISO_TEST_GPU
    where.push_back(o);
    where.back().device = test::the_gpu();
#endif
    for (const ReduceOptions& run : where) {
        ReduceReport report;
        const std::vector<Piece> batched = reduce_batch(pieces, run, &report);
        EXPECT_EQ(report.triangles_in, [&] {
            std::size_t n = 0;
            for (const Piece& p : pieces) n += p.triangle_count();
            return n;
        }());
        // The batch runs as long as its longest piece.
        EXPECT_EQ(report.rounds.size(), *std::max_element(rounds.begin(), rounds.end()));
        EXPECT_EQ(batched.size(), pieces.size());
        for (std::size_t i = 0; i < std::min(batched.size(), pieces.size()); ++i)
            EXPECT_TRUE(same_piece(alone[i], batched[i])) << "piece " << i << " of " << pieces.size();
    }
    return reports;
}

std::vector<std::size_t> rounds_of(const std::vector<ReduceReport>& reports) {
    std::vector<std::size_t> rounds;
    for (const ReduceReport& r : reports) rounds.push_back(r.rounds.size());
    return rounds;
}

TEST(ReduceBatch, EveryPieceIsItselfAloneWhereverItStops) {
    const std::vector<Piece> pieces = mixed_pieces();
    for (const int threads : {1, 4}) {
        ReduceOptions o;
        o.threads = threads;
        const std::vector<ReduceReport> reports = expect_batch_is_alone(pieces, o);
        const std::vector<std::size_t> rounds = rounds_of(reports);
        // The batch holds pieces that stop at three or more different
        // rounds, one of them round 0 (one round run), and one that stops
        // after two rounds of flips alone (its last round flipped): a piece
        // that went on with the batch would flip further, one stopped with
        // it would not have finished.
        EXPECT_EQ(rounds[1], 1u);
        EXPECT_GE(std::set<std::size_t>(rounds.begin(), rounds.end()).size(), 3u);
        EXPECT_TRUE(std::any_of(reports.begin(), reports.end(), [](const ReduceReport& r) {
            return r.rounds.size() >= 2 && r.rounds.back().collapses == 0 && r.rounds.back().flips > 0;
        }));
    }
}

TEST(ReduceBatch, PiecesStoppedByMaxRoundsAndEarlierAreThemselves) {
    ReduceOptions o;
    o.max_rounds = 3;
    const std::vector<std::size_t> rounds = rounds_of(expect_batch_is_alone(mixed_pieces(), o));
    // Some piece ran into max_rounds (its report has max_rounds rounds),
    // others finished before it.
    EXPECT_EQ(*std::max_element(rounds.begin(), rounds.end()), 3u);
    EXPECT_LT(*std::min_element(rounds.begin(), rounds.end()), 3u);
    o.max_rounds = 0; // the input checks only
    expect_batch_is_alone(mixed_pieces(), o);
}

TEST(ReduceBatch, ErrorBoundsAndSamplesHandedOnAreEachPiecesOwn) {
    const std::vector<Piece> raw = mixed_pieces();
    for (const int threads : {1, 4}) {
        ReduceOptions o;
        o.threads = threads;
        o.max_error = 0.05;
        o.keep_samples = true;
        expect_batch_is_alone(raw, o);
        // Pieces reduced before (error bounds, raw vertices kept as samples)
        // beside raw ones, as a seam's regions are: reduced again with a
        // looser Φ, the samples measured again.
        std::vector<Piece> mixed;
        for (std::size_t i = 0; i < raw.size(); ++i) mixed.push_back(i % 2 == 0 ? reduce(raw[i], o) : raw[i]);
        std::size_t carried = 0;
        for (const Piece& p : mixed) carried += p.sample_count();
        EXPECT_GT(carried, 0u);
        o.phi = 0.8;
        o.max_error = 0.08;
        expect_batch_is_alone(mixed, o);
        o.keep_samples = false;
        expect_batch_is_alone(mixed, o);
    }
}

TEST(ReduceBatch, NamesThePieceThatReduceWouldRefuse) {
    std::vector<Piece> pieces{icosphere(1), Piece{}, icosphere(1)};
    pieces[2].key[3] = pieces[2].key[2]; // keys not unique
    std::string message;
    try {
        reduce_batch(pieces);
    } catch (const Error& e) {
        message = e.what();
    }
    EXPECT_EQ(message, "tetiso::reduce_batch: piece 2: vertex keys are not sorted and unique at vertex 3 (key 2)");

    // A piece that is not a manifold, found by the first round's fans.
    Builder three;
    for (int i = 0; i < 5; ++i) three.add(i, i * i, i % 2);
    three.tri(0, 1, 2);
    three.tri(1, 0, 3);
    three.tri(0, 1, 4);
    pieces = {icosphere(2), icosphere(1), three.piece, icosphere(1)};
    message.clear();
    try {
        reduce_batch(pieces);
    } catch (const Error& e) {
        message = e.what();
    }
    EXPECT_EQ(message, "tetiso::reduce_batch: piece 2: the input is not an oriented 2-manifold: edge (key 0, key 1) "
                       "has 3 triangles");
    ReduceOptions bad;
    bad.phi = 2.0;
    EXPECT_THROW(reduce_batch({icosphere(1)}, bad), Error);
    EXPECT_TRUE(reduce_batch({}).empty());
}

// A lattice's domains built on the host, as a partition other than the
// lattice's would build them (pieces manifold: boxes).
class BuiltOnHost final : public Partition {
public:
    explicit BuiltOnHost(const LatticePartition& lattice) : lattice_(lattice) {}
    int domain_count() const override { return lattice_.domain_count(); }
    const std::vector<int>& neighbours(int d) const override { return lattice_.neighbours(d); }
    const std::vector<DomainTreeNode>& tree() const override { return lattice_.tree(); }
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override { return lattice_.domains_of_edge(a, b); }
    Domain make_domain(int d) const override { return lattice_.make_domain(d); }
    bool pieces_are_manifold() const override { return true; }
    double spacing() const override { return lattice_.spacing(); }
    std::int64_t node_count() const override { return lattice_.node_count(); }
    std::int64_t tet_count() const override { return lattice_.tet_count(); }
    std::uint64_t fingerprint() const override { return lattice_.fingerprint(); }

private:
    const LatticePartition& lattice_;
};

// run_domain_tasks (on the GPU: extraction, then the pieces reduced in
// batches, on one stream and on three side by side) against run_domain_task
// on the host, domain by domain, for lattice domains and domains built on
// the host, in batches of every domain and of a few thousand triangles.
TEST(ReduceBatch, DomainTasksAreEachDomainsTaskAlone) {
    const LatticePartition lattice(36, 27, make_field("gyroid"));
    const BuiltOnHost built(lattice);
    DomainTaskOptions alone;
    alone.level = static_cast<float>(lattice.field().default_level());
    alone.reduce = ReduceOptions{};
    alone.reduce->max_error = 0.25 * lattice.spacing();
    alone.reduce->keep_samples = true;
    std::vector<int> domains(static_cast<std::size_t>(lattice.domain_count()));
    std::iota(domains.rbegin(), domains.rend(), 0); // any order
    DomainTaskOptions batched = alone;
    std::vector<std::vector<Device>> lane_sets{{}};
#ifdef TETISO_TEST_GPU
    batched.device = test::the_gpu();
    lane_sets.push_back({Device::cuda(), Device::cuda()});
#endif
    for (const Partition* partition : {static_cast<const Partition*>(&lattice), static_cast<const Partition*>(&built)})
        for (const std::size_t limit : {std::size_t{0}, std::size_t{3000}})
            for (const std::vector<Device>& lanes : lane_sets) {
                batched.batch_triangles = limit;
                batched.lanes = lanes;
                const std::vector<DomainTaskResult> results = run_domain_tasks(*partition, domains, batched);
                ASSERT_EQ(results.size(), domains.size());
                std::size_t crossed = 0;
                for (std::size_t i = 0; i < domains.size(); ++i) {
                    const DomainTaskResult one = run_domain_task(*partition, domains[i], alone);
                    EXPECT_TRUE(same_piece(one.piece, results[i].piece))
                        << "domain " << domains[i] << ", limit " << limit << ", lanes " << 1 + lanes.size();
                    EXPECT_EQ(one.triangles_extracted, results[i].triangles_extracted) << "domain " << domains[i];
                    crossed += one.piece.triangle_count() > 0;
                }
                EXPECT_GT(crossed, 1u);
            }
#ifdef TETISO_TEST_GPU
    // Each lane needs a Device of its own: two threads on one stream and
    // its buffers would write over each other.
    batched.lanes = {Device::cuda(), batched.device};
    EXPECT_THROW(run_domain_tasks(lattice, domains, batched), Error);
#endif
}

} // namespace
} // namespace tetiso
