// The job: every domain extracted and reduced, the pieces seamed pairwise and
// reduced near each seam until one surface remains (paper, sections
// "Problem overview" and "Load balancing and job scheduling").
//
// The tasks form a tree over the decomposition (Job::node): a leaf extracts
// and reduces one domain, an inner node seams the pieces of its two
// children, which are adjacent. Tasks are handed out dynamically to whichever
// worker is free (or, for the last seams, run by the controlling rank), but
// which pieces are seamed together is fixed by the tree, and every task's
// result depends only on its inputs, so the final surface is bit-identical
// for any number of workers and any timing.
#pragma once

#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/field.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/seam.hpp"

namespace tetiso {

// The most streams a GPU's driving process runs (JobConfig::gpu_streams).
inline constexpr int kMaxGpuStreams = 16;

struct JobConfig {
    // The mesh: the N^3 lattice test problem, split into `domains` boxes, or
    // an unstructured TetGen mesh (`mesh`, the base name), split by a
    // partition file or, without one, into `domains` parts by METIS.
    std::int64_t lattice = 0;        // N of the N^3 lattice
    std::filesystem::path mesh;      // a mesh file (mesh_file.hpp: TetGen, .vtu, .pvtu, .msh), instead of the lattice
    std::filesystem::path partition; // with mesh: each tetrahedron's domain, one id per line
    // Or a mesh split into one file per domain (mesh_split.hpp): a rank
    // reads only the domains it works on, and the field and level come with it.
    std::filesystem::path split;
    int domains = 1;                 // D; with a partition file or a split, 0 or its count
    std::string field = "paper";     // built-in name or expression
    std::optional<int> attribute;    // with a TetGen mesh: the field is this node attribute instead
    std::string array;               // with a .vtu, .pvtu or .msh: the field is this point array
    std::string node_ids;            // with a .pvtu: the point array of global node ids
    // The processes of an MPI job, which share out the scan of a .pvtu's
    // pieces (PvtuPartition); the default is one process doing it all.
    RankGroup ranks;
    std::optional<double> level;     // default: the field's own (0 for an attribute)
    bool reduce = true;              // --no-reduce turns every reduction off
    ReduceOptions reduce_options;    // phi and friends; threads is set per task
    // Bound on the reduction's distance to the raw surface, in spacings h
    // (Partition::spacing: the lattice's, or an unstructured mesh's mean edge
    // length; sets reduce_options.max_error); <= 0 leaves it as given.
    double max_error_spacings = 0.25;
    int seam_rings = SeamOptions{}.rings; // reach of the reduction after a seam
    // Raw vertices each piece keeps for later seams (SeamOptions::sample_rings):
    // more reduces the seams further and costs memory and messages; -1 keeps none.
    int sample_rings = SeamOptions{}.sample_rings;
    int threads = 1;                 // threads inside one task
    // Where the domain tasks run: the CPU, this process's GPU `gpu`
    // (extraction and reduction there; seams on the CPU until every domain
    // task is placed, then on GPUs too: placement.hpp), or, with
    // automatic, wherever each node's resource manager predicts a task ends
    // first (resources.hpp). The surface is the same bytes either way.
    enum class Device { cpu, gpu, automatic };
    Device device = Device::cpu;
    // Under --device gpu: the one GPU of each node to use; -1: every GPU of
    // each node (one process drives each), and GPU 0 where a task runs
    // outside a node's placement.
    int gpu = -1;
    // The most domain tasks a GPU grant carries (placement.hpp); 0: the
    // default, kGpuBatchPerStream for each of its streams. 1: one task at a
    // time.
    int gpu_batch = 0;
    // The streams a GPU's driving process runs a grant's domains on, a host
    // thread each, side by side (DomainTaskOptions::lanes): the grant cut
    // into as many runs of consecutive domains. Four ended the N = 1000 job
    // on one H200 1.3-1.8 s before two did (results/reduce-gpu/mpi-polling).
    int gpu_streams = 4;
    // The shortest deadline a task of an MPI job gets, in seconds: a task
    // that has not ended max(this, 10 x its predicted seconds) after it was
    // sent (no deadline before some task has ended) names its rank as
    // stopped answering, and the job is aborted (core/job/scheduler.hpp);
    // workers hold rank 0 to the same. 0: none.
    double task_timeout = 60;
};

enum class TaskKind : std::int32_t { domain = 0, seam = 1 };

// One task of the job's tree: it covers domains [first, first + count); a
// leaf (count 1) is one domain's task, an inner node seams its two
// children's pieces. Unlike the partition's tree nodes it need not cover a box.
struct TaskNode {
    int first = 0;
    int count = 1;
    int left = -1;  // index of the child task, -1 for a leaf
    int right = -1;
};

// The job's task tree for a partition's merge tree: root first, children after their
// parent, leaf tasks in domain order (a lower task index is a lower domain).
//
// The tree is the partition's tree (Partition::tree; the lattice's is its
// bisection) with its rightmost
// path turned into a chain that adds the subtrees hanging off that path one
// at a time, in domain order: ((((A + B) + C) + D) + ...), where the
// bisection tree had (A + (B + (C + (D + ...)))). Domains are handed out in
// id order, so the last to finish are the highest; in the bisection tree
// every seam on their way to the root waited for them, down to the root's,
// which seams the whole middle plane of the lattice. In the chain each
// subtree joins the rest as soon as it is done, the seams along the big
// planes run while workers are still busy with domains, and after the last
// domain only the seams of the last few subtrees remain: the job's serial
// tail, which also grows with the worker count, shrinks. The chain stops at
// the first node of the path that covers at most an eighth of the domains,
// whose bisection subtree joins the rest at the root: each seam of the chain
// seams the whole surface so far, and a chain down to the last domain ended
// the job with nine of them one after the other for 1000 domains.
std::vector<TaskNode> task_tree(const std::vector<DomainTreeNode>& partition_tree);

// The threads a task runs with: `count` to begin with and, where `more` is
// set, what it offers before each reduction round (ReduceOptions::
// more_threads): cores that workers with nothing left to do lend.
struct TaskThreads {
    int count = 1;
    std::function<int()> more;
    // Where a domain task runs when a resource manager placed it (--device
    // auto, and every task of an MPI job): GPU `gpu` of the node, or the CPU
    // (-1). Unset: the job's --device.
    std::optional<int> gpu;
};

struct TaskRecord {
    std::int32_t task = 0;
    TaskKind kind = TaskKind::domain;
    std::int32_t first_domain = 0;   // the task covers domains [first, first + count)
    std::int32_t domain_count = 1;
    std::int32_t rank = 0;           // who ran it
    std::int32_t threads = 1;        // with how many threads (the most it had)
    double start = 0, end = 0;       // seconds since the job started, on rank 0's clock
    std::uint64_t triangles_in = 0;  // extracted triangles, or the two pieces' sum
    std::uint64_t triangles_out = 0;
    // Raw vertices the result carries for later seams (Piece::sample_xyz):
    // what --sample-rings costs in memory and messages, 16 bytes each.
    std::uint64_t samples_out = 0;
    // Where a task's time went, on the rank that ran it: a domain's stages
    // (on a GPU, upload and download too; extract and reduce are then the
    // device's); a seam's merge by key, region near the seam, reduction and
    // splice (SeamReport::Seconds).
    struct Stages : StageSeconds {
        double merge = 0, region = 0, splice = 0;
        std::int32_t gpu = -1; // the GPU a domain task ran on, -1 for the CPU
    } stages;
    // With --device auto (or gpu under MPI): the seconds the node's resource
    // manager predicted for the task on the device it granted, and how long
    // the task waited for that grant (0 otherwise).
    double predicted_seconds = 0, wait_seconds = 0;
    // A domain task's lowest and highest field value (none, low > high,
    // where the values stayed on a GPU): a surface that comes out empty
    // says whether its level lies outside them.
    float field_low = std::numeric_limits<float>::infinity();
    float field_high = -std::numeric_limits<float>::infinity();
};

struct JobResult {
    Piece surface;
    std::vector<TaskRecord> tasks;   // in completion order
    int ranks = 1;
    double seconds = 0;
    // Job::probe_cpu's rate where the job measured it (the CPU's prior under
    // --device auto), else 0.
    double cpu_seconds_per_triangle = 0;
};

// The lattice of Job::probe_cpu: the paper's field on 16^3 nodes, 26,552 raw
// triangles. Its rate was within 10 % of Job::execute's on the middle domain
// of three jobs, one thread each (paper N = 500 / 125 domains, gyroid 400 /
// 64, sphere 300 / 27: 80,000-360,000 raw triangles) on a 2-core Debian 12
// VM at commit d214b57; on 12^3 nodes it was 35 % low.
inline constexpr std::int64_t kCpuProbeLattice = 16;

// Called by the controlling process after each task: tasks done, total, and
// seconds since the start.
using Progress = std::function<void(int, int, double)>;

// Everything a rank needs to run tasks: the mesh's partition and the field.
// Building it validates the configuration and reads any files (throws
// tetiso::Error); every rank builds its own, and an MPI job checks that all
// agree (Partition::fingerprint) before it starts.
class Job {
public:
    explicit Job(const JobConfig& config);
    virtual ~Job();

