// The in-situ call on every rank of an MPI job (validation/mpi/test_insitu.sh
// drives it): each rank hands over its piece in memory, in a layout of its
// own (float or double coordinates, 32- or 64-bit ids, nodes in a shuffled
// order, some tetrahedra in the other orientation, another rank's cells as
// ghosts), and writes the same piece as a .vtu of a .pvtu, so that the
// script can hold the in-situ surface to `tetiso run --mesh` on that file.
//
// Usage: test_insitu MODE DIR
//   same     write the pieces and the .pvtu, call twice (DIR/insitu.ply,
//            DIR/insitu2.ply), the root being the last rank; DIR/level.txt
//   bad      the last rank's piece has a corner out of range
//   overlap  the ghost cells are not marked (two ranks hold them)
//   twice    the last rank's piece lists its tetrahedron 0 again, at its
//            end; the pieces and the .pvtu are written as in `same`, so
//            that the script can hold the message to the file route's
//   options  the last rank asks for another level
//   flat     the last rank's tetrahedron 0 has zero volume in its domain
//            task, after the collectives of the call's start, not in the
//            scan (which refuses a flat tetrahedron): one of its corners is
//            a node other pieces hold, given by this piece a hair off the
//            plane, which its domain takes from them, in it. With one rank
//            no node is shared, and the scan refuses it.
// In the error modes every rank writes the message it caught to
// DIR/error-R.txt; the exit status is 0 when the call threw on this rank.
#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tetiso/error.hpp"
#include "tetiso/insitu.hpp"
#include "tetiso/lattice.hpp"

namespace {

// A rank's piece in the arrays a solver would have.
struct SolverPiece {
    std::vector<double> xyz64;
    std::vector<float> xyz32, f32;
    std::vector<double> f64;
    std::vector<std::int64_t> ids64;
    std::vector<std::int32_t> ids32;
    std::vector<std::int32_t> tets;
    std::vector<std::uint8_t> ghost;
    bool wide = false; // double coordinates and values, 64-bit ids

    std::size_t nodes() const { return wide ? ids64.size() : ids32.size(); }
    double x(std::size_t i, int axis) const { return wide ? xyz64[3 * i + static_cast<std::size_t>(axis)] : xyz32[3 * i + static_cast<std::size_t>(axis)]; }
    double f(std::size_t i) const { return wide ? f64[i] : f32[i]; }
    std::int64_t id(std::size_t i) const { return wide ? ids64[i] : ids32[i]; }

