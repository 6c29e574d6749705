// The job's largest seams alone, over and over: what rank 0 runs by itself
// after the last domain (the root's chain, ARCHITECTURE.md "Seaming and the
// job"). Building their input pieces costs the whole job, so it is done once
// and the pieces are kept in files; timing then loads them and runs the
// seams as Job::execute does, stage by stage (SeamReport::Seconds).
//
// Usage:
//   bench_seam save DIR --lattice=N --domains=D [--field=paper] [--max-error=0.25]
//       [--threads=T] [--keep=K]
//     runs the lattice job's tasks in this process and writes the two input
//     pieces of the K seams nearest the root along its chain to DIR.
//   bench_seam time DIR [--threads=T] [--repeat=R] [--out=ODIR]
//     seams each saved pair R times with T threads, prints each stage's
//     median seconds per seam, and with --out writes each result's piece
//     bytes to ODIR/task<T>.piece, for cmp across builds and thread counts.
// Exits 2 on a bad option or file.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "byte_buffer.hpp"
#include "piece_bytes.hpp"
#include "tetiso/error.hpp"
#include "tetiso/schedule.hpp"

namespace {

using namespace tetiso;

[[noreturn]] void fail(const std::string& what) {
    std::fprintf(stderr, "bench_seam: %s\n", what.c_str());
    std::exit(2);
}

struct Options {
    std::string mode, dir, field = "paper", out;
    std::int64_t lattice = 0;
    double max_error = JobConfig{}.max_error_spacings;
    int domains = 0, threads = 1, keep = 3, repeat = 5;
};

Options parse(int argc, char** argv) {
    Options o;
    if (argc < 3) fail("usage: bench_seam save|time DIR [--option=value ...]");
    o.mode = argv[1];
    o.dir = argv[2];
    for (int i = 3; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto eq = arg.find('=');
        if (arg.rfind("--", 0) != 0 || eq == std::string::npos) fail("bad option " + arg);
        const std::string name = arg.substr(2, eq - 2), value = arg.substr(eq + 1);
        if (name == "lattice") o.lattice = std::stoll(value);
        else if (name == "domains") o.domains = std::stoi(value);
        else if (name == "field") o.field = value;
        else if (name == "max-error") o.max_error = std::stod(value);
        else if (name == "threads") o.threads = std::stoi(value);
        else if (name == "keep") o.keep = std::stoi(value);
        else if (name == "repeat") o.repeat = std::stoi(value);
        else if (name == "out") o.out = value;
        else fail("unknown option " + arg);
    }
    return o;
}

JobConfig config_of(const Options& o) {
    JobConfig config;
    config.lattice = o.lattice;
    config.domains = o.domains;
    config.field = o.field;
    config.threads = o.threads;
    config.max_error_spacings = o.max_error;
    return config;
}

std::string read_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail("cannot read " + path.string());
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) fail("cannot write " + path.string());
}

// The task's piece, its children's first (the tree lists children after
// their parent); the inputs of the seams in `saved` are written to `dir`.
Piece run_task(const Job& job, int task, const std::vector<int>& saved, const std::filesystem::path& dir) {
    const TaskNode& n = job.node(task);
    TaskRecord record;
    const TaskThreads threads{job.config().threads, {}, {}};
    if (n.count == 1) return job.execute(task, nullptr, nullptr, record, threads);
    const Piece left = run_task(job, n.left, saved, dir);
    const Piece right = run_task(job, n.right, saved, dir);
    if (std::find(saved.begin(), saved.end(), task) != saved.end()) {
        detail::ByteWriter<std::string> bytes;
        detail::put_piece(bytes, left);
        detail::put_piece(bytes, right);
        write_file(dir / ("task" + std::to_string(task) + ".pieces"), bytes.bytes);
        std::fprintf(stderr, "task %d: %zu + %zu triangles saved\n", task, left.triangle_count(),
                     right.triangle_count());
    }
    return job.execute(task, &left, &right, record, threads);
}

int save(const Options& o) {
    const Job job(config_of(o));
    std::filesystem::create_directories(o.dir);
    std::vector<int> saved;
    for (int task = 0; task >= 0 && job.node(task).count > 1 && static_cast<int>(saved.size()) < o.keep;
         task = job.node(task).left)
        saved.push_back(task);
    std::ostringstream manifest;
    manifest << o.lattice << ' ' << o.domains << ' ' << o.field << ' ' << o.max_error << '\n';
    for (const int task : saved) manifest << task << '\n';
    write_file(std::filesystem::path(o.dir) / "manifest", manifest.str());
    run_task(job, 0, saved, o.dir);
    return 0;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

int time(Options o) {
    std::istringstream manifest(read_file(std::filesystem::path(o.dir) / "manifest"));
    manifest >> o.lattice >> o.domains >> o.field >> o.max_error;
    const Job job(config_of(o));
    if (!o.out.empty()) std::filesystem::create_directories(o.out);
    std::printf("%6s %9s %9s %8s %8s %8s %8s %8s\n", "task", "tri_in", "tri_out", "merge", "region", "reduce",
                "splice", "total");
    for (int task; manifest >> task;) {
        const std::string bytes = read_file(std::filesystem::path(o.dir) / ("task" + std::to_string(task) + ".pieces"));
        detail::ByteReader in(bytes, [](const char* what) -> void { fail(std::string("truncated at ") + what); });
        const Piece left = detail::get_piece(in), right = detail::get_piece(in);
        std::vector<double> merge, region, reduce, splice, total;
        Piece out;
        for (int r = 0; r < o.repeat; ++r) {
            TaskRecord record;
            const auto start = std::chrono::steady_clock::now();
            out = job.execute(task, &left, &right, record, TaskThreads{o.threads, {}, {}});
            total.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            merge.push_back(record.stages.merge);
            region.push_back(record.stages.region);
            reduce.push_back(record.stages.reduce);
            splice.push_back(record.stages.splice);
        }
        std::printf("%6d %9zu %9zu %8.4f %8.4f %8.4f %8.4f %8.4f\n", task,
                    left.triangle_count() + right.triangle_count(), out.triangle_count(), median(merge),
                    median(region), median(reduce), median(splice), median(total));
        if (!o.out.empty()) {
            detail::ByteWriter<std::string> result;
            detail::put_piece(result, out);
            write_file(std::filesystem::path(o.out) / ("task" + std::to_string(task) + ".piece"), result.bytes);
        }
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse(argc, argv);
        if (o.mode == "save") return save(o);
        if (o.mode == "time") return time(o);
        fail("mode must be save or time, not " + o.mode);
    } catch (const std::exception& e) {
        fail(e.what());
    }
}
