// Partition files (one domain id per tetrahedron, mpmetis's format), read for
// a lattice cube of 48 tetrahedra and, where they read, turned into the
// partition a job would run: shared edges, merge tree, domains.
#include "fuzz_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_partition.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const tetiso::Domain cube = [] {
        const tetiso::Lattice lattice(3); // Decomposition keeps a reference to it
        const tetiso::Decomposition one(lattice, 1);
        return one.make_domain(0, *tetiso::make_field("sphere"));
    }();
    const auto path = tetiso::fuzz::write_file("input.part", tetiso::fuzz::bytes_of(data, size));
    try {
        const std::vector<std::int32_t> part = tetiso::read_partition(path, cube.tet_count());
        const tetiso::MeshPartition partition(cube, part, path.string());
        for (int d = 0; d < partition.domain_count(); ++d) partition.make_domain(d);
    } catch (const tetiso::Error&) {
    }
    return 0;
}