    const JobConfig& config() const { return config_; }
    const Partition& partition() const { return *partition_; }
    float level() const { return level_; }
    int task_count() const { return static_cast<int>(tree_.size()); }
    const TaskNode& node(int task) const { return tree_[static_cast<std::size_t>(task)]; }
    TaskKind kind(int task) const { return node(task).count == 1 ? TaskKind::domain : TaskKind::seam; }
    std::string describe(int task) const;

    // Runs one task. A domain task takes no pieces; a seam task takes its
    // two children's. Fills triangles_in / triangles_out of `record`. The
    // result does not depend on `threads` (config().threads, except where
    // the rank running the task has borrowed idle workers' cores). Virtual so
    // that a test can make a task fail that no input makes fail, such as the
    // root seam, which runs on rank 0 (validation/mpi/test_mpi_failure.cpp).
    virtual Piece execute(int task, const Piece* left, const Piece* right, TaskRecord& record,
                          const TaskThreads& threads) const;

    // Runs several domain tasks in one call on GPU `threads.gpu` (or the
    // job's device): run_domain_tasks reduces them side by side. Pieces and
    // records in the order of `tasks`, each what execute() gives for the
    // task alone; each record's seconds are its share of the batch's. Where
    // the batch throws, each task is run alone to find the one that fails,
    // which a BatchTaskError names.
    std::vector<Piece> execute_batch(const std::vector<int>& tasks, std::vector<TaskRecord>& records,
                                     const TaskThreads& threads) const;

