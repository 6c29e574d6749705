// Pieces made domains seamed by global node ids (piece_tables.hpp): the
// scan of a piece's boundary, the tables built from every piece's scan, and
// a piece's domain, for .pvtu pieces and in-situ pieces alike.
#include "piece_tables.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>

#include "byte_buffer.hpp"
#include "merge_tree.hpp"
#include "tet_faces.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {

PieceNodes nodes_of(const MeshArrays& a) {
    PieceNodes nodes;
    nodes.count = a.x.size();
    nodes.coordinate[0] = a.x.data(), nodes.coordinate[1] = a.y.data(), nodes.coordinate[2] = a.z.data();
    nodes.ids = a.ids.data();
    nodes.values = a.f.empty() ? nullptr : a.f.data();
    return nodes;
}

PieceMesh piece_mesh(const PieceNodes& nodes, const std::int32_t* tets, std::size_t tet_count, const std::string& name) {
    PieceMesh piece{nodes, tets, tet_count, {}};
    if (tet_count == 0) throw Error(name + ": the piece has no tetrahedra (besides ghost cells)");
    std::vector<char> is_used(nodes.count, 0);
    for (std::size_t i = 0; i < 4 * tet_count; ++i) is_used[static_cast<std::size_t>(tets[i])] = 1;
    for (std::size_t v = 0; v < is_used.size(); ++v)
        if (is_used[v]) piece.used.push_back(static_cast<std::int32_t>(v));
    std::sort(piece.used.begin(), piece.used.end(), [&nodes](std::int32_t p, std::int32_t q) {
        return std::make_pair(nodes.id(static_cast<std::size_t>(p)), p) < std::make_pair(nodes.id(static_cast<std::size_t>(q)), q);
    });
    for (std::size_t i = 1; i < piece.used.size(); ++i) {
        const auto p = static_cast<std::size_t>(piece.used[i - 1]), q = static_cast<std::size_t>(piece.used[i]);
        if (nodes.id(p) == nodes.id(q))
            throw Error(name + ": node id " + std::to_string(nodes.id(p)) + " is given to points " + std::to_string(p) +
                        " and " + std::to_string(q) + " of one piece");
    }
    return piece;
}

bool BoundaryNode::operator<(const BoundaryNode& o) const { return std::tie(id, piece) < std::tie(o.id, o.piece); }

namespace {

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

// Pieces that share no node id with the rest are legal (a mesh of several
// bodies) but more often pieces numbered apart by mistake, whose surfaces
// would meet open where they touch: said in a note, not refused.
template <class Root>
std::string unjoined_pieces(const std::vector<std::string>& names, const std::string& whole, Root root) {
    std::vector<std::vector<int>> groups(names.size());
    for (int p = 0; p < static_cast<int>(names.size()); ++p) groups[static_cast<std::size_t>(root(p))].push_back(p);
    groups.erase(std::remove_if(groups.begin(), groups.end(), [](const std::vector<int>& g) { return g.empty(); }), groups.end());
    if (groups.size() < 2) return {};
    std::string list;
    for (std::size_t g = 0; g < groups.size() && g < 4; ++g) {
        const std::vector<int>& members = groups[g];
        list += g == 0 ? "" : "; ";
        if (members.size() == 1) {
            list += "piece " + std::to_string(members[0]) + " (" + names[static_cast<std::size_t>(members[0])] + ")";
        } else {
            list += "pieces " + std::to_string(members[0]);
            for (std::size_t m = 1; m < members.size() && m < 4; ++m) list += ", " + std::to_string(members[m]);
            list += members.size() > 4 ? " and " + std::to_string(members.size() - 4) + " more" : "";
        }
    }
    if (groups.size() > 4) list += "; and " + std::to_string(groups.size() - 4) + " more groups";
    return whole + ": the pieces fall into " + std::to_string(groups.size()) + " groups that share no node id (" + list +
           "): their surfaces are not joined; if the groups touch, the node ids are not global";
}

ByteReader unpacker(std::string_view bytes) {
    return ByteReader(bytes, [](const char*) { throw Error("a piece scan's message from another rank is truncated"); });
}

} // namespace

