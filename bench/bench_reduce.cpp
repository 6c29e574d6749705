// Reduction speed and quality: tetiso's Φ-driven parallel edge collapse and
// flip against three serial quadric edge-collapse simplifiers, in one
// process, on the same surface and to the same triangle count:
// meshoptimizer's meshopt_simplify (the fast one, which does not keep
// topology) and, where this build has them, CGAL's edge_collapse with
// Garland–Heckbert plane quadrics and OpenMesh's DecimaterT with ModQuadricT
// (the careful ones, which do).
//
// The surface is the paper's: every domain of the N x N x N lattice with D = 1,
// the "paper" field at its default level, extracted and merged by key as
// `tetiso extract` does. For each N the cases are
//   reduce/tetiso/N:<N>/threads:1    tetiso, default ReduceOptions except
//                                    max_error = 0.25 h, as `tetiso run` sets it
//   reduce/tetiso/N:<N>/threads:<T>  the same, every hardware thread
//   reduce/meshopt/N:<N>/threads:1   meshopt_simplify to tetiso's triangle
//                                    count, error unbounded (target_error 1)
//   reduce/cgal/N:<N>/threads:1      CGAL, to the same count
//   reduce/openmesh/N:<N>/threads:1  OpenMesh, to the same count
// Only the simplification call is timed; for a baseline that includes its
// adapter's copy into the library's mesh and back to a Piece, as tetiso's
// time includes its input checks and compaction. The careful baselines take
// tens of seconds at N = 100, so they run --slow_repetitions times (default
// 3) rather than the --benchmark_repetitions of the others.
//
// Quality is measured once per case, outside the timed loop, on the case's
// own output, and reported as counters (their median is the value itself):
//   hausdorff, hausdorff_h       symmetric Hausdorff distance to the raw
//                                surface, absolute and in lattice spacings h
//   same_topology                1 when every component keeps its (genus,
//                                boundary loops, orientability) signature
//   non_manifold_edges/_vertices, degenerate_triangles,
//   near_degenerate_triangles, misoriented_edges   from check_topology
//   self_intersections           CGAL's count; absent where it cannot be
//                                measured (no CGAL, or a mesh CGAL cannot
//                                take without splitting it)
// The raw surface's own figures go into the JSON context ("raw/N:<N>/...").
//
// Usage: bench_reduce [--sizes=100] [Google Benchmark flags]
// Without flags it runs 5 repetitions and reports their aggregates only
// (mean, median, stddev, cv, min); tools/render_results.py reads them.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench_main.hpp"
#include "tetiso/check.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/reference.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"

