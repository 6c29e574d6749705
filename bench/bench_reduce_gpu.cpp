// Reduction on the GPU against the CPU of the same host, on the two problems
// results/reduce-gpu/ reports:
//   reduce/gpu/N:<N>           the paper surface of the N^3 lattice (D = 1),
//                              reduced at the job's default bound (0.25 h)
//                              by reduce() on a CUDA Device; timed by the device's compute
//                              seconds (the surface already on the device),
//                              upload and download reported beside them
//   reduce/tetiso/N:<N>/threads:T   the CPU's reduce, 1 and every thread
//   reduce/meshopt/N:<N>       meshopt_simplify to tetiso's triangle count
//                              (where this build has meshoptimizer)
//   domain/gpu/N:<N>/D:<D>     one domain task of the N^3 lattice in D domains
//                              (the middle domain), from nothing to its
//                              reduced piece in host memory with its samples,
//                              as the job runs it on a GPU (wall time)
//   domain/tetiso/N:<N>/D:<D>  the same task on one CPU core: field, domain,
//                              extraction, reduction
//   copy/gpu                   a device-to-device copy of 1 GiB: the memory
//                              bandwidth the figures above are measured
//                              against (bytes read plus bytes written)
// Before timing, every GPU case checks that its piece is the CPU's, byte for
// byte; a case that differs says so and fails (the program exits 1).
//
// Usage: bench_reduce_gpu [--sizes=100] [--domain=500:125] [Google Benchmark
// flags]. Without a GPU it runs the CPU cases only.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench_main.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"
#ifdef TETISO_HAVE_MESHOPTIMIZER
#include "tetiso/reference.hpp"
#endif
#ifdef TETISO_HAVE_CUDA
#include <cuda_runtime.h>
#endif

