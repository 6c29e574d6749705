// The reader for `--mesh PATH`, chosen by extension (see mesh_file.hpp), and
// the step every reader shares: arrays as read into a Domain.
#include "tetiso/mesh_file.hpp"

#include <algorithm>
#include <cmath>

#include "tetiso/error.hpp"
#include "tetiso/io_msh.hpp"
#include "tetiso/io_vtu.hpp"
#include "tetiso/pvtu.hpp"
#include "tetiso/tetgen.hpp"

namespace tetiso {

MeshFormat mesh_format(const std::filesystem::path& path) {
    const std::string extension = path.extension().string();
    if (extension == ".vtu") return MeshFormat::vtu;
    if (extension == ".pvtu") return MeshFormat::pvtu;
    if (extension == ".msh") return MeshFormat::msh;
    return MeshFormat::tetgen;
}

std::string MeshSource::field_description() const {
    if (attribute) return "attribute " + std::to_string(*attribute);
    if (!array.empty()) return "array " + array;
    return field ? field->description() : std::string();
}

double signed_volume6(const Domain& d, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t e) {
    const auto p = [&](std::int32_t v, int axis) {
        const auto i = static_cast<std::size_t>(v);
        return static_cast<double>(axis == 0 ? d.x[i] : axis == 1 ? d.y[i] : d.z[i]);
    };
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = p(b, k) - p(a, k);
        v[k] = p(c, k) - p(a, k);
        w[k] = p(e, k) - p(a, k);
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

bool negatively_oriented(const Domain& d, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t e) {
    return signed_volume6(d, a, b, c, e) < 0;
}

void orient_tetrahedra(Domain& domain, const std::string& name) {
    for (std::size_t t = 0; t < domain.tet_count(); ++t) {
        std::int32_t* v = domain.tets.data() + 4 * t;
        const double volume = signed_volume6(domain, v[0], v[1], v[2], v[3]);
        if (volume == 0)
            throw Error(name + ": tetrahedron " + std::to_string(t) +
                        " has zero volume (its corners, as stored in float, are coplanar)");
        if (volume < 0) std::swap(v[2], v[3]);
    }
}

Domain domain_from_arrays(MeshArrays arrays, const Field* field, const std::string& name) {
    Domain domain;
    const std::size_t n = arrays.x.size();
    domain.x.assign(arrays.x.begin(), arrays.x.end());
    domain.y.assign(arrays.y.begin(), arrays.y.end());
    domain.z.assign(arrays.z.begin(), arrays.z.end());
    if (!arrays.f.empty()) {
        domain.f.assign(arrays.f.begin(), arrays.f.end());
    } else {
        if (!field) throw Error("domain_from_arrays: neither a field nor an array was given");
        domain.f.resize(n);
        field->evaluate(arrays.x.data(), arrays.y.data(), arrays.z.data(), n, domain.f.data());
    }
    domain.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) domain.gid[i] = static_cast<GlobalId>(i);
    domain.interface.assign(n, 0);
    domain.tets = std::move(arrays.tets);
    // Extraction orients triangles from positively oriented tetrahedra.
    orient_tetrahedra(domain, name);
    return domain;
}

namespace {

// The TetGen base of BASE, BASE.node or BASE.ele.
std::filesystem::path tetgen_base(const std::filesystem::path& path) {
    const std::string extension = path.extension().string();
    if (extension == ".node" || extension == ".ele") return path.parent_path() / path.stem();
    return path;
}

// Every piece's domain joined by global id into one, renumbered densely in
// id order.
Domain join_pieces(const PvtuPartition& partition, std::vector<std::int32_t>* piece_of_tet) {
    std::vector<Domain> domains;
    std::vector<GlobalId> ids;
    for (int d = 0; d < partition.domain_count(); ++d) {
        domains.push_back(partition.make_domain(d));
        ids.insert(ids.end(), domains.back().gid.begin(), domains.back().gid.end());
    }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    Domain mesh;
    const std::size_t n = ids.size();
    mesh.x.resize(n), mesh.y.resize(n), mesh.z.resize(n), mesh.f.resize(n);
    mesh.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) mesh.gid[i] = static_cast<GlobalId>(i);
    mesh.interface.assign(n, 0);
    // In the .pvtu's piece order, as a job's task order does not matter here.
    std::vector<int> by_source(domains.size());
    for (int d = 0; d < partition.domain_count(); ++d) by_source[static_cast<std::size_t>(partition.source_id(d))] = d;
    for (const int d : by_source) {
        const Domain& piece = domains[static_cast<std::size_t>(d)];
        std::vector<std::int32_t> dense(piece.node_count());
        for (std::size_t v = 0; v < piece.node_count(); ++v) {
            const auto i = static_cast<std::size_t>(std::lower_bound(ids.begin(), ids.end(), piece.gid[v]) - ids.begin());
            dense[v] = static_cast<std::int32_t>(i);
            mesh.x[i] = piece.x[v], mesh.y[i] = piece.y[v], mesh.z[i] = piece.z[v], mesh.f[i] = piece.f[v];
        }
        for (const std::int32_t v : piece.tets) mesh.tets.push_back(dense[static_cast<std::size_t>(v)]);
        if (piece_of_tet) piece_of_tet->insert(piece_of_tet->end(), piece.tet_count(), partition.source_id(d));
    }
    return mesh;
}

} // namespace

Domain read_mesh(const MeshSource& source, std::vector<std::int32_t>* piece_of_tet) {
    const MeshFormat format = mesh_format(source.path);
    if (format != MeshFormat::tetgen && source.attribute)
        throw Error(source.path.string() + ": --attribute applies to TetGen meshes; name a point array with --array");
    if (format == MeshFormat::tetgen && !source.array.empty())
        throw Error(source.path.string() + ": a TetGen mesh has no named arrays; give its node attribute with --attribute");
    if (format != MeshFormat::pvtu && !source.node_ids.empty())
        throw Error(source.path.string() + ": --node-ids applies to a .pvtu, whose pieces it matches");
    if (!source.field_from_file() && !source.field)
        throw Error(source.path.string() + ": neither a field nor an array was given");
    switch (format) {
    case MeshFormat::tetgen:
        return read_tetgen(TetgenSource{tetgen_base(source.path), source.attribute, source.field});
    case MeshFormat::vtu: {
        VtuRequest request;
        request.array = source.array;
        MeshArrays arrays = read_vtu(source.path, request);
        // As a .pvtu piece of ghosts alone is refused: a surface would be empty.
        if (arrays.tets.empty() && arrays.ghost_cells > 0)
            throw Error(source.path.string() + ": no tetrahedra besides its " + std::to_string(arrays.ghost_cells) +
                        " ghost cells");
        return domain_from_arrays(std::move(arrays), source.field, source.path.string());
    }
    case MeshFormat::msh:
        return domain_from_arrays(read_msh(source.path, source.array), source.field, source.path.string());
    case MeshFormat::pvtu:
        return join_pieces(PvtuPartition(source), piece_of_tet);
    }
    throw Error(source.path.string() + ": unknown mesh format");
}

} // namespace tetiso
