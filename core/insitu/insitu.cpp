// The in-situ call (tetiso/insitu.hpp): each rank's piece checked, its
// boundary scanned and pooled into the tables every rank builds (the .pvtu
// route's code, core/inputs/piece_tables.hpp), then the job's task tree run
// over the ranks (seam_tree.hpp), every failure agreed by all
// (communicator.hpp).
#include "tetiso/insitu.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <new>
#include <utility>

#include "communicator.hpp"
#include "piece_check.hpp"
#include "piece_tables.hpp"
#include "seam_tree.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

namespace tetiso {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string piece_name(int rank) { return "rank " + std::to_string(rank) + "'s piece"; }

// The pieces of one call as a Partition, so that a domain's task is the job's
// (run_domain_task): every rank knows the tables, and builds only its own
// piece's domain.
class InSituPartition final : public Partition {
public:
    InSituPartition(const detail::PieceTables& tables, const detail::PieceMesh& mine, int rank)
        : tables_(tables), mine_(mine), rank_(rank) {}
    int domain_count() const override { return tables_.domain_count(); }
    const std::vector<int>& neighbours(int domain) const override {
        return tables_.neighbours.at(static_cast<std::size_t>(domain));
    }
    const std::vector<DomainTreeNode>& tree() const override { return tables_.tree; }
    std::vector<int> domains_of_edge(GlobalId a, GlobalId b) const override { return tables_.domains_of_edge(a, b); }
    Domain make_domain(int domain) const override {
        if (tables_.source_id.at(static_cast<std::size_t>(domain)) != rank_)
            throw Error("domain " + std::to_string(domain) + " is not " + piece_name(rank_));
        return tables_.make_domain(mine_, domain, nullptr, piece_name(rank_));
    }
    bool pieces_are_manifold() const override { return false; }
    std::string domain_name(int domain) const override {
        return "domain " + std::to_string(domain) + " (" + piece_name(tables_.source_id.at(static_cast<std::size_t>(domain))) + ")";
    }
    double spacing() const override { return tables_.spacing; }
    std::int64_t node_count() const override { return tables_.node_count; }
    std::int64_t tet_count() const override { return tables_.tet_count; }
    std::uint64_t fingerprint() const override { return 0; }

private:
    const detail::PieceTables& tables_;
    const detail::PieceMesh& mine_;
    int rank_;
};

// What an option is outside its range, or empty.
std::string option_problem(const InSituOptions& o) {
    if (!std::isfinite(o.level)) return "the level is not a finite number";
    if (std::abs(o.level) > std::numeric_limits<float>::max())
        return "the level " + std::to_string(o.level) + " does not fit a float, the type of field values";
    if (!std::isfinite(o.max_error_spacings) || o.max_error_spacings < 0)
        return "error bound " + std::to_string(o.max_error_spacings) + " is not a finite number >= 0";
    if (o.seam_rings < 0 || o.seam_rings > 64) return "seam rings " + std::to_string(o.seam_rings) + " outside [0, 64]";
    if (o.sample_rings < -1 || o.sample_rings > 64) return "sample rings " + std::to_string(o.sample_rings) + " outside [-1, 64]";
    return {};
}

// The options that decide the surface, as bytes every rank must agree on.
std::string option_bytes(const InSituOptions& o) {
    const ReduceOptions& r = o.reduce_options;
    std::string bytes;
    const auto add = [&bytes](const auto& value) { bytes.append(reinterpret_cast<const char*>(&value), sizeof value); };
    add(o.level), add(o.reduce), add(o.max_error_spacings), add(o.seam_rings), add(o.sample_rings);
    add(r.phi), add(r.max_rounds), add(r.min_angle_degrees), add(r.max_normal_turn_degrees), add(r.short_edge_ratio);
    add(r.flips), add(r.flip_max_dihedral_degrees);
    return bytes + o.output.string();
}

} // namespace

struct InSituSession::State {
    MPI_Comm comm = MPI_COMM_NULL;
    int rank = 0, size = 1;
    InSituSessionOptions options;
    Device device;
};

