// A .pvtu's pieces as the domains of a job (see pvtu.hpp): one scan of each
// piece's boundary for the tables every rank needs, then each piece read
// again, alone, by the task that extracts it.
#include "tetiso/pvtu.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>

#include <pugixml.hpp>

#include "byte_buffer.hpp"
#include "io_formats.hpp"
#include "mapped_file.hpp"
#include "merge_tree.hpp"
#include "pvtu_overlaps.hpp"
#include "tet_faces.hpp"
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
// its nodes those its tetrahedra use, in id order.
struct LoadedPiece {
    MeshArrays arrays;
    std::vector<std::int32_t> used; // point indices used by tetrahedra, sorted by id
};

LoadedPiece load_piece(std::string_view bytes, const std::filesystem::path& path, const MeshSource& source,
                       const std::string& ids_name, bool several) {
    VtuRequest request;
    request.array = source.array;
    request.node_ids = ids_name;
    request.require_node_ids = several;
    LoadedPiece piece{parse_vtu(bytes, path.string(), request), {}};
    MeshArrays& a = piece.arrays;
    if (a.tets.empty()) throw Error(path.string() + ": the piece has no tetrahedra (besides ghost cells)");
    if (a.ids.empty()) { // a single piece without ids: its point numbers
        a.ids.resize(a.x.size());
        std::iota(a.ids.begin(), a.ids.end(), GlobalId{0});
    }
    std::vector<char> is_used(a.x.size(), 0);
    for (const std::int32_t v : a.tets) is_used[static_cast<std::size_t>(v)] = 1;
    for (std::size_t v = 0; v < is_used.size(); ++v)
        if (is_used[v]) piece.used.push_back(static_cast<std::int32_t>(v));
    std::sort(piece.used.begin(), piece.used.end(), [&a](std::int32_t p, std::int32_t q) {
        return std::make_pair(a.ids[static_cast<std::size_t>(p)], p) < std::make_pair(a.ids[static_cast<std::size_t>(q)], q);
    });
    for (std::size_t i = 1; i < piece.used.size(); ++i) {
        const auto p = static_cast<std::size_t>(piece.used[i - 1]), q = static_cast<std::size_t>(piece.used[i]);
        if (a.ids[p] == a.ids[q])
            throw Error(path.string() + ": node id " + std::to_string(a.ids[p]) + " is given to points " +
                        std::to_string(p) + " and " + std::to_string(q) + " of one piece");
    }
    return piece;
}

// How far the copies of one shared node may lie apart, as a fraction of the
// mesh's mean edge length; and how many units of float rounding (of the
// larger magnitude) any two copies of a coordinate or a value may differ by.
constexpr double kPositionTolerance = 1e-4;
constexpr double kValueUlps = 4;

// Whether a and b agree: within `absolute`, or within kValueUlps of float
// rounding of the larger.
bool within(float a, float b, double absolute) {
    const double difference = std::abs(static_cast<double>(a) - static_cast<double>(b));
    const double scale = std::max(std::abs(static_cast<double>(a)), std::abs(static_cast<double>(b)));
    return difference <= absolute || difference <= kValueUlps * std::numeric_limits<float>::epsilon() * scale;
}

// A float's bits as an integer that sorts as the float does, -0 before +0: a
// total order, so that the smallest copy of a node is one whatever its pieces' order.
std::uint32_t ordered(float value) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return bits & 0x80000000u ? ~bits : bits | 0x80000000u;
}

// Enough digits to tell any two different doubles apart.
std::string full_precision(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", value);
    return text;
}

// A node on a piece's boundary, as the scan records it.
struct BoundaryNode {
    GlobalId id;
    int piece;
    float x, y, z, f;
    bool operator<(const BoundaryNode& o) const { return std::tie(id, piece) < std::tie(o.id, o.piece); }
};

} // namespace

