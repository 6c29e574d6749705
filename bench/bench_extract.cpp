// Extraction throughput: tetiso's marching tetrahedra against VTK's
// vtkContour3DLinearGrid (merged points), in one process, on the same
// tetrahedra and the same float field.
//
// The problem is the paper's: the N x N x N lattice as one domain (D = 1), the
// "paper" field, level 0.5. For each N the cases are
//   extract/tetiso/N:<N>/threads:1   tetiso, one thread
//   extract/tetiso/N:<N>/threads:<T> tetiso, every hardware thread
//   extract/vtk/N:<N>/threads:1      VTK, Sequential backend + SequentialProcessing
//   extract/vtk/N:<N>/threads:<T>    VTK, its default backend (for context)
//   extract/gpu/N:<N>/threads:1      tetiso on the GPU (where there is one):
//                                    the whole call, the domain uploaded and
//                                    the piece downloaded each time; counters
//                                    give the three stages' mean seconds
//   extract/gpu-lattice/N:<N>/threads:1  the same from the field values alone:
//                                    the device builds nodes and tetrahedra
//   domain/tetiso/N:<N>/threads:1    make_domain + extract, one thread: a
//                                    domain from nothing, as a job's task
//   domain/gpu/N:<N>/threads:1       field_values + the GPU's lattice path
// Only the extraction is timed: building the domain and converting it to a
// vtkUnstructuredGrid happen once per N, outside the timed loops. All cases
// check their vertex and triangle counts against each other in the report.
//
// Usage: bench_extract [--sizes=100,200] [Google Benchmark flags]
// Without flags it runs 5 repetitions and reports their aggregates only
// (mean, median, stddev, cv, min); tools/render_results.py reads them.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench_main.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"

// TETISO_HAVE_VTK comes with tetiso_reference, when it holds the VTK baseline.
#ifdef TETISO_HAVE_VTK
#include "tetiso/reference.hpp"
#endif

