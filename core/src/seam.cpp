// Seaming by key (paper, section "Isosurface reduction and seaming"): a
// common numbering of two pieces is the merge of their sorted key lists.
#include "tetiso/seam.hpp"

#include <algorithm>
#include <bit>
#include <string>

#include "tetiso/error.hpp"

namespace tetiso {
namespace {

bool same_position(const Piece& a, std::size_t i, const Piece& b, std::size_t j) {
    return std::bit_cast<std::uint32_t>(a.x[i]) == std::bit_cast<std::uint32_t>(b.x[j]) &&
           std::bit_cast<std::uint32_t>(a.y[i]) == std::bit_cast<std::uint32_t>(b.y[j]) &&
           std::bit_cast<std::uint32_t>(a.z[i]) == std::bit_cast<std::uint32_t>(b.z[j]);
}

void append_vertex(Piece& out, const Piece& from, std::size_t i, std::uint8_t flags) {
    out.x.push_back(from.x[i]);
    out.y.push_back(from.y[i]);
    out.z.push_back(from.z[i]);
    out.key.push_back(from.key[i]);
    out.flags.push_back(flags);
}

std::string key_text(EdgeKey key) {
    return "(" + std::to_string(edge_key_low(key)) + ", " + std::to_string(edge_key_high(key)) + ")";
}

} // namespace

Piece merge_by_key(const Piece& a, const Piece& b) {
    std::vector<int> shared;
    std::set_intersection(a.domains.begin(), a.domains.end(), b.domains.begin(), b.domains.end(),
                          std::back_inserter(shared));
    if (!shared.empty())
        throw Error("cannot seam two pieces that both cover domain " + std::to_string(shared.front()));

    Piece out;
    const std::size_t na = a.vertex_count(), nb = b.vertex_count();
    out.x.reserve(na + nb);
    out.y.reserve(na + nb);
    out.z.reserve(na + nb);
    out.key.reserve(na + nb);
    out.flags.reserve(na + nb);
    std::vector<std::int32_t> from_a(na), from_b(nb);
    std::size_t i = 0, j = 0;
    while (i < na || j < nb) {
        const auto next = static_cast<std::int32_t>(out.key.size());
        if (j == nb || (i < na && a.key[i] < b.key[j])) {
            append_vertex(out, a, i, a.flags[i]);
            from_a[i++] = next;
        } else if (i == na || b.key[j] < a.key[i]) {
            append_vertex(out, b, j, b.flags[j]);
            from_b[j++] = next;
        } else {
            if (!same_position(a, i, b, j))
                throw Error("vertex of edge " + key_text(a.key[i]) +
                            " has different positions in the two pieces being seamed");
            // A vertex on the common interface: still locked only where both
            // sides say so; unlock_settled decides what the merged piece frees.
            append_vertex(out, a, i, static_cast<std::uint8_t>(a.flags[i] & b.flags[j]));
            from_a[i++] = next;
            from_b[j++] = next;
        }
    }
    out.triangles.reserve(a.triangles.size() + b.triangles.size());
    for (const std::int32_t v : a.triangles) out.triangles.push_back(from_a[static_cast<std::size_t>(v)]);
    for (const std::int32_t v : b.triangles) out.triangles.push_back(from_b[static_cast<std::size_t>(v)]);
    std::merge(a.domains.begin(), a.domains.end(), b.domains.begin(), b.domains.end(),
               std::back_inserter(out.domains));
    return out;
}

Piece merge_all(std::vector<Piece> pieces) {
    if (pieces.empty()) return {};
    // Sorting by first domain makes the tree, and so the result's triangle
    // order, independent of the order the pieces arrived in.
    std::sort(pieces.begin(), pieces.end(), [](const Piece& p, const Piece& q) {
        return p.domains.empty() ? !q.domains.empty() : !q.domains.empty() && p.domains.front() < q.domains.front();
    });
    while (pieces.size() > 1) {
        std::vector<Piece> next;
        next.reserve((pieces.size() + 1) / 2);
        for (std::size_t k = 0; k + 1 < pieces.size(); k += 2) next.push_back(merge_by_key(pieces[k], pieces[k + 1]));
        if (pieces.size() % 2 == 1) next.push_back(std::move(pieces.back()));
        pieces = std::move(next);
    }
    return std::move(pieces.front());
}

std::size_t unlock_settled(Piece& piece, const EdgeDomains& domains_of_edge) {
    std::size_t unlocked = 0;
    for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
        if (!(piece.flags[v] & kLocked)) continue;
        const std::vector<int> holders = domains_of_edge(edge_key_low(piece.key[v]), edge_key_high(piece.key[v]));
        if (std::includes(piece.domains.begin(), piece.domains.end(), holders.begin(), holders.end())) {
            piece.flags[v] = static_cast<std::uint8_t>(piece.flags[v] & ~kLocked);
            ++unlocked;
        }
    }
    return unlocked;
}

} // namespace tetiso