    tetiso::InSituPiece view(bool mark_ghosts) const {
        tetiso::InSituPiece p;
        if (wide) {
            p.coordinates = {xyz64.data(), xyz64.size()};
            p.field = {f64.data(), f64.size()};
            p.global_ids = {ids64.data(), ids64.size()};
        } else {
            p.coordinates = {xyz32.data(), xyz32.size()};
            p.field = {f32.data(), f32.size()};
            p.global_ids = {ids32.data(), ids32.size()};
        }
        p.tetrahedra = {tets.data(), tets.size()};
        if (mark_ghosts) p.ghost_cells = {ghost.data(), ghost.size()};
        return p;
    }
};

// Domain `own` of the lattice, its nodes shuffled and every third
// tetrahedron turned over, then domain `ghost`'s cells as ghosts, their
// nodes added where the piece lacks them (a node is in a solver's piece once).
SolverPiece make_piece(const tetiso::LatticePartition& lattice, int own, int ghost, bool wide, unsigned seed) {
    SolverPiece piece;
    piece.wide = wide;
    std::map<std::int64_t, std::int32_t> index_of_id;
    for (int pass = 0; pass < 2; ++pass) {
        const tetiso::Domain domain = lattice.make_domain(pass == 0 ? own : ghost);
        std::vector<std::size_t> order(domain.node_count());
        std::iota(order.begin(), order.end(), std::size_t{0});
        std::shuffle(order.begin(), order.end(), std::mt19937(seed + static_cast<unsigned>(pass)));
        std::vector<std::int32_t> where(order.size());
        for (const std::size_t i : order) {
            const auto [at, added] = index_of_id.emplace(domain.gid[i], static_cast<std::int32_t>(piece.nodes()));
            where[i] = at->second;
            if (!added) continue;
            const float p[3] = {domain.x[i], domain.y[i], domain.z[i]};
            for (const float c : p) wide ? piece.xyz64.push_back(c) : piece.xyz32.push_back(c);
            wide ? piece.f64.push_back(domain.f[i]) : piece.f32.push_back(domain.f[i]);
            wide ? piece.ids64.push_back(domain.gid[i]) : piece.ids32.push_back(static_cast<std::int32_t>(domain.gid[i]));
        }
        for (std::size_t t = 0; t < domain.tet_count(); ++t) {
            std::int32_t v[4];
            for (int k = 0; k < 4; ++k) v[k] = where[static_cast<std::size_t>(domain.tets[4 * t + static_cast<std::size_t>(k)])];
            if (t % 3 == 0) std::swap(v[0], v[1]);
            piece.tets.insert(piece.tets.end(), v, v + 4);
            piece.ghost.push_back(static_cast<std::uint8_t>(pass));
        }
    }
    return piece;
}

void write_vtu(const SolverPiece& piece, const std::string& path) {
    std::ostringstream out;
    const char* real = piece.wide ? "Float64" : "Float32";
    const int digits = piece.wide ? 17 : 9; // enough to read back the same bits
    out.precision(digits);
    const std::size_t n = piece.nodes(), cells = piece.tets.size() / 4;
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
        << "<UnstructuredGrid><Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << cells << "\">\n"
        << "<PointData GlobalIds=\"GlobalNodeIds\"><DataArray type=\"" << real << "\" Name=\"f\" format=\"ascii\">";
    for (std::size_t i = 0; i < n; ++i) out << piece.f(i) << ' ';
    out << "</DataArray>\n<DataArray type=\"" << (piece.wide ? "Int64" : "Int32") << "\" Name=\"GlobalNodeIds\" format=\"ascii\">";
    for (std::size_t i = 0; i < n; ++i) out << piece.id(i) << ' ';
    out << "</DataArray></PointData>\n<CellData><DataArray type=\"UInt8\" Name=\"vtkGhostType\" format=\"ascii\">";
    for (const std::uint8_t g : piece.ghost) out << int(g) << ' ';
    out << "</DataArray></CellData>\n<Points><DataArray type=\"" << real << "\" NumberOfComponents=\"3\" format=\"ascii\">";
    for (std::size_t i = 0; i < n; ++i) out << piece.x(i, 0) << ' ' << piece.x(i, 1) << ' ' << piece.x(i, 2) << ' ';
    out << "</DataArray></Points>\n<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">";
    for (const std::int32_t v : piece.tets) out << v << ' ';
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">";
    for (std::size_t c = 0; c < cells; ++c) out << 4 * (c + 1) << ' ';
    out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">";
    for (std::size_t c = 0; c < cells; ++c) out << "10 ";
    out << "</DataArray></Cells>\n</Piece></UnstructuredGrid></VTKFile>\n";
    std::ofstream(path) << out.str();
}

void write_pvtu(int pieces, const std::string& path) {
    std::ofstream out(path);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
        << "<PUnstructuredGrid GhostLevel=\"1\">\n<PPointData GlobalIds=\"GlobalNodeIds\">"
        << "<PDataArray type=\"Float64\" Name=\"f\"/><PDataArray type=\"Int64\" Name=\"GlobalNodeIds\"/></PPointData>\n"
        << "<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n";
    for (int p = 0; p < pieces; ++p) out << "<Piece Source=\"piece_" << p << ".vtu\"/>\n";
    out << "</PUnstructuredGrid>\n</VTKFile>\n";
}

} // namespace

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    const std::string mode = argc > 1 ? argv[1] : "", dir = argc > 2 ? argv[2] : ".";
    int status = 1;
    {
        const tetiso::LatticePartition lattice(18, size, tetiso::make_field("torus"));
        const double level = lattice.field().default_level();
        SolverPiece piece = make_piece(lattice, rank, (rank + 1) % size, rank % 2 == 1, 7u + static_cast<unsigned>(rank));
        tetiso::InSituSessionOptions session_options;
        session_options.root = size - 1;
        // The same checks with each rank's task on a GPU (run where one is).
        if (const char* device = std::getenv("TETISO_TEST_INSITU_DEVICE"))
            session_options.device = std::string(device) == "gpu"    ? tetiso::InSituDevice::gpu
                                     : std::string(device) == "auto" ? tetiso::InSituDevice::automatic
                                                                     : tetiso::InSituDevice::cpu;
        tetiso::InSituSession session(MPI_COMM_WORLD, session_options);
        tetiso::InSituOptions options;
        options.level = level;
        if (mode == "same") {
            write_vtu(piece, dir + "/piece_" + std::to_string(rank) + ".vtu");
            if (rank == 0) {
                write_pvtu(size, dir + "/pieces.pvtu");
                std::ofstream(dir + "/level.txt") << std::to_string(level) << '\n';
                // The level as the command line will read it back.
                options.level = std::stod(std::to_string(level));
            }
            MPI_Bcast(&options.level, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            options.output = dir + "/insitu.ply";
            const tetiso::InSituResult first = session.isosurface(piece.view(true), options);
            options.output = dir + "/insitu2.ply";
            const tetiso::InSituResult second = session.isosurface(piece.view(true), options);
            // The surface comes back on the root only.
            status = (rank == size - 1) == first.surface.has_value() && second.surface.has_value() == first.surface.has_value() &&
                             first.cost.tetrahedra > 0 && first.mesh_tetrahedra == lattice.tet_count()
                         ? 0
                         : 1;
        } else {
            if (mode == "bad" && rank == size - 1) piece.tets[5] = static_cast<std::int32_t>(piece.nodes());
            if (mode == "options" && rank == size - 1) options.level = level + 0.25;
            if (mode == "twice") {
                if (rank == size - 1) {
                    piece.tets.insert(piece.tets.end(), piece.tets.begin(), piece.tets.begin() + 4);
                    piece.ghost.push_back(0);
                }
                write_vtu(piece, dir + "/piece_" + std::to_string(rank) + ".vtu");
                if (rank == 0) write_pvtu(size, dir + "/pieces.pvtu");
            }
            if (mode == "flat" && rank == size - 1) {
                std::set<std::int64_t> own, elsewhere;
                for (int d = 0; d < size; ++d)
                    for (const std::int64_t id : lattice.make_domain(d).gid) (d == rank ? own : elsewhere).insert(id);
                std::size_t shared = 0;
                if (size > 1)
                    while (!(own.count(piece.id(shared)) && elsewhere.count(piece.id(shared)))) ++shared;
                // Three nodes of this piece alone in the shared node's plane,
                // far apart, so that no face of the new tetrahedron is a face of
                // the mesh (which would be three tetrahedra on one face).
                const auto distance2 = [&](std::size_t i, std::size_t j) {
                    double sum = 0;
                    for (int axis = 0; axis < 2; ++axis) sum += (piece.x(i, axis) - piece.x(j, axis)) * (piece.x(i, axis) - piece.x(j, axis));
                    return sum;
                };
                const auto area2 = [&](std::size_t i, std::size_t j, std::size_t k) {
                    const double cross = (piece.x(j, 0) - piece.x(i, 0)) * (piece.x(k, 1) - piece.x(i, 1)) -
                                         (piece.x(j, 1) - piece.x(i, 1)) * (piece.x(k, 0) - piece.x(i, 0));
                    return cross * cross;
                };
                std::vector<std::size_t> plane;
                for (std::size_t i = 0; i < piece.nodes(); ++i)
                    if (i != shared && piece.x(i, 2) == piece.x(shared, 2) && own.count(piece.id(i)) && !elsewhere.count(piece.id(i)))
                        plane.push_back(i);
                const auto best = [&](auto score) { return *std::max_element(plane.begin(), plane.end(), [&](std::size_t i, std::size_t j) { return score(i) < score(j); }); };
                const std::size_t a = best([&](std::size_t i) { return distance2(i, shared); });
                const std::size_t b = best([&](std::size_t i) { return distance2(i, a); });
                const std::size_t c = best([&](std::size_t i) { return area2(a, b, i); });
                const std::int32_t corners[4] = {static_cast<std::int32_t>(shared), static_cast<std::int32_t>(a),
                                                 static_cast<std::int32_t>(b), static_cast<std::int32_t>(c)};
                std::copy(corners, corners + 4, piece.tets.begin());
                if (size > 1) { // above the other pieces' copy, so theirs is taken
                    if (piece.wide) piece.xyz64[3 * shared + 2] += 1e-6;
                    else piece.xyz32[3 * shared + 2] += 1e-6f;
                }
            }
            try {
                session.isosurface(piece.view(mode != "overlap"), options);
            } catch (const tetiso::Error& e) {
                std::ofstream(dir + "/error-" + std::to_string(rank) + ".txt") << e.what() << '\n';
                status = 0;
            }
        }
    }
    MPI_Finalize();
    return status;
}