namespace {

constexpr float kLevel = 0.5f;

// Every problem stays built for the whole run, so that repetitions of all
// cases can be interleaved (--benchmark_enable_random_interleaving): on a
// shared machine, a busy spell then slows tetiso and VTK alike instead of
// whichever case happened to be running. N=100 and N=200 together, with their
// VTK copies, hold several GB.
struct Problem {
    tetiso::Domain domain;
#ifdef TETISO_HAVE_VTK
    std::unique_ptr<tetiso::reference::VtkContour> vtk;
#endif
};

Problem& problem(std::int64_t n) {
    static std::map<std::int64_t, Problem> problems;
    auto found = problems.find(n);
    if (found != problems.end()) return found->second;
    Problem p;
    const tetiso::Lattice lattice(n);
    const tetiso::Decomposition decomposition(lattice, 1);
    p.domain = decomposition.make_domain(0, *tetiso::make_field("paper"));
#ifdef TETISO_HAVE_VTK
    p.vtk = std::make_unique<tetiso::reference::VtkContour>(p.domain);
#endif
    return problems.emplace(n, std::move(p)).first->second;
}

void set_size_counters(benchmark::State& state, const tetiso::Domain& domain, std::int64_t vertices,
                       std::int64_t triangles) {
    const auto tets = static_cast<double>(domain.tet_count());
    state.counters["tets/s"] = benchmark::Counter(tets * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate);
    state.counters["tets"] = tets;
    state.counters["nodes"] = static_cast<double>(domain.node_count());
    state.counters["vertices"] = static_cast<double>(vertices);
    state.counters["triangles"] = static_cast<double>(triangles);
}

void bench_tetiso(benchmark::State& state, std::int64_t n, int threads) {
    const Problem& p = problem(n);
    const tetiso::ExtractOptions options{threads};
    std::int64_t vertices = 0, triangles = 0;
    for (auto _ : state) {
        // The piece is freed inside the loop, as VTK frees its previous output.
        const tetiso::Piece piece = tetiso::extract(p.domain, kLevel, options);
        vertices = static_cast<std::int64_t>(piece.vertex_count());
        triangles = static_cast<std::int64_t>(piece.triangle_count());
        benchmark::DoNotOptimize(piece.triangles.data());
    }
    set_size_counters(state, p.domain, vertices, triangles);
}

// One GPU for every case: its buffers outlive a case, as in a worker.
const tetiso::Device& gpu_extractor() {
    static const tetiso::Device gpu = tetiso::Device::cuda();
    return gpu;
}

// A lattice domain as a domain task makes it on a GPU: built on the device.
tetiso::Piece extract_lattice(const tetiso::LatticePartition& lattice, const tetiso::Device& device,
                              tetiso::StageSeconds* seconds = nullptr) {
    tetiso::DomainTaskOptions task;
    task.level = kLevel;
    task.device = device;
    tetiso::DomainTaskResult done = tetiso::run_domain_task(lattice, 0, task);
    if (seconds) *seconds += done.seconds;
    return std::move(done.piece);
}

// Runs `extract` (one GPU call) per iteration; counters: sizes and the mean
// seconds of the call's three stages.
template <class Extract>
void time_gpu(benchmark::State& state, const tetiso::Domain& domain, const Extract& extract) {
    const tetiso::Device& gpu = gpu_extractor();
    std::int64_t vertices = 0, triangles = 0;
    tetiso::StageSeconds sum;
    for (auto _ : state) {
        const tetiso::Piece piece = extract(gpu, &sum);
        vertices = static_cast<std::int64_t>(piece.vertex_count());
        triangles = static_cast<std::int64_t>(piece.triangle_count());
        benchmark::DoNotOptimize(piece.triangles.data());
    }
    set_size_counters(state, domain, vertices, triangles);
    const auto iterations = static_cast<double>(state.iterations());
    state.counters["upload_s"] = sum.upload / iterations;
    state.counters["compute_s"] = sum.extract / iterations;
    state.counters["download_s"] = sum.download / iterations;
}

void bench_gpu(benchmark::State& state, std::int64_t n) {
    const Problem& p = problem(n);
    time_gpu(state, p.domain, [&](const tetiso::Device& gpu, tetiso::StageSeconds* seconds) {
        return tetiso::extract(p.domain, kLevel, tetiso::ExtractOptions{1, gpu}, seconds);
    });
}

void bench_gpu_lattice(benchmark::State& state, std::int64_t n) {
    const Problem& p = problem(n);
    const tetiso::LatticePartition one(n, 1, tetiso::make_field("paper"));
    time_gpu(state, p.domain, [&](const tetiso::Device& gpu, tetiso::StageSeconds* seconds) {
        return extract_lattice(one, gpu, seconds);
    });
}

// A domain from nothing to its piece, as a job's domain task makes it.
void bench_domain(benchmark::State& state, std::int64_t n, bool on_gpu) {
    const Problem& p = problem(n);
    const tetiso::LatticePartition one(n, 1, tetiso::make_field("paper"));
    std::int64_t vertices = 0, triangles = 0;
    for (auto _ : state) {
        const tetiso::Piece piece = on_gpu ? extract_lattice(one, gpu_extractor())
                                           : tetiso::extract(one.make_domain(0), kLevel);
        vertices = static_cast<std::int64_t>(piece.vertex_count());
        triangles = static_cast<std::int64_t>(piece.triangle_count());
        benchmark::DoNotOptimize(piece.triangles.data());
    }
    set_size_counters(state, p.domain, vertices, triangles);
}

#ifdef TETISO_HAVE_VTK
void bench_vtk(benchmark::State& state, std::int64_t n, int threads) {
    Problem& p = problem(n);
    const std::string backend = tetiso::reference::vtk_set_threads(threads);
    state.SetLabel("backend:" + backend);
    tetiso::reference::ContourCounts counts;
    for (auto _ : state) {
        counts = p.vtk->contour(kLevel, threads == 1);
        benchmark::DoNotOptimize(counts);
    }
    set_size_counters(state, p.domain, counts.points, counts.triangles);
}
#endif

} // namespace

int main(int argc, char** argv) {
    using namespace tetiso_bench;
    const std::vector<std::int64_t> sizes = initialize("bench_extract", argc, argv, {100, 200});

    benchmark::AddCustomContext("field", "paper");
    benchmark::AddCustomContext("level", std::to_string(kLevel));
    benchmark::AddCustomContext("domains", "1");
    const tetiso::GpuInfo gpu = tetiso::gpu_info();
    benchmark::AddCustomContext("gpu", gpu.description);
#ifdef TETISO_HAVE_VTK
    benchmark::AddCustomContext("vtk_version", tetiso::reference::vtk_version());
    benchmark::AddCustomContext("vtk_default_backend", tetiso::reference::vtk_default_backend());
#else
    benchmark::AddCustomContext("vtk_default_backend", "none (built without VTK)");
#endif

    for (const std::int64_t n : sizes) {
        for (const int threads : thread_counts())
            register_timed(case_name("extract/tetiso", n, threads), bench_tetiso, n, threads);
#ifdef TETISO_HAVE_VTK
        for (const int threads : thread_counts())
            register_timed(case_name("extract/vtk", n, threads), bench_vtk, n, threads);
#endif
        register_timed(case_name("domain/tetiso", n, 1), bench_domain, n, false);
        if (gpu.available) {
            register_timed(case_name("extract/gpu", n, 1), bench_gpu, n);
            register_timed(case_name("extract/gpu-lattice", n, 1), bench_gpu_lattice, n);
            register_timed(case_name("domain/gpu", n, 1), bench_domain, n, true);
        }
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