    // Makes this process's Device for CUDA device `gpu` and runs a small
    // batch of two domains on it, so that the context, the kernels' loading and the first
    // allocations are paid before the job's first task there (a GPU's
    // driving process does this at start-up: the first task would otherwise
    // take seconds and teach the resource manager that the GPU is slow).
    // Throws tetiso::Error where the device cannot be used.
    void prepare_gpu(int gpu) const;

    // Seconds per raw triangle of a domain task on one core of this process,
    // from a small reduction of its own (the CPU's prior in the resource
    // manager: placement.hpp). Takes a few tenths of a second.
    double probe_cpu() const;

private:
    ReduceOptions reduce_options(const TaskThreads& threads) const {
        ReduceOptions options = reduce_options_;
        options.threads = threads.count;
        options.more_threads = threads.more;
        return options;
    }

    // CUDA device `index` of this process's node, made at its first use:
    // its first stream; gpu_lanes: all config().gpu_streams of them.
    const Device& gpu(int index) const;
    const std::vector<Device>& gpu_lanes(int index) const;
    // options' device and lanes: GPU `index`'s streams.
    void use_gpu(int index, DomainTaskOptions& options) const;
    // Where a domain task runs (-1: the CPU), its options, and the samples
    // its piece keeps.
    int gpu_of(const TaskThreads& threads) const;
    DomainTaskOptions domain_options(const TaskThreads& threads) const;
    void keep_samples(DomainTaskResult& done) const;