InSituSession::InSituSession(MPI_Comm comm, const InSituSessionOptions& options) : state_(std::make_unique<State>()) {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (!initialised) throw Error("in situ: MPI is not initialised");
    State& s = *state_;
    MPI_Comm_dup(comm, &s.comm);
    MPI_Comm_rank(s.comm, &s.rank);
    MPI_Comm_size(s.comm, &s.size);
    s.options = options;
    try {
        std::string problem;
        if (options.threads < 0 || options.threads > kMaxThreads)
            problem = std::to_string(options.threads) + " threads: give 0 (all cores) to " + std::to_string(kMaxThreads);
        else if (options.root < 0 || options.root >= s.size)
            problem = "root " + std::to_string(options.root) + " is no rank of " + std::to_string(s.size);
        int differs = 0;
        {
            int mine[3] = {static_cast<int>(options.device), options.threads, options.root}, low[3], high[3];
            MPI_Allreduce(mine, low, 3, MPI_INT, MPI_MIN, s.comm);
            MPI_Allreduce(mine, high, 3, MPI_INT, MPI_MAX, s.comm);
            differs = low[0] != high[0] || low[2] != high[2];
        }
        if (problem.empty() && differs) problem = "the ranks give different devices or roots";
        if (problem.empty() && options.device != InSituDevice::cpu) {
            // The node's GPUs dealt out to its ranks by their rank within it.
            MPI_Comm node;
            MPI_Comm_split_type(s.comm, MPI_COMM_TYPE_SHARED, s.rank, MPI_INFO_NULL, &node);
            int local = 0;
            MPI_Comm_rank(node, &local);
            MPI_Comm_free(&node);
            const int gpus = gpu_count();
            try {
                if (gpus > 0) s.device = Device::cuda(local % gpus);
                else if (options.device == InSituDevice::gpu) problem = "device gpu: " + gpu_info(0).description;
            } catch (const Error& e) {
                problem = std::string("device gpu: ") + e.what();
            }
        }
        insitu::agree(s.comm, problem);
    } catch (...) {
        MPI_Comm_free(&s.comm);
        throw;
    }
}

InSituSession::~InSituSession() {
    int finalised = 0;
    MPI_Finalized(&finalised);
    if (!finalised && state_->comm != MPI_COMM_NULL) MPI_Comm_free(&state_->comm);
}

int InSituSession::rank() const { return state_->rank; }
int InSituSession::size() const { return state_->size; }
const Device& InSituSession::device() const { return state_->device; }

