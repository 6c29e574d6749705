// Many domains in flight on one GPU, through several streams and through
// batches (run_domain_tasks: B domains' pieces reduced side by side in one
// set of rounds): the domain tasks of the lattice job (the paper field, the job's error bound, samples
// kept near the interfaces, as Job::execute runs them) on K CUDA Devices of
// one GPU, each driven by its own host thread, the threads pulling domains
// from one shared counter, B domains at a time. K = 1, B = 1 is one domain
// after another on one Device.
// For each K the same domains run twice on the same Devices: "cold", while
// their buffers still grow (each growth waits for the whole device), and
// "warm", as a long job sees them. The CPU runs the same domains too, one
// domain per thread with one thread each on every core: the comparison the
// resource manager makes between a GPU and the cores.
//
// Every domain's piece, from every K, B and from the CPU, must be the first
// run's piece byte for byte; one that differs is named and the program
// exits 1.
//
// Usage: bench_gpu_streams [--lattice=N] [--domains=D] [--count=M]
//   [--pick=spread|first] [--streams=1,2,4,8,16] [--batches=1] [--cpu-threads=T]
//   [--cpu-batches=1] [--no-cpu] [--json=FILE]
// Each K of --streams runs with each B of --batches. On the CPU, B > 1 of
// --cpu-batches extracts B domains and reduces their pieces in one host
// reduce_batch (what run_domain_tasks would do if it batched on the host).
// M domains of the N^3 lattice cut in D (spread: every D/M-th domain, so
// that the sample holds the job's mix of empty and crossed domains; first:
// domains 0..M-1). Writes one JSON object (stdout, or FILE) and a table to
// stderr. Exits 2 on a bad option, 1 on a mismatch, 3 without a GPU.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <cuda_runtime.h>

#include "tetiso/device.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/schedule.hpp"
#include "tetiso/seam.hpp"

namespace {

constexpr const char* kProgram = "bench_gpu_streams";
constexpr const char* kField = "paper";

struct Options {
    std::int64_t lattice = 1000;
    int domains = 1000;
    int count = 64;
    bool spread = true;
    std::vector<int> streams{1, 2, 4, 8, 16};
    std::vector<int> batches{1};
    std::vector<int> cpu_batches{1};
    int cpu_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    bool cpu = true;
    std::string json;
};

[[noreturn]] void bad_option(const std::string& option, const std::string& why) {
    std::fprintf(stderr, "%s: %s: %s\n", kProgram, option.c_str(), why.c_str());
    std::exit(2);
}

long long parse_number(const std::string& option, const std::string& text, long long low) {
    char* end = nullptr;
    const long long value = std::strtoll(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || value < low) bad_option(option, "want an integer >= " + std::to_string(low));
    return value;
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const std::size_t eq = arg.find('=');
        const std::string name = arg.substr(0, eq), value = eq == std::string::npos ? "" : arg.substr(eq + 1);
        if (name == "--lattice") o.lattice = parse_number(arg, value, 2);
        else if (name == "--domains") o.domains = static_cast<int>(parse_number(arg, value, 1));
        else if (name == "--count") o.count = static_cast<int>(parse_number(arg, value, 1));
        else if (name == "--cpu-threads") o.cpu_threads = static_cast<int>(parse_number(arg, value, 1));
        else if (name == "--no-cpu" && eq == std::string::npos) o.cpu = false;
        else if (name == "--json") o.json = value;
        else if (name == "--pick" && (value == "spread" || value == "first")) o.spread = value == "spread";
        else if (name == "--streams" || name == "--batches" || name == "--cpu-batches") {
            std::vector<int>& list = name == "--streams" ? o.streams : name == "--batches" ? o.batches : o.cpu_batches;
            list.clear();
            std::stringstream items(value);
            for (std::string item; std::getline(items, item, ',');)
                list.push_back(static_cast<int>(parse_number(arg, item, 1)));
            if (list.empty()) bad_option(arg, "want a list of counts");
        } else {
            bad_option(arg, "unknown option");
        }
    }
    if (o.count > o.domains) bad_option("--count", "more than --domains");
    return o;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

bool same(const tetiso::Piece& a, const tetiso::Piece& b) {
    return a.key == b.key && a.flags == b.flags && a.triangles == b.triangles && same_bits(a.x, b.x) &&
           same_bits(a.y, b.y) && same_bits(a.z, b.z) && same_bits(a.error, b.error) &&
           same_bits(a.sample_xyz, b.sample_xyz) && a.sample_triangle == b.sample_triangle && a.sampled == b.sampled &&
           a.domains == b.domains;
}

// The job's domain task (Job::execute): extraction and reduction on the
// Device, then the samples near the interfaces kept on the host.
struct Task {
    const tetiso::LatticePartition* partition;
    tetiso::ReduceOptions reduce;
    float level;
    int sample_rings;
    bool host_batch = false; // on the host: extract each domain, then one reduce_batch

