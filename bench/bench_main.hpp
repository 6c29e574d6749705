// The command line and case registration that bench_extract and bench_reduce
// share. Their pages (tools/render_results.py) read the same aggregates under
// the same names, so the defaults, the "min" statistic and the timing mode
// must not drift apart between the programs; keeping them here is what holds
// them together. Header-only: each program
// is one translation unit and this is no part of tetiso's library.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace tetiso_bench {

// A comma-separated list of lattice sizes; a bad list ends the program, named
// by `program`, since a benchmark run on the wrong sizes is worth nothing.
inline std::vector<std::int64_t> parse_sizes(const char* program, const char* text) {
    std::vector<std::int64_t> sizes;
    for (const char* p = text; *p != '\0';) {
        char* end = nullptr;
        const long long value = std::strtoll(p, &end, 10);
        if (end == p || value < 2) {
            std::fprintf(stderr, "%s: bad --sizes list '%s'\n", program, text);
            std::exit(2);
        }
        sizes.push_back(value);
        p = *end == ',' ? end + 1 : end;
    }
    return sizes;
}

// Initializes Google Benchmark and returns the sizes to run: `sizes` unless
// --sizes= names others. Exits with status 1 on flags Google Benchmark does
// not know, after it has named them.
inline std::vector<std::int64_t> initialize(const char* program, int argc, char** argv,
                                            std::vector<std::int64_t> sizes) {
    // Defaults go first so that flags given on the command line override them.
    // Static, as Google Benchmark may keep pointers into its argv.
    static char repetitions[] = "--benchmark_repetitions=5";
    static char aggregates[] = "--benchmark_report_aggregates_only=true";
    static std::vector<char*> args;
    args = {argv[0], repetitions, aggregates};
    for (int i = 1; i < argc; ++i) {
        if (std::strncmp(argv[i], "--sizes=", 8) == 0)
            sizes = parse_sizes(program, argv[i] + 8);
        else
            args.push_back(argv[i]);
    }
    int count = static_cast<int>(args.size());
    benchmark::Initialize(&count, args.data());
    if (benchmark::ReportUnrecognizedArguments(count, args.data())) std::exit(1);
    return sizes;
}

// One thread and every hardware thread: the serial cost and what a whole
// machine makes of it, without a scaling curve the reports do not draw.
inline std::vector<int> thread_counts() {
    const int all_threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    std::vector<int> counts{1};
    if (all_threads > 1) counts.push_back(all_threads);
    return counts;
}

// "<method>/N:<n>/threads:<threads>", the names the reports parse.
inline std::string case_name(const std::string& method, std::int64_t n, int threads) {
    return method + "/N:" + std::to_string(n) + "/threads:" + std::to_string(threads);
}

// The fastest repetition, next to the median: on a shared machine other work
// only ever adds time, so the minimum is the least disturbed measurement.
inline double minimum(const std::vector<double>& values) {
    return *std::min_element(values.begin(), values.end());
}

// Registers a case as both programs time them: real time, since the parallel
// cases' CPU time would count every thread; milliseconds; and the "min"
// aggregate the reports show next to the median. `args` follow the State in
// each call of `fn`.
template <class Fn, class... Args>
benchmark::internal::Benchmark* register_timed(const std::string& name, Fn&& fn, Args&&... args) {
    return benchmark::RegisterBenchmark(name.c_str(), std::forward<Fn>(fn), std::forward<Args>(args)...)
        ->UseRealTime()
        ->ComputeStatistics("min", minimum)
        ->Unit(benchmark::kMillisecond);
}

} // namespace tetiso_bench
