// One domain's task (domain_task.hpp): the domain made where its Device
// wants it, extraction, then reduction, each stage timed.
#include "tetiso/domain_task.hpp"

#include <algorithm>
#include <chrono>
#include <exception>
#include <thread>

#include "device_entry.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/seam.hpp"

namespace tetiso {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::optional<ReduceOptions> reduce_options_of(const DomainTaskOptions& options) {
    std::optional<ReduceOptions> reduce = options.reduce;
    if (reduce) reduce->device = options.device;
    return reduce;
}

// A lattice domain on a GPU: built, extracted and reduced on the device.
DomainTaskResult run_on_gpu(const LatticePartition& lattice, int domain, const DomainTaskOptions& options) {
    DomainTaskResult result;
    const std::optional<ReduceOptions> reduce = reduce_options_of(options);
    ReduceReport report;
    result.piece = on_gpu::extract(options.device.state(), lattice.decomposition(), domain, lattice.field(),
                                   options.level, reduce ? &*reduce : nullptr, &report, &result.seconds);
    result.triangles_extracted = reduce ? report.triangles_in : result.piece.triangle_count();
    return result;
}

// A domain built on the host; `manifold`: its piece has no pinch.
DomainTaskResult run_built(Domain domain, bool manifold, const DomainTaskOptions& options,
                           DomainTaskResult result = {}) {
    const std::optional<ReduceOptions> reduce = reduce_options_of(options);
    if (!options.device.is_gpu() && !domain.f.empty()) {
        const auto [low, high] = std::minmax_element(domain.f.begin(), domain.f.end());
        result.field_low = *low;
        result.field_high = *high;
    }
    if (options.device.is_gpu() && reduce && manifold) {
        ReduceReport report;
        result.piece = on_gpu::extract(options.device.state(), domain, options.level, &*reduce, &report,
                                       &result.seconds);
        result.triangles_extracted = report.triangles_in;
        return result;
    }
    result.piece = extract(domain, options.level, ExtractOptions{options.threads, options.device}, &result.seconds);
    result.triangles_extracted = result.piece.triangle_count();
    domain = Domain(); // the tetrahedra go before the reduction needs its memory
    if (!reduce) return result;
    const auto t = std::chrono::steady_clock::now();
    result.piece = manifold ? tetiso::reduce(result.piece, *reduce) : reduce_piece(result.piece, *reduce);
    result.seconds.reduce += seconds_since(t);
    return result;
}

} // namespace

DomainTaskResult run_domain_task(const Partition& partition, int domain, const DomainTaskOptions& options) {
    const auto* lattice = dynamic_cast<const LatticePartition*>(&partition);
    if (lattice && options.device.is_gpu()) return run_on_gpu(*lattice, domain, options);
    const auto start = std::chrono::steady_clock::now();
    Domain built = partition.make_domain(domain);
    DomainTaskResult result;
    result.seconds.generate = seconds_since(start);
    return run_built(std::move(built), partition.pieces_are_manifold(), options, std::move(result));
}

namespace {

std::vector<DomainTaskResult> run_on_one_device(const Partition& partition, const std::vector<int>& domains,
                                                const DomainTaskOptions& options) {
    if (options.device.is_gpu() && options.reduce && !domains.empty()) {
        const std::optional<ReduceOptions> reduce = reduce_options_of(options);
        Device::State& gpu = options.device.state();
        std::vector<on_gpu::BatchTask> tasks;
        if (const auto* lattice = dynamic_cast<const LatticePartition*>(&partition))
            tasks = on_gpu::extract_batch(gpu, lattice->decomposition(), domains, lattice->field(), options.level,
                                          *reduce, options.batch_triangles);
        else if (partition.pieces_are_manifold())
            tasks = on_gpu::extract_batch(
                gpu, domains.size(), [&](std::size_t i) { return partition.make_domain(domains[i]); }, options.level,
                *reduce, options.batch_triangles);
        if (!tasks.empty()) {
            std::vector<DomainTaskResult> results(tasks.size());
            for (std::size_t i = 0; i < tasks.size(); ++i) {
                results[i].piece = std::move(tasks[i].piece);
                results[i].seconds = tasks[i].seconds;
                results[i].triangles_extracted = tasks[i].triangles_extracted;
            }
            return results;
        }
    }
    std::vector<DomainTaskResult> results;
    results.reserve(domains.size());
    for (const int domain : domains) results.push_back(run_domain_task(partition, domain, options));
    return results;
}

// The domains cut into `parts` runs of consecutive ones, of counts that
// differ by one at most, each run on its own Device by a thread of its own.
// An error is the first failing run's: its first failing domain is the first
// of the call.
std::vector<DomainTaskResult> run_in_lanes(const Partition& partition, const std::vector<int>& domains,
                                           const DomainTaskOptions& options, std::size_t parts) {
    std::vector<const Device*> devices{&options.device};
    for (std::size_t p = 1; p < parts; ++p) devices.push_back(&options.lanes[p - 1]);
    for (std::size_t a = 0; a < parts; ++a) {
        if (!devices[a]->is_gpu()) throw Error("run_domain_tasks: a lane is the host, not a CUDA Device");
        for (std::size_t b = 0; b < a; ++b)
            if (&devices[a]->state() == &devices[b]->state())
                throw Error("run_domain_tasks: one CUDA Device given as two lanes (each needs its own)");
    }
    std::vector<std::vector<DomainTaskResult>> done(parts);
    std::vector<std::exception_ptr> failed(parts);
    const auto run_part = [&](std::size_t p) {
        const auto first = static_cast<std::ptrdiff_t>(domains.size() * p / parts);
        const auto last = static_cast<std::ptrdiff_t>(domains.size() * (p + 1) / parts);
        DomainTaskOptions lane = options;
        lane.lanes.clear();
        lane.device = *devices[p];
        try {
            done[p] = run_on_one_device(partition, std::vector<int>(domains.begin() + first, domains.begin() + last),
                                        lane);
        } catch (...) {
            failed[p] = std::current_exception();
        }
    };
    std::vector<std::thread> threads;
    for (std::size_t p = 1; p < parts; ++p) threads.emplace_back(run_part, p);
    run_part(0);
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& e : failed)
        if (e) std::rethrow_exception(e);
    std::vector<DomainTaskResult> results;
    results.reserve(domains.size());
    for (std::vector<DomainTaskResult>& part : done)
        for (DomainTaskResult& r : part) results.push_back(std::move(r));
    return results;
}

} // namespace

std::vector<DomainTaskResult> run_domain_tasks(const Partition& partition, const std::vector<int>& domains,
                                               const DomainTaskOptions& options) {
    const std::size_t parts = options.device.is_gpu() ? std::min(domains.size(), 1 + options.lanes.size()) : 1;
    if (parts > 1) return run_in_lanes(partition, domains, options, parts);
    return run_on_one_device(partition, domains, options);
}

DomainTaskResult run_domain_task(Domain domain, const DomainTaskOptions& options) {
    return run_built(std::move(domain), true, options);
}

} // namespace tetiso