    // The domains' tasks in one call (a batch on a GPU).
    std::vector<tetiso::DomainTaskResult> run(const std::vector<int>& domains, const tetiso::Device& device) const {
        tetiso::DomainTaskOptions options;
        options.level = level;
        options.device = device;
        options.reduce = reduce;
        if (host_batch && !device.is_gpu()) options.reduce.reset();
        std::vector<tetiso::DomainTaskResult> done = tetiso::run_domain_tasks(*partition, domains, options);
        if (host_batch && !device.is_gpu()) {
            std::vector<tetiso::Piece> pieces;
            for (tetiso::DomainTaskResult& d : done) pieces.push_back(std::move(d.piece));
            std::vector<tetiso::Piece> reduced = tetiso::reduce_batch(pieces, reduce);
            for (std::size_t i = 0; i < done.size(); ++i) done[i].piece = std::move(reduced[i]);
        }
        for (tetiso::DomainTaskResult& d : done) tetiso::keep_samples_near_locked(d.piece, sample_rings);
        return done;
    }
};

struct Outcome {
    std::vector<tetiso::Piece> pieces; // by position in the domain list
    std::vector<std::size_t> triangles_in;
    double seconds = 0;
};

// The domains on one Device per thread, each thread taking the next `batch`
// domains of a shared counter. An exception in a thread ends the program.
Outcome run_threads(const Task& task, const std::vector<int>& domains, const std::vector<tetiso::Device>& devices,
                    int batch = 1) {
    Outcome out;
    out.pieces.resize(domains.size());
    out.triangles_in.resize(domains.size());
    std::atomic<std::size_t> next{0};
    std::atomic<bool> failed{false};
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> threads;
    for (const tetiso::Device& device : devices)
        threads.emplace_back([&, device] {
            try {
                const auto step = static_cast<std::size_t>(batch);
                for (std::size_t i; (i = next.fetch_add(step)) < domains.size() && !failed;) {
                    const std::size_t n = std::min(step, domains.size() - i);
                    std::vector<tetiso::DomainTaskResult> done =
                        task.run({domains.begin() + static_cast<std::ptrdiff_t>(i),
                                  domains.begin() + static_cast<std::ptrdiff_t>(i + n)},
                                 device);
                    for (std::size_t j = 0; j < n; ++j) {
                        out.triangles_in[i + j] = done[j].triangles_extracted;
                        out.pieces[i + j] = std::move(done[j].piece);
                    }
                }
            } catch (const std::exception& e) {
                std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
                failed = true;
            }
        });
    for (std::thread& t : threads) t.join();
    out.seconds = seconds_since(start);
    if (failed) std::exit(1);
    return out;
}

// Names every domain whose piece is not the reference's; false if any.
bool check(const char* what, const Outcome& got, const Outcome& reference, const std::vector<int>& domains) {
    bool all = true;
    for (std::size_t i = 0; i < domains.size(); ++i)
        if (!same(got.pieces[i], reference.pieces[i])) {
            std::fprintf(stderr, "%s: %s: domain %d's piece DIFFERS from the first run\n", kProgram, what,
                         domains[i]);
            all = false;
        }
    return all;
}

std::size_t device_memory_used(int gpu) {
    std::size_t free = 0, total = 0;
    if (cudaSetDevice(gpu) != cudaSuccess || cudaMemGetInfo(&free, &total) != cudaSuccess) return 0;
    return total - free;
}

struct Row {
    std::string name;
    int streams = 0; // 0: the CPU
    int batch = 1;
    double cold_s = 0, warm_s = 0;
    std::size_t buffer_bytes = 0, device_used_bytes = 0;
};

std::string json_row(const Row& r, std::size_t domains, std::size_t triangles_in, std::size_t triangles_out) {
    std::ostringstream s;
    s.precision(6);
    const double n = static_cast<double>(domains);
    const double tin = static_cast<double>(triangles_in);
    s << "{\"name\":\"" << r.name << "\",\"streams\":" << r.streams << ",\"batch\":" << r.batch
      << ",\"cold_s\":" << r.cold_s
      << ",\"warm_s\":" << r.warm_s << ",\"domains_per_s\":" << n / r.warm_s
      << ",\"raw_triangles_per_s\":" << tin / r.warm_s << ",\"cold_raw_triangles_per_s\":" << tin / r.cold_s
      << ",\"buffer_bytes\":" << r.buffer_bytes << ",\"device_used_bytes\":" << r.device_used_bytes
      << ",\"triangles_in\":" << triangles_in << ",\"triangles_out\":" << triangles_out << "}";
    return s.str();
}

} // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    const tetiso::GpuInfo info = tetiso::gpu_info();
    if (!info.available) {
        std::fprintf(stderr, "%s: %s\n", kProgram, info.description.c_str());
        return 3;
    }
    const tetiso::LatticePartition partition(o.lattice, o.domains, tetiso::make_field(kField));
    const tetiso::JobConfig job;
    Task task{&partition, {}, static_cast<float>(partition.field().default_level()), job.sample_rings};
    task.reduce.max_error = job.max_error_spacings * partition.spacing();
    task.reduce.keep_samples = true;
    std::vector<int> domains;
    for (int i = 0; i < o.count; ++i)
        domains.push_back(o.spread ? static_cast<int>(static_cast<std::int64_t>(i) * o.domains / o.count) : i);
    std::fprintf(stderr, "%s: %s; N = %lld, %d domains, %zu of them (%s)\n", kProgram, info.description.c_str(),
                 static_cast<long long>(o.lattice), o.domains, domains.size(), o.spread ? "spread" : "first");

    // Every kernel loaded before any timing (a kernel's first launch may
    // wait for the whole device), on a small domain the surface crosses, as
    // Job::prepare_gpu does.
    {
        const tetiso::LatticePartition small(24, 1, tetiso::make_field(kField));
        Task warm_up = task;
        warm_up.partition = &small;
        warm_up.reduce.max_error = job.max_error_spacings * small.spacing();
        const std::vector<tetiso::Device> one{tetiso::Device::cuda(0)};
        run_threads(warm_up, {0}, one);
    }

    std::vector<Row> rows;
    Outcome reference;
    std::size_t triangles_in = 0, triangles_out = 0;
    bool all_same = true;
    for (const int k : o.streams)
        for (const int b : o.batches) {
            std::vector<tetiso::Device> devices;
            for (int d = 0; d < k; ++d) devices.push_back(tetiso::Device::cuda(0));
            Row row{"gpu/streams:" + std::to_string(k) + "/batch:" + std::to_string(b), k, b};
            const Outcome cold = run_threads(task, domains, devices, b);
            const Outcome warm = run_threads(task, domains, devices, b);
            row.cold_s = cold.seconds;
            row.warm_s = warm.seconds;
            row.buffer_bytes = tetiso::Device::gpu_bytes_held();
            row.device_used_bytes = device_memory_used(0);
            if (reference.pieces.empty()) {
                reference = cold;
                for (std::size_t i = 0; i < domains.size(); ++i) {
                    triangles_in += reference.triangles_in[i];
                    triangles_out += reference.pieces[i].triangle_count();
                }
            }
            const std::string name = row.name;
            all_same &= check((name + " cold").c_str(), cold, reference, domains);
            all_same &= check((name + " warm").c_str(), warm, reference, domains);
            rows.push_back(row);
            std::fprintf(stderr, "%s: %-24s cold %7.3f s  warm %7.3f s  %6.1f domains/s  %6.2f M raw triangles/s  "
                                 "buffers %6.0f MiB  device %6.0f MiB\n",
                         kProgram, name.c_str(), row.cold_s, row.warm_s, static_cast<double>(domains.size()) / row.warm_s,
                         static_cast<double>(triangles_in) / row.warm_s / 1e6,
                         static_cast<double>(row.buffer_bytes) / (1 << 20),
                         static_cast<double>(row.device_used_bytes) / (1 << 20));
        }

    if (o.cpu) {
        // One thread per core, each a host Device doing one domain at a time
        // with one thread, as the job's CPU workers do.
        const std::vector<tetiso::Device> hosts(static_cast<std::size_t>(o.cpu_threads));
        for (const int b : o.cpu_batches) {
            Row row{"cpu/threads:" + std::to_string(o.cpu_threads) + (b > 1 ? "/batch:" + std::to_string(b) : ""), 0, b};
            Task on_host = task;
            on_host.host_batch = b > 1;
            const Outcome cpu = run_threads(on_host, domains, hosts, b);
            row.cold_s = row.warm_s = cpu.seconds;
            all_same &= check(row.name.c_str(), cpu, reference, domains);
            rows.push_back(row);
            std::fprintf(stderr, "%s: %-24s         %7.3f s  %6.1f domains/s  %6.2f M raw triangles/s\n", kProgram,
                         row.name.c_str(), row.warm_s, static_cast<double>(domains.size()) / row.warm_s,
                         static_cast<double>(triangles_in) / row.warm_s / 1e6);
        }
    }

    std::ostringstream json;
    json << "{\"program\":\"" << kProgram << "\",\"gpu\":\"" << info.description << "\",\"field\":\"" << kField
         << "\",\"lattice\":" << o.lattice << ",\"domains\":" << o.domains << ",\"count\":" << domains.size()
         << ",\"pick\":\"" << (o.spread ? "spread" : "first") << "\",\"max_error_spacings\":" << job.max_error_spacings
         << ",\"sample_rings\":" << job.sample_rings << ",\"all_pieces_identical\":" << (all_same ? "true" : "false")
         << ",\"rows\":[";
    for (std::size_t i = 0; i < rows.size(); ++i)
        json << (i ? "," : "") << json_row(rows[i], domains.size(), triangles_in, triangles_out);
    json << "]}\n";
    if (o.json.empty()) {
        std::cout << json.str();
    } else {
        std::ofstream file(o.json);
        file << json.str();
        if (!file) {
            std::fprintf(stderr, "%s: %s: cannot write\n", kProgram, o.json.c_str());
            return 2;
        }
    }
    if (!all_same) {
        std::fprintf(stderr, "%s: a piece differed from the first run: these figures are void\n", kProgram);
        return 1;
    }
    std::fprintf(stderr, "%s: every piece, from every stream count, batch and the CPU, is the first run's, byte for byte\n",
                 kProgram);
    return 0;
}
