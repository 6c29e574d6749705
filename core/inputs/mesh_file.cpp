// The reader for `--mesh PATH`, chosen by extension (see mesh_file.hpp), and
// the step every reader shares: arrays as read into a Domain.
#include "tetiso/mesh_file.hpp"

#include <algorithm>
#include <cmath>

#include "tet_faces.hpp"
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
    return detail::volume6(
        [&d](std::int32_t v, int axis) {
            const auto i = static_cast<std::size_t>(v);
            return static_cast<double>(axis == 0 ? d.x[i] : axis == 1 ? d.y[i] : d.z[i]);
        },
        a, b, c, e);
}

bool negatively_oriented(const Domain& d, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t e) {
    return signed_volume6(d, a, b, c, e) < 0;
}

std::string detail::TetNames::operator()(std::size_t t) const {
    std::string text = "tetrahedron " + std::to_string(t);
    if (numbers && t < count) text += std::string(" (") + word + " " + std::to_string(numbers[t]) + ")";
    return text;
}

void detail::refuse_clash(const FaceClash& clash, const std::vector<std::uint8_t>& listed_negative,
                          const std::string& name, const TetNames& names) {
    using Kind = FaceClash::Kind;
    if (clash.kind == Kind::none) return;
    const std::string others =
        clash.faces > 1 ? " (" + std::to_string(clash.faces) + " faces of the mesh clash like this)" : std::string();
    if (clash.kind == Kind::repeated)
        throw Error(name + ": " + names(clash.second) + " repeats " + names(clash.first) +
                    ": the same four corners, so the two overlap" + others);
    if (clash.kind == Kind::crowded)
        throw Error(name + ": " + names(clash.first) + ", " + names(clash.second) + " and " + names(clash.third) +
                    " share one face: at most two tetrahedra can, one on either side, so they overlap" + others);
    // Folded: one of the two is inverted. Where the mesh lists its
    // tetrahedra in one orientation, all but a few (a mesh listed all
    // negatively is a convention, not an error), and exactly one of the two
    // runs against it, that one is named; in a mesh of mixed orders the
    // listing tells nothing, and both are.
    std::size_t negative = 0;
    for (const std::uint8_t n : listed_negative) negative += n;
    const std::size_t count = listed_negative.size();
    const std::size_t against = std::min(negative, count - negative);
    const std::uint8_t convention = negative > count - negative ? 1 : 0;
    const bool has_convention = 10 * against < count;
    const bool first_against = listed_negative[clash.first] != convention;
    const bool second_against = listed_negative[clash.second] != convention;
    const char* side = "on the same side of the face they share, so the two overlap: the mesh is tangled";
    if (has_convention && first_against != second_against) {
        const std::size_t inverted = first_against ? clash.first : clash.second;
        const std::size_t other = first_against ? clash.second : clash.first;
        throw Error(name + ": " + names(inverted) + " is inverted: " + (convention ? "positively" : "negatively") +
                    " oriented where the mesh's tetrahedra are " + (convention ? "negatively" : "positively") +
                    " (all but " + std::to_string(against) + "), it lies with " + names(other) + " " + side + others);
    }
    throw Error(name + ": " + names(clash.first) + " and " + names(clash.second) + " lie " + side + others);
}

void orient_tetrahedra(Domain& domain, const std::string& name) {
    detail::orient_each(
        domain.tets, [&domain](std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) { return signed_volume6(domain, a, b, c, d); },
        name, {});
}

void check_tetrahedra(Domain& domain, const std::string& name, const std::vector<std::uint64_t>& numbers,
                      const char* number_word) {
    const detail::TetNames names{numbers.empty() ? nullptr : numbers.data(), numbers.size(), number_word};
    const std::vector<std::uint8_t> listed_negative = detail::orient_each(
        domain.tets, [&domain](std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) { return signed_volume6(domain, a, b, c, d); },
        name, names);
    const detail::FaceClash clash = detail::face_pass(domain.tets, domain.node_count(), [](std::int32_t, std::int32_t, std::int32_t, std::size_t) {});
    detail::refuse_clash(clash, listed_negative, name, names);
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
    check_tetrahedra(domain, name, arrays.tet_numbers, arrays.number_word);
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
