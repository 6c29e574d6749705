// Under mpirun with 2 ranks or more: a task that throws on rank 0 ends the
// job on every rank as a worker's failure does. Rank 0 runs the root seam
// whenever there are workers, and no input makes that seam alone fail, so a
// Job whose execute throws for a chosen task stands in. The jobs run one after
// another in one MPI session: a message left unmatched by a failed job would
// derail the next one. Exits 0 on every rank when all is as expected.
#include <cstring>
#include <iostream>
#include <optional>
#include <string>

#include "tetiso/error.hpp"
#include "tetiso/schedule.hpp"

namespace {

using namespace tetiso;

class FailingJob : public Job {
public:
    FailingJob(const JobConfig& config, int fail) : Job(config), fail_(fail) {}
    Piece execute(int task, const Piece* left, const Piece* right, TaskRecord& record,
                  const TaskThreads& threads) const override {
        if (task == fail_) throw Error("injected failure");
        return Job::execute(task, left, right, record, threads);
    }

private:
    int fail_;
};

struct Ending {
    std::optional<JobResult> result; // rank 0, when the job succeeded
    bool stopped = false;            // a worker told that the job failed
    std::string error;               // rank 0's error
};

Ending run(const Job& job) {
    Ending ending;
    try {
        ending.result = run_mpi(job, {});
    } catch (const JobStopped&) {
        ending.stopped = true;
    } catch (const Error& e) {
        ending.error = e.what();
    }
    return ending;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_surface(const Piece& a, const Piece& b) {
    return same_bytes(a.x, b.x) && same_bytes(a.y, b.y) && same_bytes(a.z, b.z) && same_bytes(a.key, b.key) &&
           same_bytes(a.flags, b.flags) && same_bytes(a.triangles, b.triangles) &&
           same_bytes(a.domains, b.domains) && same_bytes(a.error, b.error);
}

int failures = 0;
int rank = 0;

void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::cerr << "FAIL (rank " << rank << "): " << what << '\n';
    ++failures;
}

// A failed job: rank 0's error is `message`, or, with `any_worker`, starts
// with it and goes on with a worker's number; every worker was stopped.
void expect_failure(const Ending& ending, const std::string& message, bool any_worker, const std::string& what) {
    if (rank != 0) {
        expect(ending.stopped, what + ": worker not stopped");
        return;
    }
    const bool ok = any_worker ? ending.error.rfind(message, 0) == 0 && ending.error.size() > message.size() &&
                                     ending.error[message.size()] >= '1' && ending.error[message.size()] <= '9'
                               : ending.error == message;
    expect(ok, what + ": rank 0's error is '" + ending.error + "'");
}

} // namespace

int main() {
    try {
        MpiSession mpi;
        rank = mpi.rank();
        if (mpi.size() < 2) {
            std::cerr << "test_mpi_failure: run it under mpirun with 2 ranks or more\n";
            return 2;
        }
        JobConfig config;
        config.lattice = 24;
        config.domains = 8;
        const Job job(config);
        const int root = 0;
        int last_domain = -1;
        for (int t = 0; t < job.task_count(); ++t)
            if (job.kind(t) == TaskKind::domain) last_domain = t;

        // The root seam fails on rank 0.
        expect_failure(run(FailingJob(config, root)),
                       "task '" + job.describe(root) + "' failed on rank 0: injected failure", false, "root seam fails");

        // A domain task fails on a worker: rank 0 never runs domain tasks.
        expect_failure(run(FailingJob(config, last_domain)), "task '" + job.describe(last_domain) + "' failed on rank ",
                       true, "domain task fails");

        // After both, a job succeeds, gives the single-process surface, and
        // its records show rank 0 running the root seam, seams only, and
        // nothing while another task ran.
        const Ending good = run(job);
        if (rank == 0) {
            expect(good.result.has_value(), "job after the failures: " + good.error);
            if (good.result) {
                const JobResult local = run_local(job, {});
                expect(same_surface(good.result->surface, local.surface), "surface differs from the single-process one");
                bool root_here = false;
                for (const TaskRecord& r : good.result->tasks) {
                    if (r.rank != 0) continue;
                    root_here |= r.task == root;
                    expect(r.kind == TaskKind::seam, "rank 0 ran " + job.describe(r.task));
                    for (const TaskRecord& other : good.result->tasks)
                        if (&other != &r)
                            expect(other.end <= r.start + 1e-6 || other.start >= r.end - 1e-6,
                                   job.describe(other.task) + " ran beside " + job.describe(r.task) + " on rank 0");
                }
                expect(root_here, "the root seam did not run on rank 0");
            }
        } else {
            expect(!good.stopped, "worker stopped in the job that should succeed");
        }
    } catch (const std::exception& e) {
        std::cerr << "FAIL (rank " << rank << "): " << e.what() << '\n';
        return 1;
    }
    if (failures == 0 && rank == 0) std::cout << "test_mpi_failure: all as expected\n";
    return failures == 0 ? 0 : 1;
}
