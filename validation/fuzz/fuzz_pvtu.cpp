// libFuzzer target: any bytes as a .pvtu index (core/src/pvtu.cpp), whose
// piece list is then followed: the directory around it holds the three
// pieces of meshes/solver/pieces.pvtu (pieces_0.vtu .. pieces_2.vtu), and
// what a piece list must never read: a link to /dev/zero (zero.vtu), a pipe
// (fifo.vtu) and a directory (dir.vtu). The partition scan and the joined
// mesh are both built from what reads. Seeds: validation/fuzz/corpus/pvtu/.
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/pvtu.hpp"

namespace {

const std::filesystem::path& pieces_directory() {
    static const std::filesystem::path directory = [] {
        const std::filesystem::path dir = tetiso::fuzz::scratch() / "pvtu";
        std::filesystem::create_directories(dir / "dir.vtu");
        for (const char* name : {"pieces_0.vtu", "pieces_1.vtu", "pieces_2.vtu"})
            std::filesystem::copy_file(std::filesystem::path(TETISO_MESHES_DIR) / "solver" / name, dir / name);
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
