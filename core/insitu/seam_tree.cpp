// The task tree over the ranks of an in-situ call (seam_tree.hpp). Each
// task is what the job's (core/job/job.cpp, Job::execute) is: a domain
// task with the same options, samples kept near locked vertices; a seam
// with the same rings.
#include "seam_tree.hpp"

#include <chrono>
#include <deque>
#include <limits>
#include <map>
#include <new>

#include "byte_buffer.hpp"
#include "piece_bytes.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/error.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"

namespace tetiso::insitu {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A task's piece on the wire, or the failure that stands for it.
std::string encode(const Piece* piece) {
    detail::ByteWriter<std::string> out;
    out.put(static_cast<std::uint8_t>(piece ? 1 : 0));
    if (piece) detail::put_piece(out, *piece);
    return std::move(out.bytes);
}

std::optional<Piece> decode(const std::string& bytes) {
    detail::ByteReader in(bytes, [](const char*) { throw Error("a piece from another rank is truncated"); });
    if (in.get<std::uint8_t>() == 0) return std::nullopt;
    return detail::get_piece(in);
}

} // namespace

TreeRun run_tree(MPI_Comm comm, const Partition& partition, const std::vector<int>& domain_of_rank, const TreeOptions& options) {
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    const std::vector<TaskNode> tree = task_tree(partition.tree());
    const int tasks = static_cast<int>(tree.size());
    std::vector<int> rank_of_domain(domain_of_rank.size());
    for (std::size_t r = 0; r < domain_of_rank.size(); ++r) rank_of_domain[static_cast<std::size_t>(domain_of_rank[r])] = static_cast<int>(r);
    // Who runs each task, and each task's parent; children follow parents.
    std::vector<int> owner(static_cast<std::size_t>(tasks), -1), parent(static_cast<std::size_t>(tasks), -1);
    for (int t = tasks - 1; t >= 0; --t) {
        const TaskNode& n = tree[static_cast<std::size_t>(t)];
        if (n.left < 0) {
            owner[static_cast<std::size_t>(t)] = rank_of_domain[static_cast<std::size_t>(n.first)];
        } else {
            owner[static_cast<std::size_t>(t)] = owner[static_cast<std::size_t>(n.left)];
            parent[static_cast<std::size_t>(n.left)] = parent[static_cast<std::size_t>(n.right)] = t;
        }
    }
    // The root's piece goes to options.root under this tag; a child's to its
    // parent's owner under the parent's index.
    const int root_tag = tasks;

    TreeRun run;
    std::map<int, std::optional<Piece>> held; // finished tasks' pieces here (none: failed)
    std::deque<std::string> outgoing; // kept in place until every send is done
    std::vector<MPI_Request> requests;
    const auto send = [&](const std::optional<Piece>& piece, int to, int tag) {
        outgoing.push_back(encode(piece ? &*piece : nullptr));
        if (outgoing.back().size() >= static_cast<std::size_t>(std::numeric_limits<int>::max())) {
            if (run.problem.empty()) run.problem = "a piece of 2 GB or more cannot be sent";
            outgoing.back() = encode(nullptr);
        }
        run.bytes_sent += static_cast<std::int64_t>(outgoing.back().size());
        requests.emplace_back();
        MPI_Isend(outgoing.back().data(), static_cast<int>(outgoing.back().size()), MPI_CHAR, to, tag, comm, &requests.back());
    };
    const auto receive = [&](int from, int tag) -> std::optional<Piece> {
        MPI_Status status;
        MPI_Probe(from, tag, comm, &status);
        int count = 0;
        MPI_Get_count(&status, MPI_CHAR, &count);
        std::string bytes(static_cast<std::size_t>(count), '\0');
        MPI_Recv(bytes.data(), count, MPI_CHAR, from, tag, comm, MPI_STATUS_IGNORE);
        run.bytes_received += count;
        try {
            return decode(bytes);
        } catch (const Error& e) {
            if (run.problem.empty()) run.problem = e.what();
            return std::nullopt;
        }
    };
    ReduceOptions reduce_options = options.reduce_options;
    reduce_options.threads = options.threads;
    reduce_options.more_threads = {};
    reduce_options.device = Device{};

    for (int t = tasks - 1; t >= 0; --t) {
        if (owner[static_cast<std::size_t>(t)] != rank) continue;
        const TaskNode& n = tree[static_cast<std::size_t>(t)];
        std::optional<Piece> piece;
        const auto start = Clock::now();
        if (n.left < 0) {
            if (run.problem.empty()) {
                try {
                    DomainTaskOptions task;
                    task.level = options.level;
                    task.device = options.device;
                    task.threads = options.threads;
                    if (options.reduce) {
                        task.reduce = reduce_options;
                        task.reduce->keep_samples = true;
                    }
                    DomainTaskResult done = run_domain_task(partition, n.first, task);
                    if (options.reduce) {
                        const auto started = Clock::now();
                        keep_samples_near_locked(done.piece, options.sample_rings);
                        done.seconds.reduce += seconds_since(started);
                    }
                    run.stages += done.seconds;
                    run.triangles_extracted += static_cast<std::int64_t>(done.triangles_extracted);
                    run.triangles_reduced += static_cast<std::int64_t>(done.piece.triangle_count());
                    piece = std::move(done.piece);
                } catch (const Error& e) {
                    run.problem = partition.domain_name(n.first) + ": " + e.what();
                } catch (const std::bad_alloc&) {
                    run.problem = partition.domain_name(n.first) + ": out of memory";
                }
            }
            run.domain_seconds += seconds_since(start);
        } else {
            std::optional<Piece> left = std::move(held.at(n.left));
            held.erase(n.left);
            std::optional<Piece> right;
            if (owner[static_cast<std::size_t>(n.right)] == rank) {
                right = std::move(held.at(n.right));
                held.erase(n.right);
            } else {
                right = receive(owner[static_cast<std::size_t>(n.right)], t);
            }
            if (left && right && run.problem.empty()) {
                try {
                    SeamOptions seam_options;
                    seam_options.reduce = options.reduce;
                    seam_options.reduce_options = reduce_options;
                    seam_options.rings = options.seam_rings;
                    seam_options.sample_rings = options.sample_rings;
                    piece = seam(*left, *right, partition.edge_domains(n.first, n.count), seam_options);
                    ++run.seams;
                } catch (const std::exception& e) {
                    const bool memory = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
                    run.problem = "seam of domains " + std::to_string(n.first) + "-" + std::to_string(n.first + n.count - 1) +
                                  ": " + (memory ? std::string("out of memory") : std::string(e.what()));
                }
            }
            run.seam_seconds += seconds_since(start);
        }
        const int up = parent[static_cast<std::size_t>(t)];
        if (up < 0) {
            if (rank == options.root) run.surface = std::move(piece);
            else send(piece, options.root, root_tag);
        } else if (owner[static_cast<std::size_t>(up)] == rank) {
            held[t] = std::move(piece);
        } else {
            send(piece, owner[static_cast<std::size_t>(up)], up);
        }
    }
    if (rank == options.root && owner[0] != rank) {
        const auto start = Clock::now();
        run.surface = receive(owner[0], root_tag);
        run.seam_seconds += seconds_since(start);
    }
    MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
    return run;
}

} // namespace tetiso::insitu