namespace {

constexpr const char* kField = "paper";
bool g_mismatch = false;

// The GPU's reduction and domain task, each keeping its call's seconds by stage.
struct BenchGpu {
    tetiso::Device device = tetiso::Device::cuda();
    tetiso::StageSeconds last;
    const tetiso::StageSeconds& last_timings() const { return last; }
    std::size_t bytes_held() const { return tetiso::Device::gpu_bytes_held(); }
    tetiso::Piece reduce(const tetiso::Piece& raw, tetiso::ReduceOptions options,
                         tetiso::ReduceReport* report = nullptr) {
        options.device = device;
        last = {};
        return tetiso::reduce(raw, options, report, &last);
    }
    tetiso::Piece extract_and_reduce(const tetiso::LatticePartition& lattice, int domain, float level,
                                     const tetiso::ReduceOptions& options) {
        tetiso::DomainTaskOptions task;
        task.level = level;
        task.device = device;
        task.reduce = options;
        tetiso::DomainTaskResult done = tetiso::run_domain_task(lattice, domain, task);
        last = done.seconds;
        return std::move(done.piece);
    }
};

BenchGpu* gpu() {
    static std::unique_ptr<BenchGpu> device = tetiso::gpu_info().available ? std::make_unique<BenchGpu>() : nullptr;
    return device.get();
}

bool same(const tetiso::Piece& a, const tetiso::Piece& b) {
    const auto bits = [](const std::vector<float>& u, const std::vector<float>& v) {
        return u.size() == v.size() && std::memcmp(u.data(), v.data(), u.size() * sizeof(float)) == 0;
    };
    return a.key == b.key && a.flags == b.flags && a.triangles == b.triangles && bits(a.x, b.x) && bits(a.y, b.y) &&
           bits(a.z, b.z) && bits(a.error, b.error) && bits(a.sample_xyz, b.sample_xyz) &&
           a.sample_triangle == b.sample_triangle && a.sampled == b.sampled;
}

void check(const char* what, const tetiso::Piece& cpu, const tetiso::Piece& gpu_piece) {
    if (same(cpu, gpu_piece)) {
        std::fprintf(stderr, "bench_reduce_gpu: %s: the GPU's piece is the CPU's, byte for byte (%zu triangles)\n",
                     what, cpu.triangle_count());
        return;
    }
    std::fprintf(stderr, "bench_reduce_gpu: %s: the GPU's piece DIFFERS from the CPU's\n", what);
    g_mismatch = true;
}

struct Surface {
    tetiso::Piece raw;
    tetiso::ReduceOptions options;
    std::size_t reduced_triangles = 0;
};

Surface& surface(std::int64_t n) {
    static std::map<std::int64_t, Surface> all;
    Surface& s = all[n];
    if (!s.raw.key.empty()) return s;
    const tetiso::Lattice lattice(n);
    const tetiso::Decomposition one(lattice, 1);
    const auto field = tetiso::make_field(kField);
    s.raw = tetiso::extract(one.make_domain(0, *field), static_cast<float>(field->default_level()));
    s.options.max_error = tetiso::JobConfig{}.max_error_spacings * lattice.spacing();
    const tetiso::Piece cpu = tetiso::reduce(s.raw, s.options);
    s.reduced_triangles = cpu.triangle_count();
    if (gpu()) check(("reduce N=" + std::to_string(n)).c_str(), cpu, gpu()->reduce(s.raw, s.options));
    return s;
}

void counters(benchmark::State& state, const Surface& s) {
    const auto in = static_cast<double>(s.raw.triangle_count());
    state.counters["triangles_in"] = in;
    state.counters["triangles_out"] = static_cast<double>(s.reduced_triangles);
    state.counters["tris_in/s"] =
        benchmark::Counter(in * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void bench_gpu_reduce(benchmark::State& state, std::int64_t n) {
    Surface& s = surface(n);
    double upload = 0, download = 0;
    tetiso::ReduceReport report;
    for (auto _ : state) {
        const tetiso::Piece out = gpu()->reduce(s.raw, s.options, &report);
        benchmark::DoNotOptimize(out.triangles.data());
        const tetiso::StageSeconds& t = gpu()->last_timings();
        state.SetIterationTime(t.reduce);
        upload += t.upload;
        download += t.download;
    }
    counters(state, s);
    const auto iterations = static_cast<double>(state.iterations());
    state.counters["upload_s"] = upload / iterations;
    state.counters["download_s"] = download / iterations;
    state.counters["rounds"] = static_cast<double>(report.rounds.size());
    state.counters["device_MiB"] = static_cast<double>(gpu()->bytes_held()) / (1 << 20);
}

void bench_cpu_reduce(benchmark::State& state, std::int64_t n, int threads) {
    Surface& s = surface(n);
    tetiso::ReduceOptions options = s.options;
    options.threads = threads;
    for (auto _ : state) {
        const tetiso::Piece out = tetiso::reduce(s.raw, options);
        benchmark::DoNotOptimize(out.triangles.data());
    }
    counters(state, s);
}

#ifdef TETISO_HAVE_MESHOPTIMIZER
void bench_meshopt(benchmark::State& state, std::int64_t n) {
    Surface& s = surface(n);
    for (auto _ : state) {
        const tetiso::Piece out = tetiso::reference::meshopt_simplify(s.raw, s.reduced_triangles, 1.0f, false, nullptr);
        benchmark::DoNotOptimize(out.triangles.data());
    }
    counters(state, s);
}
#endif

struct DomainTask {
    std::int64_t n;
    int domains;
    int domain;
};

// The job's domain task on the CPU: field, domain, extraction, reduction,
// the samples kept near the interfaces.
tetiso::Piece cpu_domain_task(const tetiso::Decomposition& decomposition, const DomainTask& task,
                              const tetiso::Field& field, const tetiso::ReduceOptions& options) {
    tetiso::Piece piece = tetiso::reduce(
        tetiso::extract(decomposition.make_domain(task.domain, field), static_cast<float>(field.default_level())),
        options);
    tetiso::keep_samples_near_locked(piece, tetiso::JobConfig{}.sample_rings);
    return piece;
}

void bench_domain(benchmark::State& state, DomainTask task, bool on_gpu) {
    const tetiso::LatticePartition partition(task.n, task.domains, tetiso::make_field(kField));
    const tetiso::Lattice& lattice = partition.lattice();
    const tetiso::Decomposition& decomposition = partition.decomposition();
    const tetiso::Field* field = &partition.field();
    tetiso::ReduceOptions options;
    options.max_error = tetiso::JobConfig{}.max_error_spacings * lattice.spacing();
    options.keep_samples = true;
    const auto level = static_cast<float>(field->default_level());
    static bool checked = false;
    if (on_gpu && !checked) {
        checked = true;
        tetiso::Piece g = gpu()->extract_and_reduce(partition, task.domain, level, options);
        tetiso::keep_samples_near_locked(g, tetiso::JobConfig{}.sample_rings);
        check("domain task", cpu_domain_task(decomposition, task, *field, options), g);
    }
    std::size_t triangles = 0;
    double extract = 0, reduce = 0;
    for (auto _ : state) {
        tetiso::Piece piece;
        if (on_gpu) {
            piece = gpu()->extract_and_reduce(partition, task.domain, level, options);
            tetiso::keep_samples_near_locked(piece, tetiso::JobConfig{}.sample_rings);
            extract += gpu()->last_timings().extract;
            reduce += gpu()->last_timings().reduce;
        } else {
            piece = cpu_domain_task(decomposition, task, *field, options);
        }
        triangles = piece.triangle_count();
        benchmark::DoNotOptimize(piece.triangles.data());
    }
    state.counters["nodes"] = static_cast<double>(decomposition.node_count(task.domain));
    state.counters["triangles_out"] = static_cast<double>(triangles);
    if (on_gpu) {
        const auto iterations = static_cast<double>(state.iterations());
        state.counters["extract_s"] = extract / iterations;
        state.counters["reduce_s"] = reduce / iterations;
    }
}

#ifdef TETISO_HAVE_CUDA
// Timed by the device's events around each copy.
void bench_copy(benchmark::State& state) {
    constexpr std::size_t kBytes = std::size_t{1} << 30;
    void *from = nullptr, *to = nullptr;
    cudaEvent_t start, stop;
    if (cudaMalloc(&from, kBytes) != cudaSuccess || cudaMalloc(&to, kBytes) != cudaSuccess ||
        cudaMemset(from, 1, kBytes) != cudaSuccess) {
        state.SkipWithError("cannot allocate 2 GiB on the device");
        cudaFree(from);
        return;
    }
    cudaEventCreate(&start);
    cudaEventCreate(&stop);
    cudaMemcpy(to, from, kBytes, cudaMemcpyDeviceToDevice); // warm up
    for (auto _ : state) {
        cudaEventRecord(start);
        cudaMemcpyAsync(to, from, kBytes, cudaMemcpyDeviceToDevice);
        cudaEventRecord(stop);
        cudaEventSynchronize(stop);
        float ms = 0;
        cudaEventElapsedTime(&ms, start, stop);
        state.SetIterationTime(ms / 1e3);
    }
    state.counters["bytes_moved"] = 2.0 * kBytes;
    state.counters["GB/s"] = benchmark::Counter(2.0 * kBytes * static_cast<double>(state.iterations()) / 1e9,
                                                benchmark::Counter::kIsRate);
    cudaEventDestroy(start);
    cudaEventDestroy(stop);
    cudaFree(from);
    cudaFree(to);
}
#endif

} // namespace

int main(int argc, char** argv) {
    using namespace tetiso_bench;
    DomainTask task{500, 125, 62};
    std::vector<char*> rest{argv[0]};
    for (int i = 1; i < argc; ++i) {
        if (std::strncmp(argv[i], "--domain=", 9) == 0) {
            long long n = 0;
            int d = 0;
            if (std::sscanf(argv[i] + 9, "%lld:%d", &n, &d) != 2 || n < 2 || d < 1) {
                std::fprintf(stderr, "bench_reduce_gpu: bad %s (want N:D)\n", argv[i]);
                return 2;
            }
            task = {n, d, d / 2};
        } else {
            rest.push_back(argv[i]);
        }
    }
    int count = static_cast<int>(rest.size());
    const std::vector<std::int64_t> sizes = initialize("bench_reduce_gpu", count, rest.data(), {100});
    const tetiso::GpuInfo info = tetiso::gpu_info();
    benchmark::AddCustomContext("gpu", info.description);
    benchmark::AddCustomContext("field", kField);
    benchmark::AddCustomContext("max_error_spacings", std::to_string(tetiso::JobConfig{}.max_error_spacings));
    for (const std::int64_t n : sizes) {
        surface(n);
        if (gpu())
            benchmark::RegisterBenchmark(("reduce/gpu/N:" + std::to_string(n)).c_str(), bench_gpu_reduce, n)
                ->UseManualTime()
                ->ComputeStatistics("min", minimum)
                ->Unit(benchmark::kMillisecond);
        for (const int threads : thread_counts())
            register_timed(case_name("reduce/tetiso", n, threads), bench_cpu_reduce, n, threads);
#ifdef TETISO_HAVE_MESHOPTIMIZER
        register_timed(case_name("reduce/meshopt", n, 1), bench_meshopt, n);
#endif
    }
    const std::string domain = "/N:" + std::to_string(task.n) + "/D:" + std::to_string(task.domains);
    if (gpu()) register_timed("domain/gpu" + domain, bench_domain, task, true);
#ifdef TETISO_HAVE_CUDA
    if (gpu())
        benchmark::RegisterBenchmark("copy/gpu", bench_copy)
            ->UseManualTime()
            ->ComputeStatistics("min", minimum)
            ->Unit(benchmark::kMillisecond);
#endif
    register_timed("domain/tetiso" + domain, bench_domain, task, false)->Repetitions(3);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (g_mismatch) {
        std::fprintf(stderr, "bench_reduce_gpu: the GPU's output differed from the CPU's\n");
        return 1;
    }
    return 0;
}
