// Seaming by key (paper, section "Isosurface reduction and seaming"): a
// common numbering of two pieces is the merge of their sorted key lists.
#include "tetiso/seam.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <limits>
#include <numeric>
#include <string>

#include "tetiso/error.hpp"

namespace tetiso {
namespace {

// Seconds since `since`, which moves to now: consecutive calls time
// consecutive steps.
double lap(std::chrono::steady_clock::time_point& since) {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - since).count();
    since = now;
    return seconds;
}

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
    if (!a.error.empty() || !b.error.empty()) {
        out.error.reserve(a.triangle_count() + b.triangle_count());
        for (const Piece* p : {&a, &b})
            for (std::size_t t = 0; t < p->triangle_count(); ++t) out.error.push_back(p->triangle_error(t));
    }
    if (!a.sampled.empty() || !b.sampled.empty()) {
        out.sampled.reserve(a.triangle_count() + b.triangle_count());
        for (const Piece* p : {&a, &b})
            for (std::size_t t = 0; t < p->triangle_count(); ++t) out.sampled.push_back(p->triangle_sampled(t) ? 1 : 0);
    }
    out.sample_xyz = a.sample_xyz;
    out.sample_xyz.insert(out.sample_xyz.end(), b.sample_xyz.begin(), b.sample_xyz.end());
    out.sample_triangle = a.sample_triangle;
    const auto b_first = static_cast<std::int32_t>(a.triangle_count());
    for (const std::int32_t t : b.sample_triangle) out.sample_triangle.push_back(b_first + t);
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
    order_triangles(pieces.front());
    return std::move(pieces.front());
}

void order_triangles(Piece& piece) {
    const std::size_t m = piece.triangle_count();
    std::vector<std::array<std::int32_t, 3>> corners(m);
    for (std::size_t t = 0; t < m; ++t) {
        auto& c = corners[t];
        std::copy_n(piece.triangles.begin() + static_cast<std::ptrdiff_t>(3 * t), 3, c.begin());
        std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    }
    std::vector<std::int32_t> order(m);
    std::iota(order.begin(), order.end(), 0);
    // Stable: a triangle given twice keeps its copies' order (and bounds).
    std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
        return corners[static_cast<std::size_t>(a)] < corners[static_cast<std::size_t>(b)];
    });
    std::vector<std::int32_t> position(m);
    for (std::size_t t = 0; t < m; ++t) {
        const auto from = static_cast<std::size_t>(order[t]);
        std::copy(corners[from].begin(), corners[from].end(), piece.triangles.begin() + static_cast<std::ptrdiff_t>(3 * t));
        position[from] = static_cast<std::int32_t>(t);
    }
    const auto permute = [&](auto& values) {
        if (values.size() != m) return;
        auto copy = values;
        for (std::size_t t = 0; t < m; ++t) values[t] = copy[static_cast<std::size_t>(order[t])];
    };
    permute(piece.error);
    permute(piece.sampled);
    for (std::int32_t& t : piece.sample_triangle) t = position[static_cast<std::size_t>(t)];
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

