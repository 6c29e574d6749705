// STREAM-style memory bandwidth of the machine (McCalpin's STREAM, its Copy
// and Triad kernels), at 1 ... T OpenMP threads, printed as JSON. The paper
// blames memory bandwidth for the speed-up it lost past a few processes;
// results/paper-reproduction sets the job's per-core slowdown beside the
// per-core share of this bandwidth to tell whether that holds here.
//
//   bench_stream [--mib M] [--threads 1,2,4,...] [--repeat R]
//
// Each array holds M MiB (default 1024, far beyond any last-level cache so
// that the kernels stream from memory); the best of R repetitions is kept,
// as STREAM does. Bytes counted as STREAM counts them: Copy 16 B per element
// (read a, write c), Triad 24 B (read b and c, write a), write-allocate
// traffic not included. Dependencies: a C++17 compiler with OpenMP.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

std::vector<int> parse_threads(const char* text) {
    std::vector<int> out;
    for (const char* p = text; *p;) {
        char* end = nullptr;
        const long v = std::strtol(p, &end, 10);
        if (end == p || v < 1) {
            std::fprintf(stderr, "bench_stream: bad --threads list %s\n", text);
            std::exit(2);
        }
        out.push_back(static_cast<int>(v));
        p = *end == ',' ? end + 1 : end;
    }
    return out;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

} // namespace

int main(int argc, char** argv) {
    std::size_t mib = 1024;
    int repeat = 10;
    std::vector<int> threads;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--mib" && i + 1 < argc) {
            mib = std::strtoull(argv[++i], nullptr, 10);
        } else if (arg == "--repeat" && i + 1 < argc) {
            repeat = std::max(1, std::atoi(argv[++i]));
        } else if (arg == "--threads" && i + 1 < argc) {
            threads = parse_threads(argv[++i]);
        } else {
            std::fprintf(stderr, "usage: bench_stream [--mib M] [--threads 1,2,4] [--repeat R]\n");
            return 2;
        }
    }
    if (threads.empty())
        for (int t = 1; t <= omp_get_num_procs(); ++t)
            threads.push_back(t);

    const std::size_t n = mib * (std::size_t{1} << 20) / sizeof(double);
    // new[] without value-initialisation: the first touch happens in the
    // threaded loop below, so that pages land near the threads using them.
    std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
    const double scalar = 3.0;

    std::printf("{\n  \"kernel\": \"STREAM copy and triad, double precision, best of %d\",\n", repeat);
    std::printf("  \"array_mib\": %zu,\n  \"procs\": %d,\n  \"results\": [\n", mib, omp_get_num_procs());
    for (std::size_t k = 0; k < threads.size(); ++k) {
        const int t = threads[k];
        omp_set_num_threads(t);
#pragma omp parallel for schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
            a[i] = 1.0;
            b[i] = 2.0;
            c[i] = 0.0;
        }
        double copy_best = 1e30, triad_best = 1e30, expected = 1.0;
        for (int r = 0; r < repeat; ++r) {
            expected = 2.0 + scalar * expected;
            auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static)
            for (std::size_t i = 0; i < n; ++i)
                c[i] = a[i];
            copy_best = std::min(copy_best, seconds_since(t0));
            t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static)
            for (std::size_t i = 0; i < n; ++i)
                a[i] = b[i] + scalar * c[i];
            triad_best = std::min(triad_best, seconds_since(t0));
        }
        // Read back one element so the compiler keeps every store.
        if (a[n / 2] != expected) {
            std::fprintf(stderr, "bench_stream: wrong result %g\n", a[n / 2]);
            return 1;
        }
        const double gb = 1e9;
        std::printf("    {\"threads\": %d, \"copy_gb_s\": %.3f, \"triad_gb_s\": %.3f}%s\n", t,
                    16.0 * static_cast<double>(n) / copy_best / gb, 24.0 * static_cast<double>(n) / triad_best / gb,
                    k + 1 < threads.size() ? "," : "");
        std::fflush(stdout);
    }
    std::printf("  ]\n}\n");
    return 0;
}
