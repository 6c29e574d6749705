// libFuzzer target: any bytes as a .pvtu index (core/src/pvtu.cpp), whose
// piece list is then followed: the directory around it holds the three
// pieces of meshes/solver/pieces.pvtu (pieces_0.vtu .. pieces_2.vtu), what a
// piece list must never read: a link to /dev/zero (zero.vtu), a pipe
// (fifo.vtu) and a directory (dir.vtu), and small pieces that reach the
// overlap checks: two tetrahedra over one face (pair.vtu), one more above
// it (above.vtu: inside pair.vtu by that face), one listed twice
// (twice.vtu), one of ids no other piece has (apart.vtu, the note). The
// partition scan and the joined mesh are both built from what reads.
// Seeds: validation/fuzz/corpus/pvtu/.
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/pvtu.hpp"

namespace {

// An ascii piece over six points (ids from `first_id`): a triangle in
// z = 0, a point above it, one below and one higher.
std::string small_piece(const std::vector<int>& tets, int first_id) {
    std::string ids, connectivity, offsets, types;
    for (int i = 0; i < 6; ++i) ids += std::to_string(first_id + i) + " ";
    for (const int v : tets) connectivity += std::to_string(v) + " ";
    for (std::size_t t = 1; t <= tets.size() / 4; ++t) offsets += std::to_string(4 * t) + " ", types += "10 ";
    return "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"6\" NumberOfCells=\"" +
           std::to_string(tets.size() / 4) + "\"><PointData GlobalIds=\"GlobalNodeIds\"><DataArray type=\"Float64\" "
           "Name=\"distance\" format=\"ascii\">0 1 2 3 4 5</DataArray><DataArray type=\"Int64\" Name=\"GlobalNodeIds\" "
           "format=\"ascii\">" + ids + "</DataArray></PointData><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" "
           "format=\"ascii\">0 0 0 1 0 0 0 1 0 0.2 0.2 1 0.2 0.2 -1 0.2 0.2 2</DataArray></Points><Cells><DataArray "
           "type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" + connectivity + "</DataArray><DataArray type=\"Int32\" "
           "Name=\"offsets\" format=\"ascii\">" + offsets + "</DataArray><DataArray type=\"UInt8\" Name=\"types\" "
           "format=\"ascii\">" + types + "</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>";
}

const std::filesystem::path& pieces_directory() {
    static const std::filesystem::path directory = [] {
        const std::filesystem::path dir = tetiso::fuzz::scratch() / "pvtu";
        std::filesystem::create_directories(dir / "dir.vtu");
        for (const char* name : {"pieces_0.vtu", "pieces_1.vtu", "pieces_2.vtu"})
            std::filesystem::copy_file(std::filesystem::path(TETISO_MESHES_DIR) / "solver" / name, dir / name);
        const std::pair<const char*, std::string> small[] = {
            {"pair.vtu", small_piece({0, 1, 2, 3, 0, 1, 2, 4}, 0)}, {"above.vtu", small_piece({0, 1, 2, 5}, 0)},
            {"twice.vtu", small_piece({0, 1, 2, 3, 3, 2, 1, 0}, 0)}, {"apart.vtu", small_piece({0, 1, 2, 3}, 100)}};
        for (const auto& [name, bytes] : small) std::ofstream(dir / name, std::ios::binary) << bytes;
        std::filesystem::create_symlink("/dev/zero", dir / "zero.vtu");
        if (::mkfifo((dir / "fifo.vtu").c_str(), 0600) != 0) std::abort();
        return dir;
    }();
    return directory;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::filesystem::path path = pieces_directory() / "index.pvtu";
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    tetiso::MeshSource source;
    source.path = path;
    source.array = "distance";
    try {
        const tetiso::PvtuPartition partition(source);
        for (int d = 0; d < partition.domain_count(); ++d) (void)partition.make_domain(d);
        (void)tetiso::read_mesh(source);
    } catch (const tetiso::Error&) {
    }
    return 0;
}
