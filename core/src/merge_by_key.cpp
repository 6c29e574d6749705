// Merging pieces by key (paper, section "Isosurface reduction and
// seaming"): a common numbering of two pieces is the merge of their sorted
// key lists; the vertices whose edges now lie inside the merged domains are
// unlocked.
#include "tetiso/seam.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <exception>
#include <iterator>
#include <mutex>
#include <numeric>
#include <string>
#include <vector>

#include "parallel.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

bool same_position(const Piece& a, std::size_t i, const Piece& b, std::size_t j) {
    return std::bit_cast<std::uint32_t>(a.x[i]) == std::bit_cast<std::uint32_t>(b.x[j]) &&
           std::bit_cast<std::uint32_t>(a.y[i]) == std::bit_cast<std::uint32_t>(b.y[j]) &&
           std::bit_cast<std::uint32_t>(a.z[i]) == std::bit_cast<std::uint32_t>(b.z[j]);
}

std::string key_text(EdgeKey key) {
    return "(" + std::to_string(edge_key_low(key)) + ", " + std::to_string(edge_key_high(key)) + ")";
}

// Where the merge's output is cut at position d, as (i, j): a[0, i) and
// b[0, j) come before the cut. The merge path (Odeh, Green,
// Mwassi, Shmueli, Birk, "Merge Path - Parallel Merging Made Simple", 2012):
// the merge takes a's vertex first on equal keys, and the first d vertices
// it takes are a[0, i) and b[0, d - i) for the i found by binary search. A key
// held by both pieces is one vertex of the output, so its two copies are
// kept in one block.
std::pair<std::size_t, std::size_t> merge_cut(const std::vector<EdgeKey>& a, const std::vector<EdgeKey>& b,
                                              std::size_t d) {
    std::size_t lo = d > b.size() ? d - b.size() : 0, hi = std::min(d, a.size());
    while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (a[mid] <= b[d - mid - 1]) lo = mid + 1;
        else hi = mid;
    }
    std::size_t j = d - lo;
    if (lo > 0 && j < b.size() && a[lo - 1] == b[j]) ++j;
    return {lo, j};
}

// function(i) for i < n on `threads` threads, for a function that may throw:
// the exception of the lowest i is rethrown after the loop, the one a serial
// loop would have thrown first.
template <class Function>
void for_each_may_throw(int threads, std::int64_t n, parallel::Grain grain, const Function& function) {
    std::mutex mutex;
    std::int64_t first = n;
    std::exception_ptr error;
    parallel::for_each(threads, n, grain, [&](std::int64_t i) {
        try {
            function(i);
        } catch (...) {
            const std::lock_guard lock(mutex);
            if (i < first) first = i, error = std::current_exception();
        }
    });
    if (error) std::rethrow_exception(error);
}

} // namespace