namespace {

constexpr const char* kField = "paper";

struct Quality {
    std::int64_t triangles_out = 0;
    double hausdorff = 0.0, hausdorff_h = 0.0;
    bool same_topology = false;
    std::int64_t non_manifold_edges = 0, non_manifold_vertices = 0, misoriented_edges = 0;
    std::int64_t degenerate_triangles = 0, near_degenerate_triangles = 0;
    std::optional<std::size_t> self_intersections;
};

// Every problem is built before the first case runs, so that repetitions of
// all cases can be interleaved (--benchmark_enable_random_interleaving) and
// meshoptimizer's target is known whichever case comes first.
struct Problem {
    double spacing = 0.0;
    tetiso::Piece raw;
    tetiso::TopologyReport raw_topology;
    tetiso::ReduceOptions options;        // threads set per case
    std::size_t tetiso_triangles = 0;     // meshoptimizer's target
    std::map<std::string, Quality> quality; // by method and threads, filled once
};

std::map<std::int64_t, Problem>& problems() {
    static std::map<std::int64_t, Problem> all;
    return all;
}

// The library's own stages, in `tetiso extract`'s order: with D = 1 the merge
// and the unlocking change nothing, but they keep this surface the one every
// other consumer builds.
tetiso::Piece paper_surface(const tetiso::Lattice& lattice) {
    const tetiso::Decomposition decomposition(lattice, 1);
    const auto field = tetiso::make_field(kField);
    const auto level = static_cast<float>(field->default_level());
    std::vector<tetiso::Piece> pieces;
    for (int d = 0; d < decomposition.domain_count(); ++d)
        pieces.push_back(tetiso::extract(decomposition.make_domain(d, *field), level));
    tetiso::Piece surface = tetiso::merge_all(std::move(pieces));
    tetiso::unlock_settled(surface, [&](tetiso::GlobalId a, tetiso::GlobalId b) {
        return decomposition.domains_of_edge(a, b);
    });
    return surface;
}

void build_problem(std::int64_t n) {
    Problem& p = problems()[n];
    const tetiso::Lattice lattice(n);
    p.spacing = lattice.spacing();
    p.raw = paper_surface(lattice);
    p.raw_topology = tetiso::check_topology(p.raw);
    p.options.max_error = tetiso::JobConfig{}.max_error_spacings * p.spacing;
    // One untimed reduction: it fixes meshoptimizer's target, and the output
    // does not depend on the thread count (reduce.hpp), so it holds for all
    // tetiso cases; the report checks that they agree.
    p.tetiso_triangles = tetiso::reduce(p.raw, p.options).triangle_count();

    const std::string prefix = "raw/N:" + std::to_string(n) + "/";
    const auto context = [&](const std::string& key, const std::string& value) {
        benchmark::AddCustomContext(prefix + key, value);
    };
    context("spacing", std::to_string(p.spacing));
    context("max_error", std::to_string(p.options.max_error));
    context("triangles", std::to_string(p.raw.triangle_count()));
    context("vertices", std::to_string(p.raw.vertex_count()));
    context("components", std::to_string(p.raw_topology.components));
    context("non_manifold_edges", std::to_string(p.raw_topology.non_manifold_edges));
    context("non_manifold_vertices", std::to_string(p.raw_topology.non_manifold_vertices));
    context("degenerate_triangles", std::to_string(p.raw_topology.degenerate_triangles));
    context("near_degenerate_triangles", std::to_string(p.raw_topology.near_degenerate_triangles));
    const auto crossings = tetiso::count_self_intersections(p.raw);
    context("self_intersections", crossings ? std::to_string(*crossings) : "not measured");
}

const Quality& quality(Problem& p, const std::string& name, const tetiso::Piece& out) {
    auto found = p.quality.find(name);
    if (found != p.quality.end()) return found->second;
    Quality q;
    const tetiso::TopologyReport topology = tetiso::check_topology(out);
    q.triangles_out = static_cast<std::int64_t>(out.triangle_count());
    q.hausdorff = tetiso::hausdorff(p.raw, out).symmetric;
    q.hausdorff_h = q.hausdorff / p.spacing;
    q.same_topology = tetiso::same_signatures(p.raw_topology, topology);
    q.non_manifold_edges = topology.non_manifold_edges;
    q.non_manifold_vertices = topology.non_manifold_vertices;
    q.misoriented_edges = topology.misoriented_edges;
    q.degenerate_triangles = topology.degenerate_triangles;
    q.near_degenerate_triangles = topology.near_degenerate_triangles;
    q.self_intersections = tetiso::count_self_intersections(out);
    return p.quality.emplace(name, q).first->second;
}

void set_counters(benchmark::State& state, const Problem& p, const Quality& q) {
    const auto in = static_cast<double>(p.raw.triangle_count());
    state.counters["tris_in/s"] =
        benchmark::Counter(in * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["triangles_in"] = in;
    state.counters["triangles_out"] = static_cast<double>(q.triangles_out);
    state.counters["hausdorff"] = q.hausdorff;
    state.counters["hausdorff_h"] = q.hausdorff_h;
    state.counters["same_topology"] = q.same_topology ? 1.0 : 0.0;
    state.counters["non_manifold_edges"] = static_cast<double>(q.non_manifold_edges);
    state.counters["non_manifold_vertices"] = static_cast<double>(q.non_manifold_vertices);
    state.counters["misoriented_edges"] = static_cast<double>(q.misoriented_edges);
    state.counters["degenerate_triangles"] = static_cast<double>(q.degenerate_triangles);
    state.counters["near_degenerate_triangles"] = static_cast<double>(q.near_degenerate_triangles);
    if (q.self_intersections) state.counters["self_intersections"] = static_cast<double>(*q.self_intersections);
}

void bench_tetiso(benchmark::State& state, std::int64_t n, int threads) {
    Problem& p = problems().at(n);
    tetiso::ReduceOptions options = p.options;
    options.threads = threads;
    tetiso::Piece out;
    tetiso::ReduceReport report;
    for (auto _ : state) {
        // Assigning frees the previous output inside the loop, as it is for
        // meshoptimizer.
        out = tetiso::reduce(p.raw, options, &report);
        benchmark::DoNotOptimize(out.triangles.data());
    }
    set_counters(state, p, quality(p, "tetiso/threads:" + std::to_string(threads), out));
    state.counters["rounds"] = static_cast<double>(report.rounds.size());
}

void bench_meshopt(benchmark::State& state, std::int64_t n) {
    Problem& p = problems().at(n);
    tetiso::Piece out;
    float error = 0.0f;
    for (auto _ : state) {
        out = tetiso::reference::meshopt_simplify(p.raw, p.tetiso_triangles, 1.0f, false, &error);
        benchmark::DoNotOptimize(out.triangles.data());
    }
    set_counters(state, p, quality(p, "meshopt", out));
    // meshoptimizer's own error estimate, relative to the surface's extent.
    state.counters["meshopt_error"] = error;
}

// A careful baseline: name, and its adapter from reference.hpp.
void bench_careful(benchmark::State& state, std::int64_t n, const std::string& name,
                   tetiso::Piece (*simplify)(const tetiso::Piece&, std::size_t)) {
    Problem& p = problems().at(n);
    tetiso::Piece out;
    for (auto _ : state) {
        out = simplify(p.raw, p.tetiso_triangles);
        benchmark::DoNotOptimize(out.triangles.data());
    }
    set_counters(state, p, quality(p, name, out));
}

} // namespace

int main(int argc, char** argv) {
    using namespace tetiso_bench;
    // Taken out before Google Benchmark sees the flags.
    int slow_repetitions = 3;
    std::vector<char*> rest{argv[0]};
    for (int i = 1; i < argc; ++i) {
        if (std::strncmp(argv[i], "--slow_repetitions=", 19) == 0) {
            slow_repetitions = std::atoi(argv[i] + 19);
            if (slow_repetitions < 1) {
                std::fprintf(stderr, "bench_reduce: bad %s\n", argv[i]);
                return 2;
            }
        } else {
            rest.push_back(argv[i]);
        }
    }
    int rest_count = static_cast<int>(rest.size());
    const std::vector<std::int64_t> sizes = initialize("bench_reduce", rest_count, rest.data(), {100});

    const auto field = tetiso::make_field(kField);
    const tetiso::ReduceOptions defaults;
    benchmark::AddCustomContext("field", kField);
    benchmark::AddCustomContext("level", std::to_string(field->default_level()));
    benchmark::AddCustomContext("domains", "1");
    benchmark::AddCustomContext("phi", std::to_string(defaults.phi));
    benchmark::AddCustomContext("max_error_spacings", std::to_string(tetiso::JobConfig{}.max_error_spacings));
    benchmark::AddCustomContext("self_intersections_available", tetiso::have_self_intersections() ? "yes" : "no");

    for (const std::int64_t n : sizes) {
        build_problem(n);
        for (const int threads : thread_counts())
            register_timed(case_name("reduce/tetiso", n, threads), bench_tetiso, n, threads);
        // meshoptimizer is serial: one case, named like the others.
        register_timed(case_name("reduce/meshopt", n, 1), bench_meshopt, n);
#ifdef TETISO_HAVE_CGAL_SIMPLIFY
        register_timed(case_name("reduce/cgal", n, 1), bench_careful, n, std::string("cgal"),
                       &tetiso::reference::cgal_simplify)
            ->Repetitions(slow_repetitions);
#endif
#ifdef TETISO_HAVE_OPENMESH
        register_timed(case_name("reduce/openmesh", n, 1), bench_careful, n, std::string("openmesh"),
                       &tetiso::reference::openmesh_decimate)
            ->Repetitions(slow_repetitions);
#endif
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
