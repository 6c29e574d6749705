// A .pvtu's pieces as the domains of a job (see pvtu.hpp): one scan of each
// piece's boundary for the tables every rank needs, then each piece read
// again, alone, by the task that extracts it.
#include "tetiso/pvtu.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <numeric>

#include <pugixml.hpp>

#include "io_formats.hpp"
#include "mapped_file.hpp"
#include "piece_tables.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io_vtu.hpp"
#include "tetiso/mesh_split.hpp"

namespace tetiso {

PvtuIndex read_pvtu_index(const std::filesystem::path& path, int depth) {
    const std::string bytes = detail::read_whole_file(path);
    pugi::xml_document document;
    const pugi::xml_parse_result parsed = document.load_buffer(bytes.data(), bytes.size());
    const auto fail = [&path](const std::string& what) { throw Error(path.string() + ": " + what); };
    if (!parsed) fail(std::string("not well-formed XML (") + parsed.description() + ")");
    const pugi::xml_node root = document.child("VTKFile");
    // A time series (DOLFINx names it NAME.pvtu): its last data set.
    if (root && std::string_view(root.attribute("type").as_string()) == "Collection" && depth == 0) {
        pugi::xml_node last;
        for (const pugi::xml_node set : root.child("Collection").children("DataSet")) last = set;
        const std::filesystem::path file(last.attribute("file").as_string());
        if (file.empty()) fail("a collection without data sets");
        return read_pvtu_index(file.is_absolute() ? file : path.parent_path() / file, 1);
    }
    if (!root || std::string_view(root.attribute("type").as_string()) != "PUnstructuredGrid")
        fail("not a VTK PUnstructuredGrid file");
    const pugi::xml_node grid = root.child("PUnstructuredGrid");
    PvtuIndex index;
    index.global_ids = grid.child("PPointData").attribute("GlobalIds").as_string();
    for (const pugi::xml_node piece : grid.children("Piece")) {
        const std::string source = piece.attribute("Source").as_string();
        if (source.empty()) fail("piece " + std::to_string(index.pieces.size()) + " has no Source");
        const std::filesystem::path file(source);
        index.pieces.push_back(file.is_absolute() ? file : path.parent_path() / file);
    }
    if (index.pieces.empty()) fail("lists no pieces");
    return index;
}

namespace {

// A piece as read for a task or the scan: the mesh without ghost cells,
// seen by the functions every piece goes through (piece_tables.hpp).
struct LoadedPiece {
    MeshArrays arrays;
    detail::PieceMesh mesh;
};

LoadedPiece load_piece(std::string_view bytes, const std::filesystem::path& path, const MeshSource& source,
                       const std::string& ids_name, bool several) {
    VtuRequest request;
    request.array = source.array;
    request.node_ids = ids_name;
    request.require_node_ids = several;
    LoadedPiece piece{parse_vtu(bytes, path.string(), request), {}};
    MeshArrays& a = piece.arrays;
    if (a.ids.empty()) { // a single piece without ids: its point numbers
        a.ids.resize(a.x.size());
        std::iota(a.ids.begin(), a.ids.end(), GlobalId{0});
    }
    piece.mesh = detail::piece_mesh(detail::nodes_of(a), a.tets.data(), a.tets.size() / 4, path.string());
    piece.mesh.numbers = a.tet_numbers.empty() ? nullptr : a.tet_numbers.data();
    return piece;
}

detail::PieceScan scan_piece(const std::filesystem::path& path, const MeshSource& source, const std::string& ids_name,
                             bool several, int p) {
    detail::PieceScan scan;
    try {
        const detail::MappedFile file(path);
        const std::string_view bytes = file.bytes();
        const std::uint64_t digest = split_digest(bytes.data(), bytes.size());
        const LoadedPiece piece = load_piece(bytes, path, source, ids_name, several);
        scan = detail::scan_piece(piece.mesh, p, path.string(), several);
        scan.digest = digest;
    } catch (const Error& e) {
        scan.error = e.what();
    }
    return scan;
}

} // namespace

PvtuPartition::PvtuPartition(const MeshSource& source, std::unique_ptr<Field> field, const RankGroup& group)
    : field_(std::move(field)), source_(source) {
    if (field_) source_.field = field_.get();
    if (source.array.empty() && !source_.field) throw Error(source.path.string() + ": neither a field nor an array was given");
    // Every rank takes part in the exchange below whatever goes wrong here,
    // so that a rank that cannot read its pieces never leaves the others
    // waiting: what went wrong travels with its share of the scan.
    std::string index_error;
    std::vector<std::pair<int, detail::PieceScan>> mine;
    try {
        const PvtuIndex index = read_pvtu_index(source.path);
        pieces_ = index.pieces;
        ids_name_ = !source.node_ids.empty() ? source.node_ids : index.global_ids;
        if (pieces_.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 2))
            throw Error(source.path.string() + ": too many pieces");
        const int parts = static_cast<int>(pieces_.size());
        // Each rank scans every size-th piece from its own rank on.
        for (int p = group.rank; p < parts; p += group.size)
            mine.emplace_back(p, scan_piece(pieces_[static_cast<std::size_t>(p)], source_, ids_name_, parts > 1, p));
    } catch (const Error& e) {
        index_error = e.what();
    }
    std::vector<detail::PieceScan> scans(pieces_.size());
    std::vector<std::pair<int, detail::PieceInside>> inside; // of this rank's pieces
    for (auto& [p, scan] : mine) inside.emplace_back(p, std::move(scan.inside));
    const detail::PieceTables::Gather gather = [&group](const std::string& share) {
        return group.all_gather ? group.all_gather(share) : std::vector<std::string>{share};
    };
    {
        const std::string share = detail::pack_scans(index_error, mine);
        std::vector<std::pair<int, detail::PieceScan>>().swap(mine);
        detail::unpack_scans(gather(share), scans);
    }
    std::vector<std::string> names;
    for (const std::filesystem::path& piece : pieces_) names.push_back(piece.string());
    tables_ = std::make_unique<detail::PieceTables>(scans, names, source.path.string(),
                                                    source.array.empty() ? "" : "'" + source.array + "'", inside, gather);
    std::vector<std::pair<int, detail::PieceInside>>().swap(inside);
    for (std::string& note : tables_->notes) {
        note += " (name the right array with --node-ids)";
        if (group.rank == 0) std::fprintf(stderr, "tetiso: note: %s\n", note.c_str());
    }
    const detail::PieceTables& t = *tables_;
    fingerprint_ = Digest()
                       .add(t.node_count)
                       .add(t.tet_count)
                       .add(t.source_id.data(), t.source_id.size())
                       .add(t.shared_keys.data(), t.shared_keys.size())
                       .add(t.digests.data(), t.digests.size())
                       .add(source.field_description())
                       .value();
}