namespace {

// What the scan keeps of one piece: counts, its digest, its share of the
// spacing, and its boundary; or why it could not be read.
struct PieceScan {
    std::int64_t tets = 0, used = 0;
    double edge_sum = 0;
    std::uint64_t digest = 0;
    std::vector<BoundaryNode> nodes;
    std::vector<std::pair<EdgeKey, int>> edges;
    // The tetrahedra with a face on the boundary, each as its sorted node
    // ids: two pieces that hold one tetrahedron overlap (pvtu_overlaps.hpp).
    std::vector<detail::BoundaryTet> boundary_tets;
    // Its boundary faces by node ids, each with the side its tetrahedron
    // lies on: two pieces on one side of a face fold over each other.
    std::vector<detail::BoundaryFace> faces;
    // Kept by the rank that scanned it, not sent: what lies inside the piece.
    detail::PieceInside inside;
    std::string error;
};

PieceScan scan_piece(const std::filesystem::path& path, const MeshSource& source, const std::string& ids_name,
                     bool several, int p) {
    PieceScan scan;
    try {
        const detail::MappedFile file(path);
        const std::string_view bytes = file.bytes();
        scan.digest = split_digest(bytes.data(), bytes.size());
        LoadedPiece piece = load_piece(bytes, path, source, ids_name, several);
        MeshArrays& a = piece.arrays;
        const std::size_t tets = a.tets.size() / 4;
        scan.tets = static_cast<std::int64_t>(tets);
        scan.used = static_cast<std::int64_t>(piece.used.size());
        // The spacing as mean_edge_length computes it, over float positions.
        for (std::size_t t = 0; t < tets; ++t)
            for (int i = 0; i < 4; ++i)
                for (int j = i + 1; j < 4; ++j) {
                    const auto u = static_cast<std::size_t>(a.tets[4 * t + static_cast<std::size_t>(i)]);
                    const auto v = static_cast<std::size_t>(a.tets[4 * t + static_cast<std::size_t>(j)]);
                    const double dx = static_cast<float>(a.x[u]) - static_cast<double>(static_cast<float>(a.x[v]));
                    const double dy = static_cast<float>(a.y[u]) - static_cast<double>(static_cast<float>(a.y[v]));
                    const double dz = static_cast<float>(a.z[u]) - static_cast<double>(static_cast<float>(a.z[v]));
                    scan.edge_sum += std::sqrt(dx * dx + dy * dy + dz * dz);
                }
        // Oriented as a task orients them (over float positions), so that a
        // piece whose tetrahedra overlap is refused here, before any task.
        const detail::TetNames names{&a.tet_numbers, a.number_word};
        const std::vector<std::uint8_t> listed_negative = detail::orient_each(
            a.tets,
            [&a](std::int32_t c0, std::int32_t c1, std::int32_t c2, std::int32_t c3) {
                const auto position = [&a](std::int32_t v, int axis) {
                    const auto i = static_cast<std::size_t>(v);
                    return static_cast<double>(static_cast<float>(axis == 0 ? a.x[i] : axis == 1 ? a.y[i] : a.z[i]));
                };
                return detail::volume6(position, c0, c1, c2, c3);
            },
            path.string(), names);
        std::vector<std::int32_t> on_boundary;
        std::vector<std::array<std::int32_t, 3>> boundary_faces;
        const detail::FaceClash clash =
            detail::face_pass(a.tets, a.x.size(), [&](std::int32_t u, std::int32_t v, std::int32_t w, std::size_t t) {
                detail::BoundaryTet tet{{}, a.tet_numbers.empty() ? t : a.tet_numbers[t]};
                for (int k = 0; k < 4; ++k)
                    tet.ids[static_cast<std::size_t>(k)] = a.ids[static_cast<std::size_t>(a.tets[4 * t + static_cast<std::size_t>(k)])];
                std::sort(tet.ids.begin(), tet.ids.end());
                scan.boundary_tets.push_back(tet);
                boundary_faces.push_back({u, v, w});
                scan.faces.push_back(detail::boundary_face(a.tets.data() + 4 * t, {u, v, w}, a.ids,
                                                           tet.cell));
                const std::int32_t f[3] = {u, v, w};
                for (int e = 0; e < 3; ++e) {
                    const GlobalId g = a.ids[static_cast<std::size_t>(f[e])];
                    const GlobalId h = a.ids[static_cast<std::size_t>(f[(e + 1) % 3])];
                    scan.edges.push_back({edge_key(g, h), p});
                    on_boundary.push_back(f[e]);
                }
            });
        detail::refuse_clash(clash, listed_negative, path.string(), names);
        if (several) scan.inside = detail::piece_inside(a.tets, a.ids, piece.used, boundary_faces);
        std::sort(scan.edges.begin(), scan.edges.end());
        scan.edges.erase(std::unique(scan.edges.begin(), scan.edges.end()), scan.edges.end());
        std::sort(scan.boundary_tets.begin(), scan.boundary_tets.end());
        scan.boundary_tets.erase(std::unique(scan.boundary_tets.begin(), scan.boundary_tets.end()), scan.boundary_tets.end());
        std::sort(on_boundary.begin(), on_boundary.end());
        on_boundary.erase(std::unique(on_boundary.begin(), on_boundary.end()), on_boundary.end());
        for (const std::int32_t v : on_boundary) {
            const auto i = static_cast<std::size_t>(v);
            scan.nodes.push_back({a.ids[i], p, static_cast<float>(a.x[i]), static_cast<float>(a.y[i]),
                                  static_cast<float>(a.z[i]), a.f.empty() ? 0.0f : static_cast<float>(a.f[i])});
        }
    } catch (const Error& e) {
        scan.error = e.what();
    }
    return scan;
}

// Pieces that share no node id with the rest are legal (a mesh of several
// bodies) but more often pieces numbered apart by mistake, whose surfaces
// would meet open where they touch: said in a note, not refused.
template <class Root>
std::string unjoined_pieces(const MeshSource& source, const std::vector<std::filesystem::path>& pieces, Root root) {
    std::vector<std::vector<int>> groups(pieces.size());
    for (int p = 0; p < static_cast<int>(pieces.size()); ++p) groups[static_cast<std::size_t>(root(p))].push_back(p);
    groups.erase(std::remove_if(groups.begin(), groups.end(), [](const std::vector<int>& g) { return g.empty(); }), groups.end());
    if (groups.size() < 2) return {};
    std::string list;
    for (std::size_t g = 0; g < groups.size() && g < 4; ++g) {
        const std::vector<int>& members = groups[g];
        list += g == 0 ? "" : "; ";
        if (members.size() == 1) {
            list += "piece " + std::to_string(members[0]) + " (" + pieces[static_cast<std::size_t>(members[0])].string() + ")";
        } else {
            list += "pieces " + std::to_string(members[0]);
            for (std::size_t m = 1; m < members.size() && m < 4; ++m) list += ", " + std::to_string(members[m]);
            list += members.size() > 4 ? " and " + std::to_string(members.size() - 4) + " more" : "";
        }
    }
    if (groups.size() > 4) list += "; and " + std::to_string(groups.size() - 4) + " more groups";
    return source.path.string() + ": the pieces fall into " + std::to_string(groups.size()) +
           " groups that share no node id (" + list +
           "): their surfaces are not joined; if the groups touch, the node ids are not global "
           "(name the right array with --node-ids)";
}

// A rank's scans as bytes for RankGroup::all_gather, and back.
detail::ByteReader unpacker(std::string_view bytes) {
    return detail::ByteReader(bytes, [](const char*) {
        throw Error("a .pvtu scan's message from another rank is truncated");
    });
}

std::string pack(const std::string& error, const std::vector<std::pair<int, PieceScan>>& scans) {
    detail::ByteWriter<std::string> out;
    out.put_array(std::vector<char>(error.begin(), error.end()));
    out.put(static_cast<std::uint64_t>(scans.size()));
    for (const auto& [p, scan] : scans) {
        out.put(static_cast<std::int64_t>(p));
        out.put(scan.tets);
        out.put(scan.used);
        out.put(scan.edge_sum);
        out.put(scan.digest);
        out.put_array(std::vector<char>(scan.error.begin(), scan.error.end()));
        out.put_array(scan.nodes);
        std::vector<EdgeKey> keys; // the piece of each is p
        for (const auto& edge : scan.edges) keys.push_back(edge.first);
        out.put_array(keys);
        out.put_array(scan.boundary_tets);
        out.put_array(scan.faces);
    }
    return std::move(out.bytes);
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
    std::vector<std::pair<int, PieceScan>> mine;
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
    std::vector<PieceScan> scans(pieces_.size());
    std::vector<std::pair<int, detail::PieceInside>> inside; // of this rank's pieces
    for (auto& [p, scan] : mine) inside.emplace_back(p, std::move(scan.inside));
    const auto gather = [&group](const std::string& share) {
        return group.all_gather ? group.all_gather(share) : std::vector<std::string>{share};
    };
    {
        const std::vector<std::string> shares = gather(pack(index_error, mine));
        std::vector<std::pair<int, PieceScan>>().swap(mine);
        std::string first_error;
        for (const std::string& share : shares) {
            detail::ByteReader in = unpacker(share);
            const auto error = in.get_array<char>();
            if (!error.empty() && first_error.empty()) first_error.assign(error.begin(), error.end());
            const auto count = in.get<std::uint64_t>();
            for (std::uint64_t k = 0; k < count; ++k) {
                const auto p = in.get<std::int64_t>();
                if (p < 0 || static_cast<std::size_t>(p) >= scans.size()) throw Error("a .pvtu scan's message names piece " + std::to_string(p));
                PieceScan& scan = scans[static_cast<std::size_t>(p)];
                scan.tets = in.get<std::int64_t>();
                scan.used = in.get<std::int64_t>();
                scan.edge_sum = in.get<double>();
                scan.digest = in.get<std::uint64_t>();
                const auto piece_error = in.get_array<char>();
                scan.error.assign(piece_error.begin(), piece_error.end());
                scan.nodes = in.get_array<BoundaryNode>();
                for (const EdgeKey key : in.get_array<EdgeKey>()) scan.edges.push_back({key, static_cast<int>(p)});
                scan.boundary_tets = in.get_array<detail::BoundaryTet>();
                scan.faces = in.get_array<detail::BoundaryFace>();
            }
        }
        if (!first_error.empty()) throw Error(first_error);
        // The first piece, in the file's order, that could not be read.
        for (const PieceScan& scan : scans)
            if (!scan.error.empty()) throw Error(scan.error);
    }
    const int parts = static_cast<int>(pieces_.size());

    // Pieces that overlap (one listed twice, under two names, inside another
    // or holding the whole mesh each, as VTK writes an unstreamed grid in
    // several pieces; cells shared but not marked as ghosts), before any
    // task: a tetrahedron on the boundary of both, then one on the boundary
    // of one that reaches inside the other, which each rank looks for in its
    // own pieces; the first in the pieces' order is named, for any number
    // of ranks.
    {
        std::vector<std::vector<detail::BoundaryTet>> boundary(scans.size());
        for (std::size_t p = 0; p < scans.size(); ++p) boundary[p] = std::move(scans[p].boundary_tets);
        detail::refuse_shared_boundary_tets(boundary, pieces_);
        {
            std::vector<std::vector<detail::BoundaryFace>> faces(scans.size());
            for (std::size_t p = 0; p < scans.size(); ++p) faces[p] = std::move(scans[p].faces);
            detail::refuse_folds_between(faces, pieces_);
        }
        if (pieces_.size() > 1) {
            const detail::InsideOverlap mine_found = detail::find_inside_overlap(inside, boundary, pieces_);
            detail::ByteWriter<std::string> out;
            out.put(mine_found.piece), out.put(mine_found.tet), out.put(mine_found.other);
            out.put_array(std::vector<char>(mine_found.message.begin(), mine_found.message.end()));
            detail::InsideOverlap first;
            for (const std::string& share : gather(std::move(out.bytes))) {
                detail::ByteReader in = unpacker(share);
                detail::InsideOverlap found;
                found.piece = in.get<std::int64_t>(), found.tet = in.get<std::uint64_t>(), found.other = in.get<std::int64_t>();
                const auto message = in.get_array<char>();
                found.message.assign(message.begin(), message.end());
                if (!found.message.empty() &&
                    (first.message.empty() || std::tie(found.piece, found.tet, found.other) < std::tie(first.piece, first.tet, first.other)))
                    first = std::move(found);
            }
            if (!first.message.empty()) throw Error(first.message);
        }
    }
    std::vector<std::pair<int, detail::PieceInside>>().swap(inside);

    std::vector<std::int64_t> part_tets(pieces_.size());
    std::vector<std::pair<EdgeKey, int>> boundary_edges;
    std::vector<BoundaryNode> boundary_nodes;
    double edge_sum = 0; // piece by piece in the file's order, for any number of ranks
    std::int64_t used_nodes = 0;
    for (int p = 0; p < parts; ++p) {
        PieceScan& scan = scans[static_cast<std::size_t>(p)];
        part_tets[static_cast<std::size_t>(p)] = scan.tets;
        tet_count_ += scan.tets;
        used_nodes += scan.used;
        edge_sum += scan.edge_sum;
        piece_digests_.push_back(scan.digest);
        boundary_edges.insert(boundary_edges.end(), scan.edges.begin(), scan.edges.end());
        boundary_nodes.insert(boundary_nodes.end(), scan.nodes.begin(), scan.nodes.end());
        scan = PieceScan();
    }
    std::sort(boundary_edges.begin(), boundary_edges.end());
    spacing_ = edge_sum / static_cast<double>(6 * tet_count_);

    // Shared nodes: each takes the smallest of the positions and values its
    // pieces give (the pieces' order does not matter), and every other must
    // lie within the tolerance of it: a position within kPositionTolerance
    // of the mean edge length, a value within kValueUlps of float rounding
    // of the larger magnitude (the same rule for both, at least a few ulps
    // of float, which solvers' ranks may disagree by).
    std::sort(boundary_nodes.begin(), boundary_nodes.end());
    node_count_ = used_nodes;
    const auto describe = [&](const BoundaryNode& n) {
        return "(" + full_precision(n.x) + ", " + full_precision(n.y) + ", " + full_precision(n.z) + ")";
    };
    std::vector<int> group_of(pieces_.size()); // pieces joined by shared nodes (union-find)
    std::iota(group_of.begin(), group_of.end(), 0);
    const auto root = [&group_of](int p) {
        while (group_of[static_cast<std::size_t>(p)] != p) p = group_of[static_cast<std::size_t>(p)] = group_of[static_cast<std::size_t>(group_of[static_cast<std::size_t>(p)])];
        return p;
    };
    for (std::size_t i = 0; i < boundary_nodes.size();) {
        std::size_t j = i + 1;
        while (j < boundary_nodes.size() && boundary_nodes[j].id == boundary_nodes[i].id) ++j;
        for (std::size_t k = i + 1; k < j; ++k) {
            const int a = root(boundary_nodes[i].piece), b = root(boundary_nodes[k].piece);
            group_of[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
        }
        if (j - i > 1) {
            const auto smallest = [](const BoundaryNode& a, const BoundaryNode& b) {
                return std::make_tuple(ordered(a.x), ordered(a.y), ordered(a.z), ordered(a.f)) <
                       std::make_tuple(ordered(b.x), ordered(b.y), ordered(b.z), ordered(b.f));
            };
            const BoundaryNode& chosen = *std::min_element(boundary_nodes.begin() + static_cast<std::ptrdiff_t>(i),
                                                           boundary_nodes.begin() + static_cast<std::ptrdiff_t>(j), smallest);
            const std::string& chosen_piece = pieces_[static_cast<std::size_t>(chosen.piece)].string();
            node_count_ -= static_cast<std::int64_t>(j - i - 1);
            for (std::size_t k = i; k < j; ++k) {
                const BoundaryNode& other = boundary_nodes[k];
                const std::string& other_piece = pieces_[static_cast<std::size_t>(other.piece)].string();
                if (!within(other.x, chosen.x, kPositionTolerance * spacing_) ||
                    !within(other.y, chosen.y, kPositionTolerance * spacing_) ||
                    !within(other.z, chosen.z, kPositionTolerance * spacing_))
                    throw Error(other_piece + ": node id " + std::to_string(chosen.id) + " is at " + describe(other) +
                                ", where " + chosen_piece + " puts it at " + describe(chosen) +
                                ": farther apart than " + full_precision(kPositionTolerance) +
                                " of the mean edge length " + full_precision(spacing_));
                if (!source.array.empty() && !within(other.f, chosen.f, 0))
                    throw Error(other_piece + ": node id " + std::to_string(chosen.id) + " has value " +
                                full_precision(other.f) + " of '" + source.array + "', where " + chosen_piece +
                                " gives it " + full_precision(chosen.f) + ": more than float rounding apart");
            }
            shared_nodes_.push_back(chosen.id);
            shared_xyz_.insert(shared_xyz_.end(), {chosen.x, chosen.y, chosen.z});
            shared_f_.push_back(chosen.f);
        }
        i = j;
    }
    std::vector<BoundaryNode>().swap(boundary_nodes);
    if (std::string note = unjoined_pieces(source, pieces_, [&root](int p) { return root(p); }); !note.empty()) {
        if (group.rank == 0) std::fprintf(stderr, "tetiso: note: %s\n", note.c_str());
        notes_.push_back(std::move(note));
    }

    // Shared edges, the pieces' adjacency and the tree.
    detail::PairWeights weights;
    std::vector<int> shared_source;
    detail::group_shared_edges(boundary_edges, shared_keys_, shared_first_, shared_source, weights);
    std::vector<std::pair<EdgeKey, int>>().swap(boundary_edges);
    detail::build_merge_tree(part_tets, weights, tree_, source_id_);
    std::vector<int> domain_of_source(pieces_.size());
    for (int d = 0; d < parts; ++d) domain_of_source[static_cast<std::size_t>(source_id_[static_cast<std::size_t>(d)])] = d;
    neighbours_ = detail::neighbour_lists(weights, domain_of_source);
    shared_domains_.resize(shared_source.size());
    for (std::size_t e = 0; e + 1 < shared_first_.size(); ++e) {
        const auto first = shared_domains_.begin() + shared_first_[e], last = shared_domains_.begin() + shared_first_[e + 1];
        std::transform(shared_source.begin() + shared_first_[e], shared_source.begin() + shared_first_[e + 1], first,
                       [&](int p) { return domain_of_source[static_cast<std::size_t>(p)]; });
        std::sort(first, last);
    }

    fingerprint_ = Digest()
                       .add(node_count_)
                       .add(tet_count_)
                       .add(source_id_.data(), source_id_.size())
                       .add(shared_keys_.data(), shared_keys_.size())
                       .add(piece_digests_.data(), piece_digests_.size())
                       .add(source.field_description())
                       .value();
}

PvtuPartition::~PvtuPartition() = default;

const std::filesystem::path& PvtuPartition::piece_path(int domain) const {
    return pieces_.at(static_cast<std::size_t>(source_id(domain)));
}

std::string PvtuPartition::domain_name(int domain) const {
    return "domain " + std::to_string(domain) + " (piece " + std::to_string(source_id(domain)) + ", " +
           piece_path(domain).string() + ")";
}

std::vector<int> PvtuPartition::domains_of_edge(GlobalId a, GlobalId b) const {
    if (a < 0 || b < 0 || a > kMaxGlobalId || b > kMaxGlobalId) return {};
    const EdgeKey key = edge_key(a, b);
    const auto found = std::lower_bound(shared_keys_.begin(), shared_keys_.end(), key);
    if (found == shared_keys_.end() || *found != key) return {};
    const auto e = static_cast<std::size_t>(found - shared_keys_.begin());
    return {shared_domains_.begin() + shared_first_[e], shared_domains_.begin() + shared_first_[e + 1]};
}

Domain PvtuPartition::make_domain(int domain) const {
    if (domain < 0 || domain >= domain_count())
        throw Error("no domain " + std::to_string(domain) + " in " + source_.path.string() + " of " +
                    std::to_string(domain_count()));
    const int p = source_id(domain);
    const std::filesystem::path& path = pieces_[static_cast<std::size_t>(p)];
    const detail::MappedFile file(path);
    const std::string_view bytes = file.bytes();
    if (split_digest(bytes.data(), bytes.size()) != piece_digests_[static_cast<std::size_t>(p)])
        throw Error(path.string() + ": the piece changed after the job first read it");
    const LoadedPiece piece = load_piece(bytes, path, source_, ids_name_, pieces_.size() > 1);
    const MeshArrays& a = piece.arrays;

    Domain out;
    out.id = domain;
    const std::size_t n = piece.used.size();
    std::vector<std::int32_t> local(a.x.size(), -1);
    std::vector<double> px(n), py(n), pz(n);
    out.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<std::size_t>(piece.used[i]);
        local[v] = static_cast<std::int32_t>(i);
        const GlobalId id = a.ids[v];
        out.gid[i] = id;
        float x = static_cast<float>(a.x[v]), y = static_cast<float>(a.y[v]), z = static_cast<float>(a.z[v]);
        const auto shared = std::lower_bound(shared_nodes_.begin(), shared_nodes_.end(), id);
        if (shared != shared_nodes_.end() && *shared == id) {
            const auto s = 3 * static_cast<std::size_t>(shared - shared_nodes_.begin());
            x = shared_xyz_[s], y = shared_xyz_[s + 1], z = shared_xyz_[s + 2];
        }
        px[i] = x, py[i] = y, pz[i] = z;
    }
    out.x.assign(px.begin(), px.end());
    out.y.assign(py.begin(), py.end());
    out.z.assign(pz.begin(), pz.end());
    out.f.resize(n);
    if (!source_.array.empty()) {
        for (std::size_t i = 0; i < n; ++i) {
            out.f[i] = static_cast<float>(a.f[static_cast<std::size_t>(piece.used[i])]);
            // A shared node's value as every piece takes it (see the scan).
            const auto shared = std::lower_bound(shared_nodes_.begin(), shared_nodes_.end(), out.gid[i]);
            if (shared != shared_nodes_.end() && *shared == out.gid[i])
                out.f[i] = shared_f_[static_cast<std::size_t>(shared - shared_nodes_.begin())];
        }
    } else {
        // At the positions every piece agrees on, so shared nodes get one value.
        source_.field->evaluate(px.data(), py.data(), pz.data(), n, out.f.data());
    }
    out.tets.resize(a.tets.size());
    for (std::size_t i = 0; i < a.tets.size(); ++i) out.tets[i] = local[static_cast<std::size_t>(a.tets[i])];
    orient_tetrahedra(out, path.string());
    out.interface.assign(n, 0);
    for (std::size_t e = 0; e < shared_keys_.size(); ++e) {
        const auto first = shared_domains_.begin() + shared_first_[e], last = shared_domains_.begin() + shared_first_[e + 1];
        if (!std::binary_search(first, last, domain)) continue;
        out.shared_edges.push_back(shared_keys_[e]);
        for (const GlobalId g : {edge_key_low(shared_keys_[e]), edge_key_high(shared_keys_[e])}) {
            const auto at = std::lower_bound(out.gid.begin(), out.gid.end(), g);
            out.interface[static_cast<std::size_t>(at - out.gid.begin())] = 1;
        }
    }
    return out;
}

} // namespace tetiso