PieceScan scan_piece(const PieceMesh& piece, int p, const std::string& name, bool several) {
    PieceScan scan;
    const PieceNodes& a = piece.nodes;
    scan.tets = static_cast<std::int64_t>(piece.tet_count);
    scan.used = static_cast<std::int64_t>(piece.used.size());
    // The spacing as mean_edge_length computes it, over float positions.
    for (std::size_t t = 0; t < piece.tet_count; ++t)
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                const auto u = static_cast<std::size_t>(piece.tets[4 * t + static_cast<std::size_t>(i)]);
                const auto v = static_cast<std::size_t>(piece.tets[4 * t + static_cast<std::size_t>(j)]);
                const double dx = a.x(u) - static_cast<double>(a.x(v));
                const double dy = a.y(u) - static_cast<double>(a.y(v));
                const double dz = a.z(u) - static_cast<double>(a.z(v));
                scan.edge_sum += std::sqrt(dx * dx + dy * dy + dz * dz);
            }
    // Oriented as a task orients them (over float positions), in a copy: the
    // piece's arrays may be a solver's, which are only read.
    std::vector<std::int32_t> tets(piece.tets, piece.tets + 4 * piece.tet_count);
    const TetNames names{piece.numbers, piece.numbers ? piece.tet_count : 0, "cell"};
    const std::vector<std::uint8_t> listed_negative = orient_each(
        tets,
        [&a](std::int32_t c0, std::int32_t c1, std::int32_t c2, std::int32_t c3) {
            const auto position = [&a](std::int32_t v, int axis) {
                return static_cast<double>(a.coordinate_at(axis, static_cast<std::size_t>(v)));
            };
            return volume6(position, c0, c1, c2, c3);
        },
        name, names);
    std::vector<GlobalId> ids(a.count);
    for (std::size_t i = 0; i < a.count; ++i) ids[i] = a.id(i);
    std::vector<std::int32_t> on_boundary;
    std::vector<std::array<std::int32_t, 3>> boundary_faces;
    const FaceClash clash = face_pass(tets, a.count, [&](std::int32_t u, std::int32_t v, std::int32_t w, std::size_t t) {
        BoundaryTet tet{{}, piece.numbers ? piece.numbers[t] : t};
        for (int k = 0; k < 4; ++k) tet.ids[static_cast<std::size_t>(k)] = ids[static_cast<std::size_t>(tets[4 * t + static_cast<std::size_t>(k)])];
        std::sort(tet.ids.begin(), tet.ids.end());
        scan.boundary_tets.push_back(tet);
        boundary_faces.push_back({u, v, w});
        scan.faces.push_back(boundary_face(tets.data() + 4 * t, {u, v, w}, ids, tet.cell));
        const std::int32_t f[3] = {u, v, w};
        for (int e = 0; e < 3; ++e) {
            const GlobalId g = ids[static_cast<std::size_t>(f[e])];
            const GlobalId h = ids[static_cast<std::size_t>(f[(e + 1) % 3])];
            scan.edges.push_back({edge_key(g, h), p});
            on_boundary.push_back(f[e]);
        }
    });
    refuse_clash(clash, listed_negative, name, names);
    if (several) scan.inside = piece_inside(tets, ids, piece.used, boundary_faces);
    std::sort(scan.edges.begin(), scan.edges.end());
    scan.edges.erase(std::unique(scan.edges.begin(), scan.edges.end()), scan.edges.end());
    std::sort(scan.boundary_tets.begin(), scan.boundary_tets.end());
    scan.boundary_tets.erase(std::unique(scan.boundary_tets.begin(), scan.boundary_tets.end()), scan.boundary_tets.end());
    std::sort(on_boundary.begin(), on_boundary.end());
    on_boundary.erase(std::unique(on_boundary.begin(), on_boundary.end()), on_boundary.end());
    for (const std::int32_t v : on_boundary) {
        const auto i = static_cast<std::size_t>(v);
        scan.nodes.push_back({a.id(i), p, a.x(i), a.y(i), a.z(i), a.f(i)});
    }
    return scan;
}

