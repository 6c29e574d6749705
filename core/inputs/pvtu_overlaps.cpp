// Pieces that overlap (see pvtu_overlaps.hpp).
#include "pvtu_overlaps.hpp"

#include <algorithm>
#include <functional>
#include <tuple>
#include <utility>

#include "tetiso/error.hpp"

namespace tetiso::detail {
namespace {

std::string node_list(const std::array<GlobalId, 4>& ids) {
    return std::to_string(ids[0]) + ", " + std::to_string(ids[1]) + ", " + std::to_string(ids[2]) + ", " +
           std::to_string(ids[3]);
}

constexpr const char* kGhostHint = ": pieces overlap (a cell two pieces hold must be a ghost, vtkGhostType, in all but one)";

// Every piece's items, each with its piece's index, ordered by node ids and
// then piece, so that items sharing ids lie side by side.
template <class Item>
std::vector<std::pair<Item, int>> by_ids(const std::vector<std::vector<Item>>& pieces) {
    std::vector<std::pair<Item, int>> held;
    for (std::size_t p = 0; p < pieces.size(); ++p)
        for (const Item& item : pieces[p]) held.push_back({item, static_cast<int>(p)});
    std::sort(held.begin(), held.end(), [](const auto& a, const auto& b) {
        return std::tie(a.first.ids, a.second) < std::tie(b.first.ids, b.second);
    });
    return held;
}

} // namespace

PieceInside piece_inside(const std::vector<std::int32_t>& tets, const std::vector<GlobalId>& ids,
                         const std::vector<std::int32_t>& used, const std::vector<std::array<std::int32_t, 3>>& boundary_faces) {
    std::vector<char> on_boundary(ids.size(), 0);
    for (const auto& f : boundary_faces)
        for (const std::int32_t v : f) on_boundary[static_cast<std::size_t>(v)] = 1;
    PieceInside inside;
    for (const std::int32_t v : used)
        if (!on_boundary[static_cast<std::size_t>(v)]) inside.nodes.push_back(ids[static_cast<std::size_t>(v)]);
    std::sort(inside.nodes.begin(), inside.nodes.end());
    const auto face_ids = [&ids](std::int32_t a, std::int32_t b, std::int32_t c) {
        FaceIds f{static_cast<std::uint32_t>(ids[static_cast<std::size_t>(a)]), static_cast<std::uint32_t>(ids[static_cast<std::size_t>(b)]),
                  static_cast<std::uint32_t>(ids[static_cast<std::size_t>(c)])};
        std::sort(f.begin(), f.end());
        return f;
    };
    // Faces whose corners all lie on the boundary, found twice where inside.
    for (std::size_t t = 0; t < tets.size() / 4; ++t)
        for (int skip = 0; skip < 4; ++skip) {
            std::int32_t f[3];
            int k = 0;
            for (int c = 0; c < 4; ++c)
                if (c != skip) f[k++] = tets[4 * t + static_cast<std::size_t>(c)];
            if (on_boundary[static_cast<std::size_t>(f[0])] && on_boundary[static_cast<std::size_t>(f[1])] &&
                on_boundary[static_cast<std::size_t>(f[2])])
                inside.faces.push_back(face_ids(f[0], f[1], f[2]));
        }
    std::sort(inside.faces.begin(), inside.faces.end());
    inside.faces.erase(std::unique(inside.faces.begin(), inside.faces.end()), inside.faces.end());
    std::vector<FaceIds> outside;
    for (const auto& f : boundary_faces) outside.push_back(face_ids(f[0], f[1], f[2]));
    std::sort(outside.begin(), outside.end());
    std::vector<FaceIds> faces;
    std::set_difference(inside.faces.begin(), inside.faces.end(), outside.begin(), outside.end(), std::back_inserter(faces));
    inside.faces = std::move(faces);
    return inside;
}

BoundaryFace boundary_face(const std::int32_t* corners, const std::array<std::int32_t, 3>& face,
                           const std::vector<GlobalId>& ids, std::uint64_t cell) {
    // The target order: the face's corners by id, then the one it lacks.
    std::array<std::int32_t, 4> target{face[0], face[1], face[2], 0};
    std::sort(target.begin(), target.begin() + 3, [&ids](std::int32_t a, std::int32_t b) {
        return ids[static_cast<std::size_t>(a)] < ids[static_cast<std::size_t>(b)];
    });
    for (int k = 0; k < 4; ++k)
        if (std::find(face.begin(), face.end(), corners[k]) == face.end()) target[3] = corners[k];
    int position[4];
    for (int k = 0; k < 4; ++k)
        position[k] = static_cast<int>(std::find(target.begin(), target.end(), corners[k]) - target.begin());
    std::uint32_t odd = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) odd ^= position[i] > position[j] ? 1u : 0u;
    BoundaryFace out{{}, odd, cell};
    for (int k = 0; k < 3; ++k)
        out.ids[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(ids[static_cast<std::size_t>(target[static_cast<std::size_t>(k)])]);
    return out;
}

void refuse_folds_between(const std::vector<std::vector<BoundaryFace>>& faces,
                          const std::vector<std::string>& names) {
    const std::vector<std::pair<BoundaryFace, int>> held = by_ids(faces);
    for (std::size_t i = 0; i < held.size();) {
        std::size_t j = i + 1;
        while (j < held.size() && held[j].first.ids == held[i].first.ids) ++j;
        const auto name = [&](std::size_t k) {
            return names[static_cast<std::size_t>(held[k].second)] + " (cell " + std::to_string(held[k].first.cell) + ")";
        };
        const FaceIds& f = held[i].first.ids;
        const std::string face = "the face of node ids " + std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " + std::to_string(f[2]);
        if (j - i > 2)
            throw Error(names[static_cast<std::size_t>(held[i + 2].second)] + ": " + face + " is on the boundary of " +
                        name(i) + ", " + name(i + 1) + " and " + name(i + 2) + kGhostHint);
        if (j - i == 2 && held[i].first.side == held[i + 1].first.side)
            throw Error(names[static_cast<std::size_t>(held[i + 1].second)] + ": cell " +
                        std::to_string(held[i + 1].first.cell) + " lies on the same side of " + face + " as cell " +
                        std::to_string(held[i].first.cell) + " of " + names[static_cast<std::size_t>(held[i].second)] +
                        ", its neighbour across it, so the two overlap: the mesh is tangled where it crosses from one "
                        "piece into the other");
        i = j;
    }
}

void refuse_shared_boundary_tets(const std::vector<std::vector<BoundaryTet>>& boundary,
                                 const std::vector<std::string>& names) {
    const std::vector<std::pair<BoundaryTet, int>> held = by_ids(boundary);
    for (std::size_t i = 1; i < held.size(); ++i)
        if (held[i].first == held[i - 1].first) {
            const auto& [tet, p] = held[i];
            const auto& [earlier, q] = held[i - 1];
            throw Error(names[static_cast<std::size_t>(p)] + ": the tetrahedron of node ids " + node_list(tet.ids) +
                        " (cell " + std::to_string(tet.cell) + ") is also in " + names[static_cast<std::size_t>(q)] +
                        " (cell " + std::to_string(earlier.cell) + ")" + kGhostHint);
        }
}

InsideOverlap find_inside_overlap(const std::vector<std::pair<int, PieceInside>>& inside,
                                  const std::vector<std::vector<BoundaryTet>>& boundary,
                                  const std::vector<std::string>& names) {
    // This rank's pieces' insides as one sorted table each, so that every
    // boundary tetrahedron is looked up once, whatever the number of pieces.
    std::vector<std::pair<GlobalId, int>> nodes;
    std::vector<std::pair<FaceIds, int>> faces;
    for (const auto& [p, in] : inside) {
        for (const GlobalId id : in.nodes) nodes.push_back({id, p});
        for (const FaceIds& f : in.faces) faces.push_back({f, p});
    }
    std::sort(nodes.begin(), nodes.end());
    std::sort(faces.begin(), faces.end());
    // For each boundary tetrahedron, the lowest piece it reaches inside and
    // the first reason in a fixed order (corners, then faces): each piece is
    // one rank's, so the choice is the same for any number of ranks.
    InsideOverlap found;
    for (std::size_t q = 0; q < boundary.size() && found.message.empty(); ++q) {
        for (std::size_t i = 0; i < boundary[q].size() && found.message.empty(); ++i) {
            const BoundaryTet& tet = boundary[q][i];
            std::string reason;
            const auto reach = [&](int other, const std::function<std::string()>& why) {
                if (other == static_cast<int>(q) || (found.other >= 0 && other >= found.other)) return;
                found.other = other;
                reason = why();
            };
            for (int k = 0; k < 4; ++k) {
                const GlobalId id = tet.ids[static_cast<std::size_t>(k)];
                for (auto at = std::lower_bound(nodes.begin(), nodes.end(), std::make_pair(id, -1));
                     at != nodes.end() && at->first == id; ++at)
                    reach(at->second, [&] { return "node id " + std::to_string(id) + " lies on no face of that piece's boundary"; });
            }
            for (int skip = 0; skip < 4; ++skip) {
                FaceIds f{};
                int k = 0;
                for (int c = 0; c < 4; ++c)
                    if (c != skip) f[static_cast<std::size_t>(k++)] = static_cast<std::uint32_t>(tet.ids[static_cast<std::size_t>(c)]);
                for (auto at = std::lower_bound(faces.begin(), faces.end(), std::make_pair(f, -1));
                     at != faces.end() && at->first == f; ++at)
                    reach(at->second, [&] {
                        return "its face of node ids " + std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " +
                               std::to_string(f[2]) + " lies between two tetrahedra of that piece";
                    });
            }
            if (found.other >= 0) {
                found.piece = static_cast<std::int64_t>(q);
                found.tet = i;
                found.message = names[q] + ": the tetrahedron of node ids " + node_list(tet.ids) + " (cell " +
                                std::to_string(tet.cell) + ") reaches inside " +
                                names[static_cast<std::size_t>(found.other)] + ": " + reason + kGhostHint;
            }
        }
    }
    return found;
}

} // namespace tetiso::detail
