// Peak memory of extracting one lattice domain, in a fresh process: the
// resident-set high-water mark (VmHWM) after the domain is generated and after
// it is extracted. Google Benchmark cannot measure this, since its process
// holds every problem it has built; one run of this program is one data point.
//
// Usage: bench_extract_memory [--n=100] [--threads=1] [--method=tetiso|vtk]
// Prints one JSON object on stdout. --method=vtk measures the VTK baseline
// instead (domain, its vtkUnstructuredGrid copy, and the filter), for context.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"

#ifdef TETISO_HAVE_VTK
#include "tetiso/reference.hpp"
#endif

namespace {

// Resident-set high-water mark in bytes, as the kernel tracks it. Unlike
// getrusage's ru_maxrss it is per process image and can be read at any point.
long long vm_hwm_bytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024; // reported in kB
    return -1;
}

const char* option(int argc, char** argv, const char* name, const char* fallback) {
    const std::size_t length = std::strlen(name);
    for (int i = 1; i < argc; ++i)
        if (std::strncmp(argv[i], name, length) == 0 && argv[i][length] == '=') return argv[i] + length + 1;
    return fallback;
}

} // namespace

int main(int argc, char** argv) {
    try {
        for (int i = 1; i < argc; ++i)
            if (std::strncmp(argv[i], "--n=", 4) != 0 && std::strncmp(argv[i], "--threads=", 10) != 0 &&
                std::strncmp(argv[i], "--method=", 9) != 0)
                throw tetiso::Error(std::string("unknown argument ") + argv[i]);
        const std::int64_t n = std::stoll(option(argc, argv, "--n", "100"));
        const int threads = std::stoi(option(argc, argv, "--threads", "1"));
        const std::string method = option(argc, argv, "--method", "tetiso");
        constexpr float level = 0.5f;

        const tetiso::Lattice lattice(n);
        const tetiso::Decomposition decomposition(lattice, 1);
        const tetiso::Domain domain = decomposition.make_domain(0, *tetiso::make_field("paper"));
        const long long after_domain = vm_hwm_bytes();

        long long vertices = 0, triangles = 0;
        if (method == "tetiso") {
            const tetiso::Piece piece = tetiso::extract(domain, level, tetiso::ExtractOptions{threads});
            vertices = static_cast<long long>(piece.vertex_count());
            triangles = static_cast<long long>(piece.triangle_count());
        } else if (method == "vtk") {
#ifdef TETISO_HAVE_VTK
            tetiso::reference::vtk_set_threads(threads);
            tetiso::reference::VtkContour vtk(domain);
            const tetiso::reference::ContourCounts counts = vtk.contour(level, threads == 1);
            vertices = counts.points;
            triangles = counts.triangles;
#else
            throw tetiso::Error("built without VTK");
#endif
        } else {
            throw tetiso::Error("unknown method " + method + " (tetiso or vtk)");
        }
        const long long peak = vm_hwm_bytes();

        std::printf("{\"method\": \"%s\", \"n\": %lld, \"threads\": %d, \"nodes\": %zu, \"tets\": %zu, "
                    "\"vertices\": %lld, \"triangles\": %lld, \"vm_hwm_after_domain_bytes\": %lld, "
                    "\"vm_hwm_bytes\": %lld}\n",
                    method.c_str(), static_cast<long long>(n), threads, domain.node_count(), domain.tet_count(),
                    vertices, triangles, after_domain, peak);
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench_extract_memory: %s\n", error.what());
        return 2;
    }
}