std::string pack_scans(const std::string& error, const std::vector<std::pair<int, PieceScan>>& scans) {
    ByteWriter<std::string> out;
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

void unpack_scans(const std::vector<std::string>& shares, std::vector<PieceScan>& scans) {
    std::string first_error;
    for (const std::string& share : shares) {
        ByteReader in = unpacker(share);
        const auto error = in.get_array<char>();
        if (!error.empty() && first_error.empty()) first_error.assign(error.begin(), error.end());
        const auto count = in.get<std::uint64_t>();
        for (std::uint64_t k = 0; k < count; ++k) {
            const auto p = in.get<std::int64_t>();
            if (p < 0 || static_cast<std::size_t>(p) >= scans.size()) throw Error("a piece scan's message names piece " + std::to_string(p));
            PieceScan& scan = scans[static_cast<std::size_t>(p)];
            scan.tets = in.get<std::int64_t>();
            scan.used = in.get<std::int64_t>();
            scan.edge_sum = in.get<double>();
            scan.digest = in.get<std::uint64_t>();
            const auto piece_error = in.get_array<char>();
            scan.error.assign(piece_error.begin(), piece_error.end());
            scan.nodes = in.get_array<BoundaryNode>();
            for (const EdgeKey key : in.get_array<EdgeKey>()) scan.edges.push_back({key, static_cast<int>(p)});
            scan.boundary_tets = in.get_array<BoundaryTet>();
            scan.faces = in.get_array<BoundaryFace>();
        }
    }
    if (!first_error.empty()) throw Error(first_error);
    // The first piece, in the file's order, that could not be read.
    for (const PieceScan& scan : scans)
        if (!scan.error.empty()) throw Error(scan.error);
}

PieceTables::PieceTables(std::vector<PieceScan>& scans, const std::vector<std::string>& names, const std::string& whole,
                         const std::string& values, const std::vector<std::pair<int, PieceInside>>& inside,
                         const Gather& gather) {
    const int parts = static_cast<int>(scans.size());

    // Pieces that overlap (one listed twice, under two names, inside another
    // or holding the whole mesh each, as VTK writes an unstreamed grid in
    // several pieces; cells shared but not marked as ghosts), before any
    // task: a tetrahedron on the boundary of both, a fold across the face two
    // pieces share, then one on the boundary of one that reaches inside the
    // other, which each rank looks for in its own pieces; the first in the
    // pieces' order is named, for any number of ranks.
    {
        std::vector<std::vector<BoundaryTet>> boundary(scans.size());
        for (std::size_t p = 0; p < scans.size(); ++p) boundary[p] = std::move(scans[p].boundary_tets);
        refuse_shared_boundary_tets(boundary, names);
        {
            std::vector<std::vector<BoundaryFace>> faces(scans.size());
            for (std::size_t p = 0; p < scans.size(); ++p) faces[p] = std::move(scans[p].faces);
            refuse_folds_between(faces, names);
        }
        if (parts > 1) {
            const InsideOverlap mine = find_inside_overlap(inside, boundary, names);
            ByteWriter<std::string> out;
            out.put(mine.piece), out.put(mine.tet), out.put(mine.other);
            out.put_array(std::vector<char>(mine.message.begin(), mine.message.end()));
            InsideOverlap first;
            for (const std::string& share : gather(out.bytes)) {
                ByteReader in = unpacker(share);
                InsideOverlap found;
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

    std::vector<std::int64_t> part_tets(static_cast<std::size_t>(parts));
    std::vector<std::pair<EdgeKey, int>> boundary_edges;
    std::vector<BoundaryNode> boundary_nodes;
    double edge_sum = 0; // piece by piece in the file's order, for any number of ranks
    std::int64_t used_nodes = 0;
    for (int p = 0; p < parts; ++p) {
        PieceScan& scan = scans[static_cast<std::size_t>(p)];
        part_tets[static_cast<std::size_t>(p)] = scan.tets;
        tet_count += scan.tets;
        used_nodes += scan.used;
        edge_sum += scan.edge_sum;
        digests.push_back(scan.digest);
        boundary_edges.insert(boundary_edges.end(), scan.edges.begin(), scan.edges.end());
        boundary_nodes.insert(boundary_nodes.end(), scan.nodes.begin(), scan.nodes.end());
        scan = PieceScan();
    }
    std::sort(boundary_edges.begin(), boundary_edges.end());
    spacing = edge_sum / static_cast<double>(6 * tet_count);

    // Shared nodes: each takes the smallest of the positions and values its
    // pieces give (the pieces' order does not matter), and every other must
    // lie within the tolerance of it: a position within kPositionTolerance
    // of the mean edge length, a value within kValueUlps of float rounding
    // of the larger magnitude (the same rule for both, at least a few ulps
    // of float, which solvers' ranks may disagree by).
    std::sort(boundary_nodes.begin(), boundary_nodes.end());
    node_count = used_nodes;
    const auto describe = [&](const BoundaryNode& n) {
        return "(" + full_precision(n.x) + ", " + full_precision(n.y) + ", " + full_precision(n.z) + ")";
    };
    std::vector<int> group_of(static_cast<std::size_t>(parts)); // pieces joined by shared nodes (union-find)
    std::iota(group_of.begin(), group_of.end(), 0);
    const auto root = [&group_of](int p) {
        while (group_of[static_cast<std::size_t>(p)] != p)
            p = group_of[static_cast<std::size_t>(p)] = group_of[static_cast<std::size_t>(group_of[static_cast<std::size_t>(p)])];
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
            const std::string& chosen_piece = names[static_cast<std::size_t>(chosen.piece)];
            node_count -= static_cast<std::int64_t>(j - i - 1);
            for (std::size_t k = i; k < j; ++k) {
                const BoundaryNode& other = boundary_nodes[k];
                const std::string& other_piece = names[static_cast<std::size_t>(other.piece)];
                if (!within(other.x, chosen.x, kPositionTolerance * spacing) ||
                    !within(other.y, chosen.y, kPositionTolerance * spacing) ||
                    !within(other.z, chosen.z, kPositionTolerance * spacing))
                    throw Error(other_piece + ": node id " + std::to_string(chosen.id) + " is at " + describe(other) +
                                ", where " + chosen_piece + " puts it at " + describe(chosen) +
                                ": farther apart than " + full_precision(kPositionTolerance) +
                                " of the mean edge length " + full_precision(spacing));
                if (!values.empty() && !within(other.f, chosen.f, 0))
                    throw Error(other_piece + ": node id " + std::to_string(chosen.id) + " has value " +
                                full_precision(other.f) + " of " + values + ", where " + chosen_piece + " gives it " +
                                full_precision(chosen.f) + ": more than float rounding apart");
            }
            shared_nodes.push_back(chosen.id);
            shared_xyz.insert(shared_xyz.end(), {chosen.x, chosen.y, chosen.z});
            shared_f.push_back(chosen.f);
        }
        i = j;
    }
    std::vector<BoundaryNode>().swap(boundary_nodes);
    if (std::string note = unjoined_pieces(names, whole, root); !note.empty()) notes.push_back(std::move(note));

    // Shared edges, the pieces' adjacency and the tree.
    PairWeights weights;
    std::vector<int> shared_source;
    group_shared_edges(boundary_edges, shared_keys, shared_first, shared_source, weights);
    std::vector<std::pair<EdgeKey, int>>().swap(boundary_edges);
    build_merge_tree(part_tets, weights, tree, source_id);
    std::vector<int> domain_of_source(static_cast<std::size_t>(parts));
    for (int d = 0; d < parts; ++d) domain_of_source[static_cast<std::size_t>(source_id[static_cast<std::size_t>(d)])] = d;
    neighbours = neighbour_lists(weights, domain_of_source);
    shared_domains.resize(shared_source.size());
    for (std::size_t e = 0; e + 1 < shared_first.size(); ++e) {
        const auto first = shared_domains.begin() + shared_first[e], last = shared_domains.begin() + shared_first[e + 1];
        std::transform(shared_source.begin() + shared_first[e], shared_source.begin() + shared_first[e + 1], first,
                       [&](int p) { return domain_of_source[static_cast<std::size_t>(p)]; });
        std::sort(first, last);
    }
}

std::vector<int> PieceTables::domains_of_edge(GlobalId a, GlobalId b) const {
    if (a < 0 || b < 0 || a > kMaxGlobalId || b > kMaxGlobalId) return {};
    const EdgeKey key = edge_key(a, b);
    const auto found = std::lower_bound(shared_keys.begin(), shared_keys.end(), key);
    if (found == shared_keys.end() || *found != key) return {};
    const auto e = static_cast<std::size_t>(found - shared_keys.begin());
    return {shared_domains.begin() + shared_first[e], shared_domains.begin() + shared_first[e + 1]};
}

Domain PieceTables::make_domain(const PieceMesh& piece, int domain, const Field* field, const std::string& name) const {
    const PieceNodes& a = piece.nodes;
    Domain out;
    out.id = domain;
    const std::size_t n = piece.used.size();
    std::vector<std::int32_t> local(a.count, -1);
    std::vector<double> px(n), py(n), pz(n);
    out.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<std::size_t>(piece.used[i]);
        local[v] = static_cast<std::int32_t>(i);
        const GlobalId id = a.id(v);
        out.gid[i] = id;
        float x = a.x(v), y = a.y(v), z = a.z(v);
        const auto shared = std::lower_bound(shared_nodes.begin(), shared_nodes.end(), id);
        if (shared != shared_nodes.end() && *shared == id) {
            const auto s = 3 * static_cast<std::size_t>(shared - shared_nodes.begin());
            x = shared_xyz[s], y = shared_xyz[s + 1], z = shared_xyz[s + 2];
        }
        px[i] = x, py[i] = y, pz[i] = z;
    }
    out.x.assign(px.begin(), px.end());
    out.y.assign(py.begin(), py.end());
    out.z.assign(pz.begin(), pz.end());
    out.f.resize(n);
    if (a.values) {
        for (std::size_t i = 0; i < n; ++i) {
            out.f[i] = a.f(static_cast<std::size_t>(piece.used[i]));
            // A shared node's value as every piece takes it (see the scan).
            const auto shared = std::lower_bound(shared_nodes.begin(), shared_nodes.end(), out.gid[i]);
            if (shared != shared_nodes.end() && *shared == out.gid[i])
                out.f[i] = shared_f[static_cast<std::size_t>(shared - shared_nodes.begin())];
        }
    } else {
        if (!field) throw Error(name + ": neither a field nor values were given");
        // At the positions every piece agrees on, so shared nodes get one value.
        field->evaluate(px.data(), py.data(), pz.data(), n, out.f.data());
    }
    out.tets.resize(4 * piece.tet_count);
    for (std::size_t i = 0; i < out.tets.size(); ++i) out.tets[i] = local[static_cast<std::size_t>(piece.tets[i])];
    orient_tetrahedra(out, name);
    out.interface.assign(n, 0);
    for (std::size_t e = 0; e < shared_keys.size(); ++e) {
        const auto first = shared_domains.begin() + shared_first[e], last = shared_domains.begin() + shared_first[e + 1];
        if (!std::binary_search(first, last, domain)) continue;
        out.shared_edges.push_back(shared_keys[e]);
        for (const GlobalId g : {edge_key_low(shared_keys[e]), edge_key_high(shared_keys[e])}) {
            const auto at = std::lower_bound(out.gid.begin(), out.gid.end(), g);
            out.interface[static_cast<std::size_t>(at - out.gid.begin())] = 1;
        }
    }
    return out;
}

} // namespace tetiso::detail
