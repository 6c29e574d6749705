// The in-situ call against the file route on the same pieces
// (tools/bench_insitu.sh drives it, results/insitu/ holds what it measured).
// Each rank's piece is domain `rank` of the N^3 lattice, in a solver's
// layout: interleaved double coordinates, 64-bit ids, double values, int32
// tetrahedra.
//
//   bench_insitu run N DIR REPEATS   the call REPEATS times on one session
//                                    (DIR/insitu.json, DIR/insitu.ply), then
//                                    the pieces written as DIR/pieces.pvtu
//                                    (DIR/write.json): the file route's first step
//   bench_insitu read FILE REPEATS   a surface read back, as the solver
//                                    would read the file route's result
#include <mpi.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "tetiso/insitu.hpp"
#include "tetiso/io.hpp"
#include "tetiso/lattice.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// This process's CPU seconds so far (user and system): on a shared machine
// the wall clock says more about the others' load than about the work.
double cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Every rank's CPU seconds since `start` (this rank's), summed on rank 0.
double summed_cpu_since(double start) {
    const double mine = cpu_seconds() - start;
    double sum = 0;
    MPI_Reduce(&mine, &sum, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    return sum;
}

struct SolverPiece {
    std::vector<double> xyz, f;
    std::vector<std::int64_t> ids;
    std::vector<std::int32_t> tets;
};

// VTK's appended raw binary, UInt64 headers: the layout ParaView writes large
// pieces in, and the fastest the reader reads.
std::size_t write_vtu(const SolverPiece& p, const std::string& path) {
    const std::size_t n = p.ids.size(), cells = p.tets.size() / 4;
    std::vector<std::int64_t> offsets(cells);
    std::vector<std::uint8_t> types(cells, 10);
    for (std::size_t c = 0; c < cells; ++c) offsets[c] = static_cast<std::int64_t>(4 * (c + 1));
    struct Block {
        const void* data;
        std::uint64_t bytes;
    };
    const Block blocks[] = {{p.f.data(), n * 8}, {p.ids.data(), n * 8}, {p.xyz.data(), 3 * n * 8},
                            {p.tets.data(), 4 * cells * 4}, {offsets.data(), cells * 8}, {types.data(), cells}};
    std::uint64_t at[6], offset = 0;
    for (int b = 0; b < 6; ++b) at[b] = offset, offset += 8 + blocks[b].bytes;
    std::FILE* out = std::fopen(path.c_str(), "wb");
    std::fprintf(out,
                 "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt64\">\n<UnstructuredGrid><Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
                 "<PointData GlobalIds=\"GlobalNodeIds\"><DataArray type=\"Float64\" Name=\"f\" format=\"appended\" offset=\"%llu\"/>"
                 "<DataArray type=\"Int64\" Name=\"GlobalNodeIds\" format=\"appended\" offset=\"%llu\"/></PointData>\n"
                 "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"%llu\"/></Points>\n"
                 "<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"%llu\"/>"
                 "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"%llu\"/>"
                 "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"%llu\"/></Cells>\n"
                 "</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_",
                 n, cells, (unsigned long long)at[0], (unsigned long long)at[1], (unsigned long long)at[2],
                 (unsigned long long)at[3], (unsigned long long)at[4], (unsigned long long)at[5]);
    for (const Block& b : blocks) {
        std::fwrite(&b.bytes, 8, 1, out);
        std::fwrite(b.data, 1, b.bytes, out);
    }
    std::fprintf(out, "\n</AppendedData>\n</VTKFile>\n");
    const long size = std::ftell(out);
    std::fclose(out);
    return static_cast<std::size_t>(size);
}

int run(int n, const std::string& dir, int repeats) {
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    SolverPiece piece;
    double level = 0;
    {
        const tetiso::LatticePartition lattice(n, size, tetiso::make_field("paper"));
        level = lattice.field().default_level();
        tetiso::Domain d = lattice.make_domain(rank);
        for (std::size_t i = 0; i < d.node_count(); ++i) piece.xyz.insert(piece.xyz.end(), {double(d.x[i]), double(d.y[i]), double(d.z[i])});
        piece.f.assign(d.f.begin(), d.f.end());
        piece.ids = std::move(d.gid);
        piece.tets = std::move(d.tets);
    }
    tetiso::InSituPiece view;
    view.coordinates = {piece.xyz.data(), piece.xyz.size()};
    view.global_ids = {piece.ids.data(), piece.ids.size()};
    view.field = {piece.f.data(), piece.f.size()};
    view.tetrahedra = {piece.tets.data(), piece.tets.size()};

    std::string calls = "[";
    {
        MPI_Barrier(MPI_COMM_WORLD);
        const auto made = Clock::now();
        tetiso::InSituSession session(MPI_COMM_WORLD);
        const double session_seconds = seconds_since(made);
        tetiso::InSituOptions options;
        options.level = level;
        for (int k = 0; k < repeats; ++k) {
            if (k == repeats - 1) options.output = dir + "/insitu.ply";
            MPI_Barrier(MPI_COMM_WORLD);
            const auto start = Clock::now();
            const double cpu_start = cpu_seconds();
            const tetiso::InSituResult r = session.isosurface(view, options);
            MPI_Barrier(MPI_COMM_WORLD);
            const double wall = seconds_since(start);
            const double cpu = summed_cpu_since(cpu_start);
            // Every rank's stages, on the root.
            const tetiso::InSituCost::Seconds& s = r.cost.seconds;
            const double mine[] = {s.check, s.scan, s.pool, s.domain, s.seams, s.write, s.total,
                                   double(r.cost.nodes), double(r.cost.tetrahedra), double(r.cost.triangles_extracted),
                                   double(r.cost.triangles_reduced), double(r.cost.bytes_sent), double(r.cost.seams)};
            constexpr int fields = sizeof mine / sizeof mine[0];
            std::vector<double> all(static_cast<std::size_t>(fields * size));
            MPI_Gather(mine, fields, MPI_DOUBLE, all.data(), fields, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            if (rank == 0) {
                char text[256];
                std::snprintf(text, sizeof text, "%s{\"wall\": %.4f, \"cpu\": %.4f, \"session\": %.4f, \"triangles\": %zu, \"ranks\": [",
                              k ? ", " : "", wall, cpu, k == 0 ? session_seconds : 0.0, r.surface ? r.surface->triangle_count() : 0);
                calls += text;
                for (int q = 0; q < size; ++q) {
                    const double* v = all.data() + fields * q;
                    std::snprintf(text, sizeof text,
                                  "%s{\"check\": %.4f, \"scan\": %.4f, \"pool\": %.4f, \"domain\": %.4f, \"seams\": %.4f, "
                                  "\"write\": %.4f, \"total\": %.4f, ",
                                  q ? ", " : "", v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
                    calls += text;
                    std::snprintf(text, sizeof text,
                                  "\"nodes\": %.0f, \"tetrahedra\": %.0f, \"extracted\": %.0f, \"reduced\": %.0f, "
                                  "\"bytes_sent\": %.0f, \"seams_run\": %.0f}",
                                  v[7], v[8], v[9], v[10], v[11], v[12]);
                    calls += text;
                }
                calls += "]}";
            }
        }
    }
    calls += "]";

    // The file route's first step: the same pieces as a .pvtu.
    MPI_Barrier(MPI_COMM_WORLD);
    const auto start = Clock::now();
    const double cpu_start = cpu_seconds();
    const double bytes = static_cast<double>(write_vtu(piece, dir + "/piece_" + std::to_string(rank) + ".vtu"));
    if (rank == 0) {
        std::ofstream out(dir + "/pieces.pvtu");
        out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
               "header_type=\"UInt64\">\n<PUnstructuredGrid GhostLevel=\"0\">\n<PPointData GlobalIds=\"GlobalNodeIds\">"
               "<PDataArray type=\"Float64\" Name=\"f\"/><PDataArray type=\"Int64\" Name=\"GlobalNodeIds\"/></PPointData>\n"
               "<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n";
        for (int p = 0; p < size; ++p) out << "<Piece Source=\"piece_" << p << ".vtu\"/>\n";
        out << "</PUnstructuredGrid>\n</VTKFile>\n";
    }
    MPI_Barrier(MPI_COMM_WORLD);
    const double write_seconds = seconds_since(start);
    const double write_cpu = summed_cpu_since(cpu_start);
    double total_bytes = 0;
    MPI_Reduce(&bytes, &total_bytes, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank == 0) {
        std::ofstream(dir + "/insitu.json") << "{\"n\": " << n << ", \"ranks\": " << size << ", \"level\": " << level
                                           << ", \"calls\": " << calls << "}\n";
        std::ofstream(dir + "/write.json") << "{\"seconds\": " << write_seconds << ", \"cpu\": " << write_cpu << ", \"bytes\": " << total_bytes << "}\n";
        std::ofstream(dir + "/level.txt") << std::to_string(level) << '\n';
    }
    return 0;
}

int read(const std::string& file, int repeats) {
    std::string wall, cpu;
    for (int k = 0; k < repeats; ++k) {
        const auto start = Clock::now();
        const double cpu_start = cpu_seconds();
        const tetiso::Piece surface = tetiso::read_piece(file);
        char text[64];
        std::snprintf(text, sizeof text, "%s%.4f", k ? ", " : "", seconds_since(start));
        wall += text;
        std::snprintf(text, sizeof text, "%s%.4f", k ? ", " : "", cpu_seconds() - cpu_start);
        cpu += text;
        if (surface.triangle_count() == 0) return 1;
    }
    std::printf("{\"seconds\": [%s], \"cpu\": [%s]}\n", wall.c_str(), cpu.c_str());
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "read" && argc == 4) return read(argv[2], std::stoi(argv[3]));
    if (mode != "run" || argc != 5) {
        std::fprintf(stderr, "usage: bench_insitu run N DIR REPEATS | bench_insitu read FILE REPEATS\n");
        return 2;
    }
    MPI_Init(&argc, &argv);
    const int status = run(std::stoi(argv[2]), argv[3], std::stoi(argv[4]));
    MPI_Finalize();
    return status;
}