PvtuPartition::~PvtuPartition() = default;

int PvtuPartition::domain_count() const { return tables_->domain_count(); }
const std::vector<int>& PvtuPartition::neighbours(int domain) const {
    return tables_->neighbours.at(static_cast<std::size_t>(domain));
}
const std::vector<DomainTreeNode>& PvtuPartition::tree() const { return tables_->tree; }
double PvtuPartition::spacing() const { return tables_->spacing; }
std::int64_t PvtuPartition::node_count() const { return tables_->node_count; }
std::int64_t PvtuPartition::tet_count() const { return tables_->tet_count; }
const std::vector<std::string>& PvtuPartition::notes() const { return tables_->notes; }
int PvtuPartition::source_id(int domain) const { return tables_->source_id.at(static_cast<std::size_t>(domain)); }

const std::filesystem::path& PvtuPartition::piece_path(int domain) const {
    return pieces_.at(static_cast<std::size_t>(source_id(domain)));
}

std::string PvtuPartition::domain_name(int domain) const {
    return "domain " + std::to_string(domain) + " (piece " + std::to_string(source_id(domain)) + ", " +
           piece_path(domain).string() + ")";
}

std::vector<int> PvtuPartition::domains_of_edge(GlobalId a, GlobalId b) const { return tables_->domains_of_edge(a, b); }

Domain PvtuPartition::make_domain(int domain) const {
    if (domain < 0 || domain >= domain_count())
        throw Error("no domain " + std::to_string(domain) + " in " + source_.path.string() + " of " +
                    std::to_string(domain_count()));
    const int p = source_id(domain);
    const std::filesystem::path& path = pieces_[static_cast<std::size_t>(p)];
    const detail::MappedFile file(path);
    const std::string_view bytes = file.bytes();
    if (split_digest(bytes.data(), bytes.size()) != tables_->digests[static_cast<std::size_t>(p)])
        throw Error(path.string() + ": the piece changed after the job first read it");
    const LoadedPiece piece = load_piece(bytes, path, source_, ids_name_, pieces_.size() > 1);
    return tables_->make_domain(piece.mesh, domain, source_.array.empty() ? source_.field : nullptr, path.string());
}

} // namespace tetiso
