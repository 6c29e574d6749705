// The MPI master/worker run (paper, section "Load balancing and job
// scheduling"): rank 0 keeps the task queue and the finished pieces; a worker
// says it is ready, receives a task with the pieces it needs, and returns the
// piece it made, which also says it is ready again. Under --device cpu a
// task goes to whichever worker asks first; under auto or gpu each node's
// resource manager places it on a device and the worker that runs it (see
// Controller). Either way load balances itself and the output does not
// depend on it.
// The seams at the end of the job, which nothing can run beside, rank 0 runs
// itself, with threads on the cores of the workers left idle (see Controller).
//
// Failure: a task that throws, on a worker or on rank 0, is reported to rank
// 0, which stops handing out work, waits for the tasks in flight, tells every
// worker to stop and raises the error — no rank is left blocked, so
// MPI_Finalize returns everywhere and the launcher exits with a non-zero
// status.
#include "tetiso/schedule.hpp"

#ifdef TETISO_HAVE_MPI

#include <mpi.h>
#include <sched.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <thread>

#include "byte_buffer.hpp"
#include "tetiso/placement.hpp"
#include "tetiso/error.hpp"
#include "tetiso/device.hpp"

namespace tetiso {
namespace {

enum Tag : int { kReady = 1, kTask = 2, kResult = 3, kFailure = 4, kStop = 5, kLend = 6 };

// Messages between ranks: values, arrays and pieces (byte_buffer.hpp).
class Packer : public detail::ByteWriter<std::vector<std::byte>> {
public:
    // Bytes that put_piece(piece) appends: reserving them first keeps a
    // large reply from growing by doubling, which on the root seam's worker
    // held up to twice the surface's size at once.
    static std::size_t piece_size(const Piece& piece) {
        const auto array = [](const auto& v) { return sizeof(std::uint64_t) + v.size() * sizeof(v[0]); };
        return array(piece.x) + array(piece.y) + array(piece.z) + array(piece.key) + array(piece.flags) +
               array(piece.triangles) + array(piece.domains) + array(piece.error) + array(piece.sample_xyz) +
               array(piece.sample_triangle) + array(piece.sampled);
    }
    void reserve(std::size_t more) { bytes.reserve(bytes.size() + more); }
    void put_piece(const Piece& piece) {
        put_array(piece.x);
        put_array(piece.y);
        put_array(piece.z);
        put_array(piece.key);
        put_array(piece.flags);
        put_array(piece.triangles);
        put_array(piece.domains);
        put_array(piece.error);
        put_array(piece.sample_xyz);
        put_array(piece.sample_triangle);
        put_array(piece.sampled);
    }
};

class Unpacker : public detail::ByteReader {
public:
    explicit Unpacker(const std::vector<std::byte>& bytes)
        : ByteReader(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                     [](const char*) { throw Error("truncated message between MPI ranks"); }) {}
    Piece get_piece() {
        Piece piece;
        piece.x = get_array<float>();
        piece.y = get_array<float>();
        piece.z = get_array<float>();
        piece.key = get_array<EdgeKey>();
        piece.flags = get_array<std::uint8_t>();
        piece.triangles = get_array<std::int32_t>();
        piece.domains = get_array<int>();
        piece.error = get_array<float>();
        piece.sample_xyz = get_array<float>();
        piece.sample_triangle = get_array<std::int32_t>();
        piece.sampled = get_array<std::uint8_t>();
        return piece;
    }
    std::string get_string() {
        const auto chars = get_array<char>();
        return std::string(chars.begin(), chars.end());
    }
};

void send(const std::vector<std::byte>& bytes, int to, int tag) {
    if (bytes.size() > static_cast<std::size_t>(INT32_MAX)) throw Error("message over 2 GiB between MPI ranks");
    MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

// Waits for the next message from `from` (or any rank) without holding a
// core: Open MPI's blocking probe polls at full speed, so rank 0 and every
// idle worker would each keep a core busy while waiting. With P workers on P
// + 1 cores that left no core for anything else on the node, and the rank
// running the job's last seams found every other core taken by ranks that
// had nothing to do. Sleeping between polls, with the pause growing to at
// most kLongestPause, costs a task at most that much latency; tasks take
// 10^-2 to 1 s.
void wait_for_message(int from, MPI_Status& status) {
    constexpr auto kLongestPause = std::chrono::microseconds(500);
    auto pause = std::chrono::microseconds(5);
    for (;;) {
        int arrived = 0;
        MPI_Iprobe(from, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status);
        if (arrived) return;
        std::this_thread::sleep_for(pause);
        pause = std::min(2 * pause, kLongestPause);
    }
}

// Receives the message a probe found, whatever its size.
std::vector<std::byte> receive_probed(const MPI_Status& status) {
    int size = 0;
    MPI_Get_count(&status, MPI_BYTE, &size);
    std::vector<std::byte> bytes(static_cast<std::size_t>(size));
    MPI_Recv(bytes.data(), size, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return bytes;
}

// Receives the next message from `from` (or any rank).
std::vector<std::byte> receive(int from, MPI_Status& status) {
    wait_for_message(from, status);
    return receive_probed(status);
}

// The cores the calling thread may run on (the launcher's binding); false
// where that is not known.
bool current_cores(cpu_set_t& cores) {
    CPU_ZERO(&cores);
    return sched_getaffinity(0, sizeof cores, &cores) == 0;
}

// current_cores() as a message: the bytes of a cpu_set_t, or none.
std::vector<std::byte> cores_message() {
    cpu_set_t cores;
    if (!current_cores(cores)) return {};
    std::vector<std::byte> bytes(sizeof cores);
    std::memcpy(bytes.data(), &cores, sizeof cores);
    return bytes;
}

// Moves this process's calling thread and the first `threads` OpenMP threads
// onto `cores`: a thread OpenMP made earlier keeps the cores it was made on.
void run_on(const cpu_set_t& cores, int threads) {
    sched_setaffinity(0, sizeof cores, &cores);
#ifdef _OPENMP
#pragma omp parallel num_threads(threads)
    sched_setaffinity(0, sizeof cores, &cores);
#else
    (void)threads;
#endif
}

// Cores that workers with nothing left to do lend to the task this worker
// runs (the Controller sends them at the end of the domain phase). Each lend
// brings one worker's share of threads; the reduction takes them between
// rounds (ReduceOptions::more_threads), on the main thread, the only one that
// calls MPI.
class LentCores {
public:
    explicit LentCores(int threads_per_worker)
        : per_worker_(std::max(1, threads_per_worker)), known_(current_cores(own_)), cores_(own_) {}

    // Takes the lends that have arrived; returns the threads to use now, or
    // 0 when nothing changed.
    int take() {
        int taken = 0;
        for (;;) {
            int arrived = 0;
            MPI_Status status;
            MPI_Iprobe(0, kLend, MPI_COMM_WORLD, &arrived, &status);
            if (!arrived) break;
            const std::vector<std::byte> message = receive_probed(status);
            if (message.size() == sizeof(cpu_set_t)) {
                cpu_set_t lent;
                std::memcpy(&lent, message.data(), sizeof lent);
                CPU_OR(&cores_, &cores_, &lent);
            }
            ++taken;
        }
        if (taken == 0 || !known_) return 0;
        lends_ += taken;
        const int threads = std::min(per_worker_ * (1 + lends_), kMaxThreads);
        most_ = std::max(most_, threads);
        run_on(cores_, threads);
        return threads;
    }

    int most() const { return most_; }

    // After the task: back to this worker's own cores and threads (the
    // OpenMP threads too: run_on moved them onto the lent cores).
    void give_back() {
        if (known_ && lends_ > 0) run_on(own_, per_worker_);
        cores_ = own_;
        lends_ = 0;
        most_ = per_worker_;
    }

private:
    int per_worker_;
    cpu_set_t own_;
    bool known_;
    cpu_set_t cores_;
    int lends_ = 0;
    int most_ = per_worker_;
};

// driven_gpu: the GPU this worker drives (-1 for none), made ready before
// it says it is ready: its first task there then takes what its next ones
// take.
void work(const Job& job, int driven_gpu) {
    if (driven_gpu >= 0) {
        try {
            job.prepare_gpu(driven_gpu);
        } catch (const std::exception&) {
            // Its tasks there fail with the same error, which rank 0 reports.
        }
    }
    // The first "ready" names this worker's cores, which rank 0 lends to
    // other ranks when this worker has nothing to do (Controller).
    send(cores_message(), 0, kReady);
    LentCores lent(job.config().threads);
    for (;;) {
        MPI_Status status;
        std::vector<std::byte> message = receive(0, status);
        if (status.MPI_TAG == kLend) continue; // for a task that ended before it came
        if (status.MPI_TAG == kStop) {
            Unpacker in(message);
            if (in.get<std::int32_t>() != 0) throw JobStopped();
            return;
        }
        std::int32_t task = 0, gpu = -1;
        std::optional<Piece> left, right;
        {
            Unpacker in(message);
            task = in.get<std::int32_t>();
            gpu = in.get<std::int32_t>();
            if (in.get<std::int32_t>() == 2) {
                left = in.get_piece();
                right = in.get_piece();
            }
        }
        // The pieces are unpacked: the message's copy of them would only
        // add to the task's peak memory.
        std::vector<std::byte>().swap(message);
        TaskRecord record;
        Packer out;
        const auto started = std::chrono::steady_clock::now();
        try {
            const Piece piece = job.execute(task, left ? &*left : nullptr, right ? &*right : nullptr, record,
                                            TaskThreads{job.config().threads, [&lent] { return lent.take(); }, gpu});
            const int threads = lent.most();
            lent.give_back();
            left.reset();
            right.reset();
            out.put(task);
            out.put(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
            out.put<std::int32_t>(threads);
            out.put(record.triangles_in);
            out.put(record.triangles_out);
            out.put(record.samples_out);
            out.put(record.stages);
            out.put(record.field_low);
            out.put(record.field_high);
            out.reserve(Packer::piece_size(piece));
            out.put_piece(piece);
            send(out.bytes, 0, kResult);
        } catch (const std::exception& e) {
            lent.give_back();
            // Report, then wait to be told to stop: rank 0 decides the end.
            Packer failure;
            failure.put(task);
            const std::string what = dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what();
            failure.put_array(std::vector<char>(what.begin(), what.end()));
            send(failure.bytes, 0, kFailure);
        }
    }
}

// What rank 0 says when the job is stopped from outside. A worker killed by
// SIGKILL (by hand, or by the kernel out of memory) says nothing, and the
// launcher names only its rank and the signal before it sends SIGTERM to
// every other rank: rank 0, which knows which task each rank held, says so
// on its way out. The line is rebuilt whenever a task starts or ends and
// written from the signal handler with write(2), which is all a handler may
// use: two buffers, the one in use switched atomically.
class TasksInFlight {
public:
    TasksInFlight() {
        set("no task had started");
        struct sigaction action {};
        action.sa_handler = &TasksInFlight::on_signal;
        sigemptyset(&action.sa_mask);
        for (const int signal : kSignals) sigaction(signal, &action, &previous_[index_of(signal)]);
    }
    ~TasksInFlight() {
        for (const int signal : kSignals) sigaction(signal, &previous_[index_of(signal)], nullptr);
    }
    TasksInFlight(const TasksInFlight&) = delete;
    TasksInFlight& operator=(const TasksInFlight&) = delete;

    // running: rank -> the task it holds, of `ranks` ranks.
    void update(const Job& job, const std::map<int, int>& running, int ranks) {
        std::string held;
        for (int rank = 0; rank < ranks; ++rank) {
            const auto it = running.find(rank);
            if (rank == 0 && it == running.end()) continue; // rank 0 is the one speaking
            held += std::string(held.empty() ? "" : ", ") + "rank " + std::to_string(rank) +
                    (it == running.end() ? " held no task" : " held task '" + job.describe(it->second) + "'");
        }
        set(held);
    }

private:
    static constexpr int kSignals[] = {SIGTERM, SIGINT, SIGHUP};
    static constexpr std::size_t kLength = 4096;
    static std::size_t index_of(int signal) {
        return static_cast<std::size_t>(std::find(std::begin(kSignals), std::end(kSignals), signal) - std::begin(kSignals));
    }

    void set(const std::string& held) {
        const std::string line = "tetiso: the job was stopped from outside (a rank was killed or ran out of memory, "
                                 "or the launcher was interrupted) while " + held + "\n";
        const int next = 1 - current_.load();
        const std::size_t n = std::min(line.size(), kLength);
        std::memcpy(lines_[next], line.data(), n);
        if (n == kLength) lines_[next][kLength - 1] = '\n';
        lengths_[next] = n;
        current_.store(next);
    }

    static void on_signal(int signal) {
        const int at = current_.load();
        const ssize_t written = ::write(STDERR_FILENO, lines_[at], lengths_[at]);
        (void)written;
        ::signal(signal, SIG_DFL);
        ::raise(signal);
    }

    static inline char lines_[2][kLength];
    static inline std::size_t lengths_[2];
    static inline std::atomic<int> current_{0};
    struct sigaction previous_[std::size(kSignals)];
};

// How many of a node's worker processes drive a GPU, one GPU each. One
// process per GPU keeps the device's context, kernels and buffers warm from
// task to task and runs its tasks one after another (placement.hpp says
// why); at least one worker is left for the seams, which run on the CPU. A
// lone worker drives none: it runs the tasks granted to its node's GPUs
// itself, as the only process that uses them.
int driver_count(int workers, int gpus) { return workers >= 2 ? std::min(gpus, workers - 1) : 0; }

// Which node each rank is on, each node's GPUs and which rank drives each:
// ranks that share memory (MPI_COMM_TYPE_SHARED) are a node, named by its
// lowest rank, and its lowest worker ranks drive its GPUs. A node's GPUs are
// counted, and the first usable one's memory taken, on every rank there;
// the smallest answer stands, in case ranks see different devices. Every rank learns the GPU it
// drives; rank 0 learns the whole layout.
struct NodeLayout {
    int my_gpu = -1;                     // the GPU this rank drives, -1 for none
    std::vector<int> node_of;            // by rank
    std::vector<int> driving;            // by rank: the GPU it drives, -1 for none
    std::vector<int> workers;            // by node: its worker ranks (rank 0 is none)
    std::vector<std::vector<int>> gpus;  // by node: the GPUs its resource manager places tasks on
    std::vector<double> gpu_mib;         // by node: its first usable GPU's memory
};

NodeLayout node_layout(int rank, int ranks, const JobConfig& config) {
    MPI_Comm local;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &local);
    int leader = rank, local_rank = 0, local_size = 1;
    MPI_Allreduce(&rank, &leader, 1, MPI_INT, MPI_MIN, local);
    MPI_Comm_rank(local, &local_rank);
    MPI_Comm_size(local, &local_size);
    const int seen = gpu_count();
    int count = 0;
    MPI_Allreduce(&seen, &count, 1, MPI_INT, MPI_MIN, local);
    const std::vector<int> usable = NodePlacement::usable_gpus(config, count);
    const int seen_mib = usable.empty() ? 0 : static_cast<int>(gpu_memory_mib(usable.front()));
    int mib = 0;
    MPI_Allreduce(&seen_mib, &mib, 1, MPI_INT, MPI_MIN, local);
    MPI_Comm_free(&local);
    // Ranks keep their order within the node (the split's key), and rank 0,
    // the lowest, is no worker.
    const int with_controller = leader == 0 ? 1 : 0;
    const int worker_index = local_rank - with_controller;
    const int drivers = driver_count(local_size - with_controller, static_cast<int>(usable.size()));
    NodeLayout layout;
    if (rank != 0 && worker_index < drivers) layout.my_gpu = usable[static_cast<std::size_t>(worker_index)];

    const int mine[4] = {leader, count, mib, layout.my_gpu};
    std::vector<int> all(4 * static_cast<std::size_t>(ranks));
    MPI_Gather(mine, 4, MPI_INT, all.data(), 4, MPI_INT, 0, MPI_COMM_WORLD);
    if (rank != 0) return layout;
    std::map<int, int> node_of_leader;
    std::vector<int> gpu_count_of;         // by node
    std::vector<std::vector<int>> driven;  // by node: the GPUs its ranks drive, in rank order
    for (int r = 0; r < ranks; ++r) {
        const int* row = &all[4 * static_cast<std::size_t>(r)];
        const auto [it, added] = node_of_leader.try_emplace(row[0], static_cast<int>(layout.workers.size()));
        if (added) {
            layout.workers.push_back(0);
            gpu_count_of.push_back(row[1]);
            layout.gpu_mib.push_back(row[2]);
            driven.emplace_back();
        }
        const auto node = static_cast<std::size_t>(it->second);
        layout.node_of.push_back(it->second);
        layout.driving.push_back(row[3]);
        if (r != 0) ++layout.workers[node];
        if (row[3] >= 0) driven[node].push_back(row[3]);
    }
    // A node's tasks go to the GPUs its ranks drive (GPUs beyond the drivers
    // stay unused: a worker that ran their tasks would be a second process
    // on them), or, for a lone worker, to every usable GPU, which it runs
    // itself.
    for (std::size_t node = 0; node < layout.workers.size(); ++node)
        layout.gpus.push_back(layout.workers[node] == 1 ? NodePlacement::usable_gpus(config, gpu_count_of[node]) : driven[node]);
    return layout;
}

// Rank 0's side of the job: the task queue, the finished pieces, which
// worker holds which task, and the cores idle workers lend.
class Controller {
public:
    // nodes: with --device auto or gpu, which node each rank is on, its GPUs
    // and which ranks drive them: one resource manager per node then places
    // that node's tasks.
    Controller(const Job& job, int ranks, const Progress& progress, const std::optional<NodeLayout>& nodes)
        : job_(job), ranks_(ranks), progress_(progress), start_(clock::now()), queue_(job),
          pieces_(static_cast<std::size_t>(job.task_count())), greeted_(static_cast<std::size_t>(ranks), false),
          own_cores_known_(current_cores(own_cores_)), job_cores_(own_cores_),
          worker_cores_(static_cast<std::size_t>(ranks)), cores_known_(static_cast<std::size_t>(ranks), false),
          lent_to_(static_cast<std::size_t>(ranks), -1) {
        result_.ranks = ranks;
        if (nodes) {
            node_of_ = nodes->node_of;
            driving_ = nodes->driving;
            const bool domains_on_cpu = job.config().device == JobConfig::Device::automatic;
            std::vector<int> drivers(nodes->gpus.size(), 0); // by node
            for (int r = 0; r < ranks; ++r) {
                const int node = node_of_[static_cast<std::size_t>(r)], gpu = driving_[static_cast<std::size_t>(r)];
                if (gpu < 0) continue;
                ++drivers[static_cast<std::size_t>(node)];
                driver_of_gpu_[{node, gpu}] = r;
            }
            for (std::size_t node = 0; node < nodes->gpus.size(); ++node)
                placements_.emplace_back(job, nodes->workers[node] - drivers[node], nodes->gpus[node],
                                         nodes->gpu_mib[node], domains_on_cpu);
        }
    }

    JobResult run() {
        while (!queue_.finished() || !running_.empty() || !waiting_.empty()) {
            if (should_run_here()) {
                execute_here();
                continue;
            }
            if (placements_.empty())
                while (failure_.empty() && !idle_.empty() && queue_.has_ready()) dispatch(take_idle());
            else
                while (failure_.empty() && queue_.has_ready()) {
                    const int node = node_with_room();
                    if (node < 0) break;
                    place(node);
                }
            if (failure_.empty()) start_granted();
            else cancel_waiting();
            if (failure_.empty() && !queue_.has_ready()) lend_idle_cores();
            // A grant waits only for units that a running task holds: its
            // result, the next message, frees them.
            if (running_.empty() && (!failure_.empty() || queue_.finished())) break;
            MPI_Status status;
            const std::vector<std::byte> message = receive(MPI_ANY_SOURCE, status);
            const int worker = status.MPI_SOURCE;
            greeted_[static_cast<std::size_t>(worker)] = true;
            if (status.MPI_TAG == kReady && message.size() == sizeof(cpu_set_t)) {
                take_cores(worker, message);
            } else if (status.MPI_TAG == kResult) {
                take_result(worker, message);
            } else if (status.MPI_TAG == kFailure) {
                take_failure(worker, message);
            }
            idle_.push_back(worker);
        }
        stop_workers();
        if (!failure_.empty()) throw Error(failure_);
        result_.surface = std::move(*pieces_[0]);
        result_.seconds = seconds();
        return std::move(result_);
    }

private:
    using clock = std::chrono::steady_clock;

    // A task's grant, from its request to its result.
    struct Placed {
        int task = 0, node = 0;
        Grant grant;
        double asked_at = 0, sent_at = 0;
    };

    double seconds() const { return std::chrono::duration<double>(clock::now() - start_).count(); }
    std::optional<Piece>& piece(int task) { return pieces_[static_cast<std::size_t>(task)]; }

    void fail(int task, int rank, const std::string& what) {
        if (failure_.empty())
            failure_ = "task '" + job_.describe(task) + "' failed on rank " + std::to_string(rank) + ": " + what;
    }

    // A seam rank 0 runs itself when no task is in flight and it is the only
    // one ready. Then every unfinished task is one of its ancestors (any
    // other would have a ready or running task below it), so nothing could
    // start before it ends, and no worker loses work while rank 0 computes
    // and answers nobody. That is always so for the root, and, because the
    // queue finishes subtrees early, in practice for every seam after the
    // last domain task. Run here, such a seam skips packing both pieces,
    // the worker's unpacking, and the same again for its result; and the
    // root seam, which holds the whole surface several times, takes no
    // worker's memory. A looser rule,
    // with seams of other subtrees still in flight, could keep a finished
    // worker's result and the parent it readies waiting for rank 0.
    bool should_run_here() const {
        return failure_.empty() && running_.empty() && waiting_.empty() && queue_.ready_count() == 1 &&
               job_.kind(queue_.peek()) == TaskKind::seam;
    }

    // Such a seam runs on the cores of rank 0 and of every worker, which are
    // all idle then and wait without spinning (wait_for_message): one thread
    // per rank's share, on the union of the ranks' bindings. Threads do not
    // change the result. Otherwise the job's last seams, mostly their
    // reduction near the seam, would run on one rank's cores with the others
    // idle.
    void execute_here() {
        const int task = queue_.pop();
        const TaskNode& n = job_.node(task);
        TaskRecord record;
        record.start = seconds();
        int threads = job_.config().threads;
        if (own_cores_known_) {
            threads = std::min(std::max(1, threads) * ranks_, kMaxThreads);
            run_on(job_cores_, threads);
        }
        auto back_home = [&] {
            if (own_cores_known_) run_on(own_cores_, std::max(1, job_.config().threads));
        };
        in_flight_.update(job_, {{0, task}}, ranks_);
        try {
            piece(task) = job_.execute(task, &*piece(n.left), &*piece(n.right), record, TaskThreads{threads, {}, {}});
        } catch (const std::exception& e) {
            back_home();
            fail(task, 0, dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory" : e.what());
            return;
        }
        back_home();
        in_flight_.update(job_, running_, ranks_);
        piece(n.left).reset();
        piece(n.right).reset();
        record.rank = 0;
        record.end = seconds();
        result_.tasks.push_back(record);
        queue_.complete(task);
        if (progress_) progress_(++done_, job_.task_count(), seconds());
    }

    // Lending. Once no task is ready, a worker without work lends its cores
    // to a running task (the one with the fewest lends, the latest started
    // among equals), which takes them at its next reduction round
    // (LentCores). The domain tasks' times vary by a third with the machine's
    // noise, not with the domain, so the phase's end is uneven whatever the
    // order. A lent core comes back when its borrower's task ends; a lender
    // given a seam meanwhile shares it for that seam's time. A GPU's driver
    // neither lends (a task for its GPU may come at any moment) nor borrows
    // (its task runs on the GPU).
    void lend_idle_cores() {
        for (const int lender : idle_) {
            if (lent_to_[static_cast<std::size_t>(lender)] >= 0 || !cores_known_[static_cast<std::size_t>(lender)] ||
                drives_gpu(lender))
                continue;
            int borrower = -1;
            for (const auto& [worker, task] : running_) {
                if (!cores_known_[static_cast<std::size_t>(worker)] || runs_on_gpu(worker)) continue;
                if (borrower < 0 || lends_[worker] < lends_[borrower] ||
                    (lends_[worker] == lends_[borrower] && dispatched_at_[worker] > dispatched_at_[borrower]))
                    borrower = worker;
            }
            if (borrower < 0) return;
            std::vector<std::byte> cores(sizeof(cpu_set_t));
            std::memcpy(cores.data(), &worker_cores_[static_cast<std::size_t>(lender)], sizeof(cpu_set_t));
            send(cores, borrower, kLend);
            lent_to_[static_cast<std::size_t>(lender)] = borrower;
            ++lends_[borrower];
        }
    }

    void end_lends_to(int borrower) {
        for (int& to : lent_to_)
            if (to == borrower) to = -1;
        lends_.erase(borrower);
    }

    // An idle worker whose cores are not lent out, where there is one.
    int take_idle() {
        auto it = std::find_if(idle_.begin(), idle_.end(),
                               [&](int worker) { return lent_to_[static_cast<std::size_t>(worker)] < 0; });
        if (it == idle_.end()) it = idle_.begin();
        const int worker = *it;
        idle_.erase(it);
        return worker;
    }

    // Hands the next task to `worker` (--device cpu: no placement).
    void dispatch(int worker) {
        send_task(worker, queue_.pop(), -1);
    }

    // Whether `worker`'s task runs on a GPU (its grant is for one).
    bool runs_on_gpu(int worker) const {
        const auto it = placed_.find(worker);
        return it != placed_.end() &&
               placements_[static_cast<std::size_t>(it->second.node)].gpu_of(it->second.grant.device) >= 0;
    }

    bool drives_gpu(int worker) const {
        return !driving_.empty() && driving_[static_cast<std::size_t>(worker)] >= 0;
    }

    // The rank that drives the GPU of a node's manager device, -1 where none
    // does (the CPU, or the GPUs of a node with a lone worker).
    int driver_of(int node, int device) const {
        const int gpu = placements_[static_cast<std::size_t>(node)].gpu_of(device);
        const auto it = driver_of_gpu_.find({node, gpu});
        return gpu < 0 || it == driver_of_gpu_.end() ? -1 : it->second;
    }

    // A node that can take another task: one of its processes is idle and
    // not already promised to a grant that waits (a driver to one for its
    // GPU; the other workers to those for the CPU). Placing a task only then,
    // not as soon as it is ready, keeps each device's queue as short as the
    // predictions make it worth, and lets a task's place be decided with
    // the latest models. Nodes are served in the order their processes
    // became idle.
    int node_with_room() const {
        std::map<int, int> free_workers; // node -> idle workers that drive no GPU, less the grants waiting for one
        std::map<int, int> waiting_for;  // driver -> grants waiting for it
        for (const int worker : idle_)
            if (!drives_gpu(worker)) ++free_workers[node_of_[static_cast<std::size_t>(worker)]];
        for (const Placed& p : waiting_) {
            if (const int driver = driver_of(p.node, p.grant.device); driver >= 0)
                ++waiting_for[driver];
            else
                --free_workers[p.node];
        }
        for (const int worker : idle_) {
            const bool room = drives_gpu(worker) ? waiting_for[worker] == 0
                                                 : free_workers[node_of_[static_cast<std::size_t>(worker)]] > 0;
            if (room) return node_of_[static_cast<std::size_t>(worker)];
        }
        return -1;
    }

    // Asks `node`'s manager where and when the next task runs; it waits for
    // that grant in waiting_.
    void place(int node) {
        const int task = queue_.pop();
        const TaskNode& n = job_.node(task);
        NodePlacement& placement = placements_[static_cast<std::size_t>(node)];
        const Piece* left = n.left >= 0 ? &*piece(n.left) : nullptr;
        const Piece* right = n.right >= 0 ? &*piece(n.right) : nullptr;
        Placed p;
        p.task = task;
        p.node = node;
        try {
            p.grant = placement.manager.request(placement.request(task, left, right), seconds());
        } catch (const Error& e) {
            fail(task, 0, e.what());
            return;
        }
        p.asked_at = seconds();
        waiting_.push_back(p);
    }

    // The idle rank that runs a grant now: its GPU's driver, or an idle
    // worker of its node that drives none (one whose cores are not lent out
    // where there is one); -1 while none is idle.
    int executor_of(const Placed& p) const {
        if (const int driver = driver_of(p.node, p.grant.device); driver >= 0)
            return std::find(idle_.begin(), idle_.end(), driver) != idle_.end() ? driver : -1;
        int lent = -1;
        for (const int worker : idle_) {
            if (drives_gpu(worker) || node_of_[static_cast<std::size_t>(worker)] != p.node) continue;
            if (lent_to_[static_cast<std::size_t>(worker)] < 0) return worker;
            if (lent < 0) lent = worker;
        }
        return lent;
    }

    // Sends the tasks whose grants their devices admit now, in the order
    // they were asked for (the manager keeps each device's order).
    void start_granted() {
        for (auto it = waiting_.begin(); it != waiting_.end();) {
            Placed& p = *it;
            NodePlacement& placement = placements_[static_cast<std::size_t>(p.node)];
            const int worker = executor_of(p);
            if (worker < 0 || !placement.manager.start(p.grant.ticket, seconds())) {
                ++it;
                continue;
            }
            p.sent_at = seconds();
            idle_.erase(std::find(idle_.begin(), idle_.end(), worker));
            placed_[worker] = p;
            send_task(worker, p.task, placement.gpu_of(p.grant.device));
            it = waiting_.erase(it);
        }
    }

    // After a failure no task is sent: those waiting for a grant give it up.
    void cancel_waiting() {
        for (const Placed& p : waiting_) placements_[static_cast<std::size_t>(p.node)].manager.cancel(p.grant.ticket);
        waiting_.clear();
    }

    // gpu: where a domain task runs, GPU `gpu` of the worker's node or (-1) the CPU.
    void send_task(int worker, int task, int gpu) {
        const TaskNode& n = job_.node(task);
        Packer out;
        out.put<std::int32_t>(task);
        out.put<std::int32_t>(gpu);
        out.put<std::int32_t>(n.left >= 0 ? 2 : 0);
        if (n.left >= 0) {
            out.reserve(Packer::piece_size(*piece(n.left)) + Packer::piece_size(*piece(n.right)));
            out.put_piece(*piece(n.left));
            out.put_piece(*piece(n.right));
            piece(n.left).reset();
            piece(n.right).reset();
        }
        send(out.bytes, worker, kTask);
        running_[worker] = task;
        in_flight_.update(job_, running_, ranks_);
        dispatched_at_[worker] = seconds();
    }

    // A worker's first "ready": the cores it is bound to.
    void take_cores(int worker, const std::vector<std::byte>& message) {
        cpu_set_t& cores = worker_cores_[static_cast<std::size_t>(worker)];
        std::memcpy(&cores, message.data(), sizeof cores);
        cores_known_[static_cast<std::size_t>(worker)] = true;
        CPU_OR(&job_cores_, &job_cores_, &cores);
    }

    void take_result(int worker, const std::vector<std::byte>& message) {
        Unpacker in(message);
        TaskRecord record;
        record.task = in.get<std::int32_t>();
        const double duration = in.get<double>();
        const auto threads = in.get<std::int32_t>();
        record.triangles_in = in.get<std::uint64_t>();
        record.triangles_out = in.get<std::uint64_t>();
        record.samples_out = in.get<std::uint64_t>();
        record.stages = in.get<TaskRecord::Stages>();
        record.field_low = in.get<float>();
        record.field_high = in.get<float>();
        const TaskNode& n = job_.node(record.task);
        record.kind = job_.kind(record.task);
        record.first_domain = n.first;
        record.domain_count = n.count;
        record.rank = worker;
        record.threads = threads;
        record.end = seconds();
        record.start = std::max(0.0, record.end - duration);
        if (const auto it = placed_.find(worker); it != placed_.end()) {
            const Placed& p = it->second;
            placements_[static_cast<std::size_t>(p.node)].finish(p.grant, duration, record);
            record.wait_seconds = p.sent_at - p.asked_at;
            placed_.erase(it);
        }
        piece(record.task) = in.get_piece();
        result_.tasks.push_back(record);
        running_.erase(worker);
        in_flight_.update(job_, running_, ranks_);
        end_lends_to(worker);
        queue_.complete(record.task);
        if (progress_) progress_(++done_, job_.task_count(), seconds());
    }

    void take_failure(int worker, const std::vector<std::byte>& message) {
        Unpacker in(message);
        const int task = in.get<std::int32_t>();
        fail(task, worker, in.get_string());
        if (const auto it = placed_.find(worker); it != placed_.end()) {
            placements_[static_cast<std::size_t>(it->second.node)].manager.cancel(it->second.grant.ticket);
            placed_.erase(it);
        }
        running_.erase(worker);
        in_flight_.update(job_, running_, ranks_);
        end_lends_to(worker);
    }

    // Every worker's first "ready" is received before it is told to stop, so
    // no message is left unmatched at MPI_Finalize.
    void stop_workers() {
        for (int worker = 1; worker < ranks_; ++worker)
            if (!greeted_[static_cast<std::size_t>(worker)]) {
                MPI_Status status;
                receive(worker, status);
            }
        Packer stop;
        stop.put<std::int32_t>(failure_.empty() ? 0 : 1);
        for (int worker = 1; worker < ranks_; ++worker) send(stop.bytes, worker, kStop);
    }

    const Job& job_;
    const int ranks_;
    const Progress& progress_;
    TasksInFlight in_flight_;
    const clock::time_point start_;
    TaskQueue queue_;
    std::vector<std::optional<Piece>> pieces_; // by task, while its parent has not taken it
    std::deque<int> idle_;
    std::map<int, int> running_; // worker -> task
    std::vector<bool> greeted_;
    JobResult result_;
    std::string failure_;
    int done_ = 0;
    cpu_set_t own_cores_;
    bool own_cores_known_;
    cpu_set_t job_cores_; // the union of every rank's cores
    std::vector<cpu_set_t> worker_cores_;
    std::vector<bool> cores_known_;
    std::vector<int> lent_to_;           // lender -> borrower
    std::map<int, int> lends_;           // borrower -> lends it has
    std::map<int, double> dispatched_at_; // worker -> when its task was sent
    // --device auto or gpu: a manager per node, the ranks that drive its
    // GPUs, and each task's grant from the request to its result.
    std::vector<int> node_of_;                 // by rank
    std::vector<int> driving_;                 // by rank: the GPU it drives, -1 for none
    std::map<std::pair<int, int>, int> driver_of_gpu_; // (node, CUDA index) -> rank
    std::deque<NodePlacement> placements_;     // by node
    std::map<int, Placed> placed_;             // worker -> the grant of the task it runs
    std::deque<Placed> waiting_;               // grants not started yet, in the order asked
};

} // namespace

MpiSession::MpiSession() {
    if (!launched_with_mpi()) return;
    int provided = 0;
    // Tasks may use OpenMP threads, but only the main thread calls MPI.
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    active_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    // MPI_Init returns on a rank whose transport failed (Open MPI warns that
    // an mmap of its shared memory failed, and goes on); its messages then
    // never arrive and every rank waits in the first collective. A barrier
    // right after start-up, before any rank does work of its own, completes
    // within moments when all is well; one that does not is that failure.
    MPI_Request started;
    MPI_Ibarrier(MPI_COMM_WORLD, &started);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kMpiStartSeconds);
    for (int done = 0;;) {
        MPI_Test(&started, &done, MPI_STATUS_IGNORE);
        if (done) break;
        if (std::chrono::steady_clock::now() > deadline) {
            if (rank_ == 0)
                std::fprintf(stderr,
                             "tetiso: the %d MPI ranks could not all reach each other within %d s of start-up "
                             "(a rank's MPI transport failed to start: see the launcher's messages); the job is "
                             "stopped\n",
                             size_, kMpiStartSeconds);
            MPI_Abort(MPI_COMM_WORLD, 2);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

MpiSession::~MpiSession() {
    if (active_) MPI_Finalize();
}

bool MpiSession::broadcast(bool value) const {
    if (!active_) return value;
    int flag = value ? 1 : 0;
    MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return flag != 0;
}

bool MpiSession::all(bool value) const {
    if (!active_) return value;
    int flag = value ? 1 : 0, every = 0;
    MPI_Allreduce(&flag, &every, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    return every != 0;
}

std::vector<std::string> MpiSession::all_gather(const std::string& mine) const {
    if (!active_ || size_ == 1) return {mine};
    // Sizes first, -1 for a share too large for MPI's int counts: every rank
    // then refuses together instead of some waiting for the rest.
    const long long size = mine.size() < static_cast<std::size_t>(std::numeric_limits<int>::max()) ? static_cast<long long>(mine.size()) : -1;
    std::vector<long long> sizes(static_cast<std::size_t>(size_));
    MPI_Allgather(&size, 1, MPI_LONG_LONG, sizes.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    long long total = 0;
    for (const long long s : sizes) {
        if (s < 0 || total + s >= std::numeric_limits<int>::max())
            throw Error("the ranks' shares of a .pvtu's scan exceed 2 GB: use fewer pieces per job or split it once with `tetiso split`");
        total += s;
    }
    std::vector<int> counts(sizes.begin(), sizes.end()), offsets(static_cast<std::size_t>(size_), 0);
    for (int r = 1; r < size_; ++r) offsets[static_cast<std::size_t>(r)] = offsets[static_cast<std::size_t>(r - 1)] + counts[static_cast<std::size_t>(r - 1)];
    std::string all(static_cast<std::size_t>(total), '\0');
    MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_CHAR, all.data(), counts.data(), offsets.data(), MPI_CHAR,
                   MPI_COMM_WORLD);
    std::vector<std::string> shares;
    for (int r = 0; r < size_; ++r)
        shares.emplace_back(all, static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                            static_cast<std::size_t>(counts[static_cast<std::size_t>(r)]));
    return shares;
}

RankGroup MpiSession::group() const {
    RankGroup group;
    group.rank = rank_;
    group.size = size_;
    if (active_ && size_ > 1) group.all_gather = [this](const std::string& mine) { return all_gather(mine); };
    return group;
}

std::optional<JobResult> run_mpi(const Job& job, const Progress& progress) {
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (ranks == 1) {
        JobResult result = run_local(job, progress);
        return result;
    }
    // Each rank built its own partition (read the mesh's files, ran METIS):
    // pieces of different partitions would not fit, so all must agree.
    const std::uint64_t mine = job.partition().fingerprint();
    std::uint64_t lowest = 0, highest = 0;
    MPI_Allreduce(&mine, &lowest, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(&mine, &highest, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
    if (lowest != highest) {
        if (rank != 0) throw JobStopped();
        throw Error("the ranks built different partitions of the mesh (its files, or METIS's parts, differ "
                    "between them); no task was run");
    }
    std::optional<NodeLayout> nodes;
    if (job.config().device != JobConfig::Device::cpu) nodes = node_layout(rank, ranks, job.config());
    if (rank != 0) {
        work(job, nodes ? nodes->my_gpu : -1);
        return std::nullopt;
    }
    return Controller(job, ranks, progress, nodes).run();
}

} // namespace tetiso

#else

#include "tetiso/error.hpp"

namespace tetiso {
std::optional<JobResult> run_mpi(const Job&, const Progress&) {
    throw Error("this tetiso was built without MPI");
}
MpiSession::MpiSession() = default;
MpiSession::~MpiSession() = default;
bool MpiSession::broadcast(bool value) const { return value; }
bool MpiSession::all(bool value) const { return value; }
std::vector<std::string> MpiSession::all_gather(const std::string& mine) const { return {mine}; }
RankGroup MpiSession::group() const { return {}; }
} // namespace tetiso

#endif