Piece merge_by_key(const Piece& a, const Piece& b, int threads) {
    threads = parallel::resolve_threads(threads);
    std::vector<int> shared;
    std::set_intersection(a.domains.begin(), a.domains.end(), b.domains.begin(), b.domains.end(),
                          std::back_inserter(shared));
    if (!shared.empty())
        throw Error("cannot seam two pieces that both cover domain " + std::to_string(shared.front()));

    // The merge in contiguous blocks of its inputs, cut by merge_cut: each
    // block counts its vertices, the counts are summed in block order, and
    // each block writes its vertices from there, so the output is the
    // serial merge's for any thread count.
    const std::size_t na = a.vertex_count(), nb = b.vertex_count();
    const parallel::Blocks blocks(threads, static_cast<std::int64_t>(na + nb));
    const auto block_count = static_cast<std::size_t>(blocks.count);
    std::vector<std::pair<std::size_t, std::size_t>> cut(block_count + 1);
    for (std::size_t k = 0; k <= block_count; ++k)
        cut[k] = merge_cut(a.key, b.key, static_cast<std::size_t>(blocks.begin(static_cast<std::int64_t>(k))));
    // Each block's vertex count, and the first key in it whose two copies
    // lie at different positions (none: the block's end).
    std::vector<std::int64_t> first(block_count + 1, 0);
    std::vector<std::pair<std::size_t, std::size_t>> mismatch(block_count);
    parallel::for_each(blocks.parallel() ? threads : 1, blocks.count, [&](std::int64_t block) {
        const auto k = static_cast<std::size_t>(block);
        auto [i, j] = cut[k];
        const auto [i_end, j_end] = cut[k + 1];
        std::int64_t count = 0;
        mismatch[k] = {i_end, j_end};
        while (i < i_end || j < j_end) {
            ++count;
            if (j == j_end || (i < i_end && a.key[i] < b.key[j])) {
                ++i;
            } else if (i == i_end || b.key[j] < a.key[i]) {
                ++j;
            } else {
                if (!same_position(a, i, b, j) && mismatch[k].first == i_end) mismatch[k] = {i, j};
                ++i, ++j;
            }
        }
        first[k + 1] = count;
    }, 0);
    for (std::size_t k = 0; k < block_count; ++k)
        if (mismatch[k].first != cut[k + 1].first)
            throw Error("vertex of edge " + key_text(a.key[mismatch[k].first]) +
                        " has different positions in the two pieces being seamed");
    for (std::size_t k = 0; k < block_count; ++k) first[k + 1] += first[k];

    Piece out;
    const auto n = static_cast<std::size_t>(first.back());
    out.x.resize(n);
    out.y.resize(n);
    out.z.resize(n);
    out.key.resize(n);
    out.flags.resize(n);
    std::vector<std::int32_t> from_a(na), from_b(nb);
    const auto put = [&out](std::size_t at, const Piece& from, std::size_t i, std::uint8_t flags) {
        out.x[at] = from.x[i];
        out.y[at] = from.y[i];
        out.z[at] = from.z[i];
        out.key[at] = from.key[i];
        out.flags[at] = flags;
    };
    parallel::for_each(blocks.parallel() ? threads : 1, blocks.count, [&](std::int64_t block) {
        const auto k = static_cast<std::size_t>(block);
        auto [i, j] = cut[k];
        const auto [i_end, j_end] = cut[k + 1];
        for (auto next = static_cast<std::size_t>(first[k]); i < i_end || j < j_end; ++next) {
            if (j == j_end || (i < i_end && a.key[i] < b.key[j])) {
                put(next, a, i, a.flags[i]);
                from_a[i++] = static_cast<std::int32_t>(next);
            } else if (i == i_end || b.key[j] < a.key[i]) {
                put(next, b, j, b.flags[j]);
                from_b[j++] = static_cast<std::int32_t>(next);
            } else {
                // A vertex on the common interface: still locked only where both
                // sides say so; unlock_settled decides what the merged piece frees.
                put(next, a, i, static_cast<std::uint8_t>(a.flags[i] & b.flags[j]));
                from_a[i++] = static_cast<std::int32_t>(next);
                from_b[j++] = static_cast<std::int32_t>(next);
            }
        }
    }, 0);

    const std::size_t ma = a.triangle_count(), mb = b.triangle_count();
    const std::size_t corners_a = a.triangles.size();
    out.triangles.resize(corners_a + b.triangles.size());
    parallel::for_each(threads, static_cast<std::int64_t>(corners_a), [&](std::int64_t c) {
        out.triangles[static_cast<std::size_t>(c)] = from_a[static_cast<std::size_t>(a.triangles[static_cast<std::size_t>(c)])];
    });
    parallel::for_each(threads, static_cast<std::int64_t>(b.triangles.size()), [&](std::int64_t c) {
        out.triangles[corners_a + static_cast<std::size_t>(c)] =
            from_b[static_cast<std::size_t>(b.triangles[static_cast<std::size_t>(c)])];
    });
    if (!a.error.empty() || !b.error.empty()) {
        out.error.resize(ma + mb);
        parallel::for_each(threads, static_cast<std::int64_t>(ma + mb), [&](std::int64_t t) {
            const auto u = static_cast<std::size_t>(t);
            out.error[u] = u < ma ? a.triangle_error(u) : b.triangle_error(u - ma);
        });
    }
    if (!a.sampled.empty() || !b.sampled.empty()) {
        out.sampled.resize(ma + mb);
        parallel::for_each(threads, static_cast<std::int64_t>(ma + mb), [&](std::int64_t t) {
            const auto u = static_cast<std::size_t>(t);
            out.sampled[u] = (u < ma ? a.triangle_sampled(u) : b.triangle_sampled(u - ma)) ? 1 : 0;
        });
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

std::size_t unlock_settled(Piece& piece, const EdgeDomains& domains_of_edge, int threads) {
    threads = parallel::resolve_threads(threads);
    const auto n = static_cast<std::int64_t>(piece.vertex_count());
    // Uneven costs (only locked vertices ask domains_of_edge, and they
    // gather along the interfaces, so in runs of keys): dynamic chunks.
    std::vector<std::uint8_t> freed(piece.vertex_count(), 0);
    for_each_may_throw(threads, n, parallel::Grain::kTests, [&](std::int64_t i) {
        const auto v = static_cast<std::size_t>(i);
        if (!(piece.flags[v] & kLocked)) return;
        const std::vector<int> holders = domains_of_edge(edge_key_low(piece.key[v]), edge_key_high(piece.key[v]));
        if (std::includes(piece.domains.begin(), piece.domains.end(), holders.begin(), holders.end())) {
            piece.flags[v] = static_cast<std::uint8_t>(piece.flags[v] & ~kLocked);
            freed[v] = 1;
        }
    });
    return static_cast<std::size_t>(parallel::count(threads, n, [&](std::int64_t v) { return freed[static_cast<std::size_t>(v)] != 0; }));
}

} // namespace tetiso