namespace tetiso {
namespace {

// Compressed rows: row r lists list[first[r] .. first[r+1]).
struct Rows {
    std::vector<std::int32_t> first;
    std::vector<std::int32_t> list;
};

// Groups entry i of `row_of` (a row index in [0, rows)) as i / per into its
// row, by a counting sort, so each row lists its members in ascending order.
Rows group_by(std::size_t rows, const std::vector<std::int32_t>& row_of, std::size_t per) {
    Rows out;
    out.first.assign(rows + 1, 0);
    for (const std::int32_t r : row_of) ++out.first[static_cast<std::size_t>(r) + 1];
    for (std::size_t r = 0; r < rows; ++r) out.first[r + 1] += out.first[r];
    out.list.resize(row_of.size());
    std::vector<std::int32_t> cursor(out.first.begin(), out.first.end() - 1);
    for (std::size_t i = 0; i < row_of.size(); ++i)
        out.list[static_cast<std::size_t>(cursor[static_cast<std::size_t>(row_of[i])]++)] = static_cast<std::int32_t>(i / per);
    return out;
}

// Triangles around each vertex.
Rows incidence(const Piece& piece) { return group_by(piece.vertex_count(), piece.triangles, 3); }

// Vertices of the region that would have more than one fan in it (more than
// two region-border edges): the sub-piece must be a manifold for reduce().
std::vector<std::int32_t> pinched_vertices(const Piece& piece, const std::vector<std::int32_t>& region) {
    std::vector<std::uint64_t> edges;
    edges.reserve(region.size() * 3);
    for (const std::int32_t t : region)
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::uint32_t>(piece.triangles[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::uint32_t>(piece.triangles[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>((k + 1) % 3)]);
            edges.push_back((static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    std::vector<std::int32_t> ends;
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i == 1) {
            ends.push_back(static_cast<std::int32_t>(edges[i] >> 32));
            ends.push_back(static_cast<std::int32_t>(edges[i] & 0xffffffffu));
        }
        i = j;
    }
    std::sort(ends.begin(), ends.end());
    std::vector<std::int32_t> pinched;
    for (std::size_t i = 0; i < ends.size();) {
        std::size_t j = i;
        while (j < ends.size() && ends[j] == ends[i]) ++j;
        if (j - i > 2) pinched.push_back(ends[i]);
        i = j;
    }
    return pinched;
}

// Each triangle's samples.
Rows samples_of(const Piece& piece) { return group_by(piece.triangle_count(), piece.sample_triangle, 1); }

// Appends sample i of `from` to `to`, held by triangle t.
void append_sample(Piece& to, const Piece& from, std::size_t i, std::int32_t t) {
    to.sample_xyz.insert(to.sample_xyz.end(), from.sample_xyz.begin() + static_cast<std::ptrdiff_t>(3 * i),
                         from.sample_xyz.begin() + static_cast<std::ptrdiff_t>(3 * i + 3));
    to.sample_triangle.push_back(t);
}

// Vertices within `rings` edges of the marked ones (marks set to 1 in
// place), by breadth-first search; returns every vertex reached, the marked
// ones first.
std::vector<std::int32_t> grow(const Piece& piece, const Rows& around, std::vector<std::uint8_t>& near,
                               int rings) {
    std::vector<std::int32_t> frontier;
    for (std::size_t v = 0; v < near.size(); ++v)
        if (near[v]) frontier.push_back(static_cast<std::int32_t>(v));
    std::vector<std::int32_t> reached = frontier;
    for (int ring = 0; ring < rings && !frontier.empty(); ++ring) {
        std::vector<std::int32_t> next;
        for (const std::int32_t v : frontier)
            for (std::int32_t i = around.first[static_cast<std::size_t>(v)]; i < around.first[static_cast<std::size_t>(v) + 1]; ++i)
                for (int k = 0; k < 3; ++k) {
                    const std::int32_t w = piece.triangles[3 * static_cast<std::size_t>(around.list[static_cast<std::size_t>(i)]) + static_cast<std::size_t>(k)];
                    if (!near[static_cast<std::size_t>(w)]) {
                        near[static_cast<std::size_t>(w)] = 1;
                        next.push_back(w);
                    }
                }
        reached.insert(reached.end(), next.begin(), next.end());
        frontier = std::move(next);
    }
    return reached;
}

} // namespace

void keep_samples_near_locked(Piece& piece, int rings) {
    if (piece.sampled.empty()) return;
    std::vector<std::uint8_t> near(piece.vertex_count(), 0);
    bool any = false;
    for (std::size_t v = 0; v < piece.vertex_count(); ++v)
        if (piece.flags[v] & kLocked) near[v] = 1, any = true;
    if (!any || rings < 0) {
        piece.sample_xyz = {};
        piece.sample_triangle = {};
        piece.sampled = {};
        return;
    }
    grow(piece, incidence(piece), near, rings);
    for (std::size_t t = 0; t < piece.triangle_count(); ++t)
        if (!(near[static_cast<std::size_t>(piece.triangles[3 * t])] || near[static_cast<std::size_t>(piece.triangles[3 * t + 1])] ||
              near[static_cast<std::size_t>(piece.triangles[3 * t + 2])]))
            piece.sampled[t] = 0;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < piece.sample_count(); ++i) {
        if (!piece.sampled[static_cast<std::size_t>(piece.sample_triangle[i])]) continue;
        for (std::size_t c = 0; c < 3; ++c) piece.sample_xyz[3 * kept + c] = piece.sample_xyz[3 * i + c];
        piece.sample_triangle[kept++] = piece.sample_triangle[i];
    }
    piece.sample_xyz.resize(3 * kept);
    piece.sample_triangle.resize(kept);
    piece.sample_xyz.shrink_to_fit();
    piece.sample_triangle.shrink_to_fit();
}

Piece reduce_near(const Piece& piece, const std::vector<std::uint8_t>& seed, const SeamOptions& options,
                  SeamReport* report) {
    auto clock = std::chrono::steady_clock::now();
    const std::size_t n = piece.vertex_count();
    const Rows around = incidence(piece);

    std::vector<std::uint8_t> near(n, 0);
    for (std::size_t v = 0; v < n; ++v) near[v] = seed[v] ? 1 : 0;
    const std::vector<std::int32_t> reached = grow(piece, around, near, options.rings);

    // The region: every triangle around a reached vertex, grown over pinched
    // rim vertices until it is a manifold with border. A vertex can also be
    // pinched in the piece itself: where a domain of an unstructured
    // partition touches itself along an edge, its piece has two fans there
    // until the domain across that edge joins (the vertex is locked until
    // then). Growing cannot mend that; such a vertex is frozen instead, its
    // triangles left out of the region for good, which makes each step
    // either freeze a vertex or add a triangle, so the loop ends.
    std::vector<std::uint8_t> in_region(piece.triangle_count(), 0);
    std::vector<std::uint8_t> frozen(n, 0);
    std::vector<std::int32_t> region;
    const auto corners = [&piece](std::int32_t t) { return piece.triangles.data() + 3 * static_cast<std::size_t>(t); };
    const auto allowed = [&](std::int32_t t) {
        const std::int32_t* c = corners(t);
        return !frozen[static_cast<std::size_t>(c[0])] && !frozen[static_cast<std::size_t>(c[1])] &&
               !frozen[static_cast<std::size_t>(c[2])];
    };
    auto take_umbrella = [&](std::int32_t v) {
        bool grew = false;
        for (std::int32_t i = around.first[static_cast<std::size_t>(v)]; i < around.first[static_cast<std::size_t>(v) + 1]; ++i) {
            const std::int32_t t = around.list[static_cast<std::size_t>(i)];
            if (!in_region[static_cast<std::size_t>(t)] && allowed(t)) {
                in_region[static_cast<std::size_t>(t)] = 1;
                region.push_back(t);
                grew = true;
            }
        }
        return grew;
    };
    // Grows the region over pinched vertices until it is a manifold with
    // border, freezing the vertices that growing cannot mend.
    auto mend_pinches = [&] {
        for (std::vector<std::int32_t> pinched = pinched_vertices(piece, region); !pinched.empty();
             pinched = pinched_vertices(piece, region)) {
            bool froze = false;
            for (const std::int32_t v : pinched)
                if (!take_umbrella(v)) {
                    frozen[static_cast<std::size_t>(v)] = 1;
                    froze = true;
                }
            if (froze) {
                std::erase_if(region, [&](std::int32_t t) {
                    if (allowed(t)) return false;
                    in_region[static_cast<std::size_t>(t)] = 0;
                    return true;
                });
            }
        }
    };
    const auto whole_umbrella_in = [&](std::size_t v, const std::vector<std::uint8_t>& in) {
        for (std::int32_t j = around.first[v]; j < around.first[v + 1]; ++j)
            if (!in[static_cast<std::size_t>(around.list[static_cast<std::size_t>(j)])]) return false;
        return true;
    };
    for (const std::int32_t v : reached) take_umbrella(v);
    mend_pinches();

    // What the reduction may change: the vertices whose every triangle is in
    // the region (inner); the others, the rim, are locked so that the region
    // still fits the rest of the piece. The legality tests of a collapse or
    // flip (link condition, valences, cones, contacts) read the whole fan of
    // every corner of the faces it makes, rim vertices among them: a fan cut
    // at the rim hides the common neighbours that only faces beyond it join,
    // and the faces beyond it that a new face may come to touch (soak job
    // 46:514: two faces laid into the plane of a fold just beyond the rim,
    // across its edge). So the reduction also gets the triangles around the
    // rim, every vertex of theirs locked; no operation changes a face whose
    // corners are all locked (legality.hpp), so they come back as they were.
    // Where a rim vertex's fan cannot be completed (a frozen vertex beside
    // it), its neighbours are locked too, so that no face is made at it.
    std::vector<std::uint8_t> inner(n, 0);
    for (const std::int32_t t : region)
        for (int k = 0; k < 3; ++k) {
            const auto v = static_cast<std::size_t>(piece.triangles[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)]);
            inner[v] = whole_umbrella_in(v, in_region);
        }
    for (std::size_t r = 0, inner_end = region.size(); r < inner_end; ++r)
        for (int k = 0; k < 3; ++k) {
            const std::int32_t v = piece.triangles[3 * static_cast<std::size_t>(region[r]) + static_cast<std::size_t>(k)];
            if (!inner[static_cast<std::size_t>(v)]) take_umbrella(v);
        }
    mend_pinches();
    std::sort(region.begin(), region.end());