    JobConfig config_;
    std::unique_ptr<Partition> partition_;
    // Made by prepare_gpu or at the first domain task that runs on each GPU
    // (rank 0 of an MPI job runs only seams, and needs none); kept for the
    // next.
    mutable std::map<int, std::vector<Device>> gpus_;
    std::vector<TaskNode> tree_;
    float level_ = 0;
    ReduceOptions reduce_options_;
};

// Which task to hand out next: a seam as soon as both its pieces exist (it
// frees memory and is on the way to the root), else the lowest domain, so
// subtrees complete early. Only timing depends on this order, never output.
class TaskQueue {
public:
    explicit TaskQueue(const Job& job);
    bool has_ready() const { return !ready_.empty(); }
    std::size_t ready_count() const { return ready_.size(); }
    int peek() const { return ready_.begin()->second; } // what pop() would return
    int pop();
    // Marks `task` done; its parent becomes ready once both children are.
    void complete(int task);
    bool finished() const { return done_root_; }

private:
    std::vector<int> parent_;
    std::vector<int> children_done_;
    std::set<std::pair<int, int>> ready_; // (priority class, task)
    bool done_root_ = false;
};

// Runs every task in this process, in TaskQueue order.
JobResult run_local(const Job& job, const Progress& progress);

// Whether this process was started by an MPI launcher with several ranks
// (and tetiso was built with MPI).
bool launched_with_mpi();

// Runs the job over MPI_COMM_WORLD: rank 0 controls, and runs the seams that
// no other task can run beside (the chain up to the root at the end); the
// others work. The caller has initialised MPI. Returns the result on rank 0,
// nullopt on workers; a task run by rank 0 is recorded with rank 0. A task
// that throws, on any rank, ends the job on every rank: rank 0 throws
// tetiso::Error naming the task and rank, workers throw JobStopped. A rank
// that stops answering (JobConfig::task_timeout) is named on stderr, by rank 0
// or, for rank 0, by a worker, and the job is aborted with status 2.
std::optional<JobResult> run_mpi(const Job& job, const Progress& progress);

// MPI for the lifetime of the object, when launched_with_mpi(); otherwise a
// single rank of one. Finalises on destruction, also when unwinding from an
// error, so that every rank leaves cleanly. The constructor checks that every
// rank can reach every other (a rank whose transport failed to start, e.g.
// its shared memory could not be mapped, would leave the others waiting in
// their first collective for ever): where that takes more than
// kMpiStartSeconds, rank 0 says so and the job is aborted.
inline constexpr int kMpiStartSeconds = 10;

class MpiSession {
public:
    MpiSession();
    ~MpiSession();
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;
    int rank() const { return rank_; }
    int size() const { return size_; }
    // Rank 0's value, on every rank.
    bool broadcast(bool value) const;
    // Whether `value` is true on every rank, on every rank.
    bool all(bool value) const;
    // Every rank's `mine`, in rank order, on every rank; throws
    // tetiso::Error on every rank if any share is 2 GB or more.
    std::vector<std::string> all_gather(const std::string& mine) const;
    // This session as a RankGroup (one process where MPI is not running).
    RankGroup group() const;

private:
    bool active_ = false;
    int rank_ = 0, size_ = 1;
};

// A task of a batch (Job::execute_batch) that failed, and why.
struct BatchTaskError : std::runtime_error {
    BatchTaskError(int failed_task, const std::string& what) : std::runtime_error(what), task(failed_task) {}
    int task;
};

// Thrown on worker ranks when the job ended because of a failure elsewhere;
// rank 0 has reported it.
struct JobStopped : std::runtime_error {
    JobStopped() : std::runtime_error("job stopped") {}
};

} // namespace tetiso