InSituResult InSituSession::isosurface(const InSituPiece& piece, const InSituOptions& options) {
    const State& s = *state_;
    const auto start = Clock::now();
    InSituResult result;
    InSituCost& cost = result.cost;

    // Options and piece checked; every rank agrees before any goes on.
    auto stage = Clock::now();
    insitu::CheckedPiece checked;
    {
        std::string problem = option_problem(options);
        const std::vector<std::string> all = insitu::all_gather(s.comm, option_bytes(options));
        if (problem.empty() && all[static_cast<std::size_t>(s.rank)] != all[0])
            problem = "its options (level, reduction, output) differ from rank 0's";
        if (problem.empty()) {
            try {
                checked = insitu::check_piece(piece);
            } catch (const Error& e) {
                problem = piece_name(s.rank) + ": " + e.what();
            } catch (const std::bad_alloc&) {
                problem = piece_name(s.rank) + ": out of memory while checking it";
            }
        }
        insitu::agree(s.comm, problem);
    }
    cost.nodes = static_cast<std::int64_t>(checked.mesh.used.size());
    cost.tetrahedra = static_cast<std::int64_t>(checked.mesh.tet_count);
    cost.seconds.check = seconds_since(stage);

    // This piece's boundary, pooled with every other's into the tables.
    stage = Clock::now();
    // A rank that cannot scan still takes part in the exchange, its problem
    // in its share, so that every rank throws it.
    std::vector<std::pair<int, detail::PieceScan>> mine;
    std::string scan_problem;
    std::vector<std::pair<int, detail::PieceInside>> inside;
    try {
        mine.emplace_back(s.rank, detail::scan_piece(checked.mesh, s.rank, piece_name(s.rank), s.size > 1));
        inside.emplace_back(s.rank, std::move(mine.back().second.inside));
    } catch (const Error& e) { // its tetrahedra overlap, as the .pvtu route's scan refuses them
        mine.clear();
        scan_problem = e.what();
    } catch (const std::bad_alloc&) {
        mine.clear();
        scan_problem = "rank " + std::to_string(s.rank) + ": out of memory while scanning " + piece_name(s.rank);
    }
    const std::string share = detail::pack_scans(scan_problem, mine);
    std::vector<std::pair<int, detail::PieceScan>>().swap(mine);
    cost.seconds.scan = seconds_since(stage);
    stage = Clock::now();
    std::vector<detail::PieceScan> scans(static_cast<std::size_t>(s.size));
    const detail::PieceTables::Gather gather = [&s](const std::string& bytes) { return insitu::all_gather(s.comm, bytes); };
    detail::unpack_scans(gather(share), scans);
    std::vector<std::string> names;
    for (int r = 0; r < s.size; ++r) names.push_back(piece_name(r));
    // The same on every rank, errors too: no rank goes on alone.
    const detail::PieceTables tables(scans, names, "the pieces", "the field", inside, gather);
    std::vector<std::pair<int, detail::PieceInside>>().swap(inside);
    for (const std::string& note : tables.notes)
        if (s.rank == s.options.root) std::fprintf(stderr, "tetiso: note: %s\n", note.c_str());
    const InSituPartition partition(tables, checked.mesh, s.rank);
    std::vector<int> domain_of_rank(static_cast<std::size_t>(s.size));
    for (int d = 0; d < tables.domain_count(); ++d) domain_of_rank[static_cast<std::size_t>(tables.source_id[static_cast<std::size_t>(d)])] = d;
    result.mesh_nodes = tables.node_count;
    result.mesh_tetrahedra = tables.tet_count;
    result.spacing = tables.spacing;
    result.domain = domain_of_rank[static_cast<std::size_t>(s.rank)];
    cost.seconds.pool = seconds_since(stage);

    insitu::TreeOptions tree;
    tree.level = static_cast<float>(options.level);
    tree.reduce = options.reduce;
    tree.reduce_options = options.reduce_options;
    tree.reduce_options.max_error = options.max_error_spacings > 0 ? options.max_error_spacings * tables.spacing : 0.0;
    result.max_error = options.reduce ? tree.reduce_options.max_error : 0.0;
    tree.seam_rings = options.seam_rings;
    tree.sample_rings = options.sample_rings;
    tree.threads = s.options.threads;
    tree.device = s.device;
    tree.root = s.options.root;
    insitu::TreeRun run = insitu::run_tree(s.comm, partition, domain_of_rank, tree);
    cost.seconds.domain = run.domain_seconds;
    cost.seconds.seams = run.seam_seconds;
    cost.domain_stages = run.stages;
    cost.triangles_extracted = run.triangles_extracted;
    cost.triangles_reduced = run.triangles_reduced;
    cost.seams = run.seams;
    cost.bytes_sent = run.bytes_sent;
    cost.bytes_received = run.bytes_received;
    insitu::agree(s.comm, run.problem);

    if (!options.output.empty()) {
        stage = Clock::now();
        std::string problem;
        if (s.rank == s.options.root) {
            try {
                write_piece(*run.surface, options.output);
            } catch (const Error& e) {
                problem = e.what();
            }
        }
        insitu::agree(s.comm, problem);
        cost.seconds.write = seconds_since(stage);
    }
    result.surface = std::move(run.surface);
    cost.seconds.total = seconds_since(start);
    return result;
}

} // namespace tetiso