    // The sub-piece, numbered in the piece's (key) order.
    std::vector<std::int32_t> local(n, -1);
    std::vector<std::int32_t> members;
    for (const std::int32_t t : region)
        for (int k = 0; k < 3; ++k) {
            const std::int32_t v = piece.triangles[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)];
            if (local[static_cast<std::size_t>(v)] < 0) {
                local[static_cast<std::size_t>(v)] = 0;
                members.push_back(v);
            }
        }
    std::sort(members.begin(), members.end());
    std::vector<std::uint8_t> complete(n, 0);
    for (const std::int32_t v : members)
        complete[static_cast<std::size_t>(v)] = whole_umbrella_in(static_cast<std::size_t>(v), in_region);
    const auto free_to_change = [&](std::size_t v) {
        if (!inner[v] || !complete[v]) return false;
        for (std::int32_t j = around.first[v]; j < around.first[v + 1]; ++j)
            for (int k = 0; k < 3; ++k)
                if (!complete[static_cast<std::size_t>(
                        piece.triangles[3 * static_cast<std::size_t>(around.list[static_cast<std::size_t>(j)]) + static_cast<std::size_t>(k)])])
                    return false;
        return true;
    };
    Piece sub;
    sub.domains = piece.domains;
    for (std::size_t i = 0; i < members.size(); ++i) {
        const auto v = static_cast<std::size_t>(members[i]);
        local[v] = static_cast<std::int32_t>(i);
        sub.x.push_back(piece.x[v]);
        sub.y.push_back(piece.y[v]);
        sub.z.push_back(piece.z[v]);
        sub.key.push_back(piece.key[v]);
        sub.flags.push_back(static_cast<std::uint8_t>(piece.flags[v] | (free_to_change(v) ? 0 : kLocked)));
    }
    const Rows held = samples_of(piece);
    for (std::size_t r = 0; r < region.size(); ++r) {
        const auto t = static_cast<std::size_t>(region[r]);
        sub.error.push_back(piece.triangle_error(t));
        if (!piece.sampled.empty()) sub.sampled.push_back(piece.sampled[t]);
        for (int k = 0; k < 3; ++k)
            sub.triangles.push_back(local[static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)])]);
        for (std::int32_t j = held.first[t]; j < held.first[t + 1]; ++j)
            append_sample(sub, piece, static_cast<std::size_t>(held.list[static_cast<std::size_t>(j)]), static_cast<std::int32_t>(r));
    }

    const double region_seconds = lap(clock);
    ReduceReport reduce_report;
    ReduceOptions reduce_options = options.reduce_options;
    reduce_options.keep_samples = true;
    // The reduction keeps its new faces within the box of the region's
    // vertices (each new vertex lies on an edge it collapses): the faces of
    // the rest of the piece that reach into that box are its obstacles.
    if (!members.empty()) {
        std::array<float, 3> lo{sub.x[0], sub.y[0], sub.z[0]}, hi = lo;
        for (std::size_t i = 0; i < sub.vertex_count(); ++i) {
            const std::array<float, 3> p{sub.x[i], sub.y[i], sub.z[i]};
            for (int c = 0; c < 3; ++c) {
                lo[c] = std::min(lo[c], p[c]);
                hi[c] = std::max(hi[c], p[c]);
            }
        }
        for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
            if (in_region[t]) continue;
            bool apart = false;
            for (int c = 0; c < 3 && !apart; ++c) {
                float low = std::numeric_limits<float>::max(), high = -low;
                for (int k = 0; k < 3; ++k) {
                    const auto v = static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)]);
                    const float q = c == 0 ? piece.x[v] : c == 1 ? piece.y[v] : piece.z[v];
                    low = std::min(low, q);
                    high = std::max(high, q);
                }
                apart = low > hi[c] || high < lo[c];
            }
            if (apart) continue;
            for (int k = 0; k < 3; ++k) {
                const auto v = static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)]);
                reduce_options.obstacles.insert(reduce_options.obstacles.end(), {piece.x[v], piece.y[v], piece.z[v]});
            }
        }
    }
    const Piece reduced = options.reducer ? options.reducer(sub, reduce_options, &reduce_report)
                                          : reduce(sub, reduce_options, &reduce_report);
    const double reduce_seconds = lap(clock);

    // Splice: vertices of the sub-piece that the reduction removed are dropped,
    // those it kept take their new positions; both lists are in key order.
    std::vector<std::uint8_t> keep(n, 1);
    std::vector<std::int32_t> from_reduced(reduced.vertex_count(), -1);
    std::size_t r = 0;
    for (const std::int32_t v : members) {
        const auto vi = static_cast<std::size_t>(v);
        if (r < reduced.vertex_count() && reduced.key[r] == piece.key[vi]) {
            from_reduced[r++] = v;
        } else {
            keep[vi] = 0;
        }
    }
    std::vector<std::int32_t> renumber(n, -1);
    Piece out;
    out.domains = piece.domains;
    for (std::size_t v = 0, r2 = 0; v < n; ++v) {
        if (!keep[v]) continue;
        renumber[v] = static_cast<std::int32_t>(out.key.size());
        const bool moved = local[v] >= 0;
        if (moved) {
            while (reduced.key[r2] != piece.key[v]) ++r2;
        }
        out.x.push_back(moved ? reduced.x[r2] : piece.x[v]);
        out.y.push_back(moved ? reduced.y[r2] : piece.y[v]);
        out.z.push_back(moved ? reduced.z[r2] : piece.z[v]);
        out.key.push_back(piece.key[v]);
        out.flags.push_back(piece.flags[v]);
    }
    out.triangles.reserve(piece.triangles.size());
    out.error.reserve(piece.triangle_count());
    for (std::size_t t = 0; t < piece.triangle_count(); ++t)
        if (!in_region[t]) {
            const auto to = static_cast<std::int32_t>(out.triangle_count());
            for (int k = 0; k < 3; ++k)
                out.triangles.push_back(renumber[static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)])]);
            out.error.push_back(piece.triangle_error(t));
            out.sampled.push_back(piece.triangle_sampled(t) ? 1 : 0);
            for (std::int32_t j = held.first[t]; j < held.first[t + 1]; ++j)
                append_sample(out, piece, static_cast<std::size_t>(held.list[static_cast<std::size_t>(j)]), to);
        }
    const auto reduced_first = static_cast<std::int32_t>(out.triangle_count());
    for (const std::int32_t v : reduced.triangles)
        out.triangles.push_back(renumber[static_cast<std::size_t>(from_reduced[static_cast<std::size_t>(v)])]);
    out.error.insert(out.error.end(), reduced.error.begin(), reduced.error.end());
    for (std::size_t t = 0; t < reduced.triangle_count(); ++t) out.sampled.push_back(reduced.triangle_sampled(t) ? 1 : 0);
    if (std::find(out.sampled.begin(), out.sampled.end(), 1) == out.sampled.end()) out.sampled = {};
    for (std::size_t i = 0; i < reduced.sample_count(); ++i)
        append_sample(out, reduced, i, reduced_first + reduced.sample_triangle[i]);
    if (report) {
        report->region_triangles = region.size();
        report->reduce = reduce_report;
        report->seconds.region = region_seconds;
        report->seconds.reduce = reduce_seconds;
        report->seconds.splice = lap(clock);
    }
    return out;
}

Piece reduce_piece(const Piece& piece, const ReduceOptions& options, ReduceReport* report, const Reducer& reducer) {
    std::vector<std::int32_t> all(piece.triangle_count());
    std::iota(all.begin(), all.end(), 0);
    if (pinched_vertices(piece, all).empty()) {
        ReduceOptions whole = options;
        whole.keep_samples = true;
        return reducer ? reducer(piece, whole, report) : reduce(piece, whole, report);
    }
    SeamOptions around_pinches;
    around_pinches.reduce_options = options;
    around_pinches.reducer = reducer;
    around_pinches.rings = 0;
    SeamReport seam_report;
    Piece out = reduce_near(piece, std::vector<std::uint8_t>(piece.vertex_count(), 1), around_pinches, &seam_report);
    if (report) *report = seam_report.reduce;
    return out;
}

Piece seam(const Piece& a, const Piece& b, const EdgeDomains& domains_of_edge, const SeamOptions& options,
           SeamReport* report) {
    auto clock = std::chrono::steady_clock::now();
    Piece merged = merge_by_key(a, b);
    std::vector<std::uint8_t> seed(merged.flags);
    const std::size_t unlocked = unlock_settled(merged, domains_of_edge);
    if (report) {
        *report = SeamReport{};
        report->vertices_unlocked = unlocked;
        report->seconds.merge = lap(clock);
    }
    if (!options.reduce || unlocked == 0) return merged;
    for (std::size_t v = 0; v < seed.size(); ++v)
        seed[v] = (seed[v] & kLocked) && !(merged.flags[v] & kLocked) ? 1 : 0;
    Piece out = reduce_near(merged, seed, options, report);
    keep_samples_near_locked(out, options.sample_rings);
    return out;
}

} // namespace tetiso
