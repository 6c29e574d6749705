// Seaming (paper, section "Isosurface reduction and seaming"): two pieces
// merged by key (merge_by_key.cpp), then reduced again within a few rings of
// the vertices the merge unlocked, and spliced back by key.
#include "tetiso/seam.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <limits>
#include <numeric>
#include <string>

#include "exec_host.hpp"
#include "hd.hpp"
#include "parallel.hpp"
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

// An array whose elements are all written after it is sized: no zero fill
// first, a pass over the whole piece fewer.
template <class T>
using Written = std::vector<T, NoInitAllocator<T>>;

// Compressed rows: row r lists list[first[r] .. first[r+1]).
struct Rows {
    Written<std::int32_t> first;
    Written<std::int32_t> list;
};

// Groups entry i of `row_of` (a row index in [0, rows)) as i / per into its
// row, by a stable counting sort, so each row lists its members in
// ascending order. On several threads the sort goes by ranges of
// kRowsPerRange rows first (each block of entries counts its share of each
// range, the counts are summed range by range in block order, and each
// block copies its entries there), then each range is sorted by row alone,
// in a counting array that stays in cache: no atomics, and the rows come
// out as one thread makes them. That moves each entry twice more than the
// serial sort does, which a few threads do not repay: on two (a 2-core VM), a
// 900 k-triangle seam's region step took 35 ms with it against 26 without.
Rows group_by(int threads, std::size_t rows, const std::vector<std::int32_t>& row_of, std::int32_t per) {
    constexpr std::size_t kRowsPerRange = 4096;
    constexpr int kMinThreads = 4;
    Rows out;
    out.list.resize(row_of.size());
    const auto n = static_cast<std::int64_t>(row_of.size());
    const parallel::Blocks blocks(threads, n);
    if (!blocks.parallel() || threads < kMinThreads || rows == 0) {
        out.first.assign(rows + 1, 0);
        for (const std::int32_t r : row_of) ++out.first[static_cast<std::size_t>(r) + 1];
        for (std::size_t r = 0; r < rows; ++r) out.first[r + 1] += out.first[r];
        Written<std::int32_t> cursor(out.first.begin(), out.first.end() - 1);
        for (std::size_t i = 0; i < row_of.size(); ++i)
            out.list[static_cast<std::size_t>(cursor[static_cast<std::size_t>(row_of[i])]++)] = static_cast<std::int32_t>(i) / per;
        return out;
    }
    out.first.resize(rows + 1);
    const auto block_count = static_cast<std::size_t>(blocks.count);
    const std::size_t ranges = (rows + kRowsPerRange - 1) / kRowsPerRange;
    // at[block * ranges + range]: where the block's entries of that range go
    // (each block's counters apart, so that no two threads write one line).
    std::vector<std::int64_t> at(ranges * block_count, 0);
    parallel::for_each(threads, blocks.count, [&](std::int64_t b) {
        std::int64_t* count = at.data() + static_cast<std::size_t>(b) * ranges;
        for (std::int64_t i = blocks.begin(b); i < blocks.begin(b + 1); ++i)
            ++count[static_cast<std::size_t>(row_of[static_cast<std::size_t>(i)]) / kRowsPerRange];
    }, 0);
    parallel::offsets_by_bucket_then_block(at.data(), ranges, block_count);
    // Each entry and its row, by range: the sort within a range then reads
    // them in order, not row_of at random.
    Written<std::int32_t> entry(row_of.size()), row(row_of.size());
    parallel::for_each(threads, blocks.count, [&](std::int64_t b) {
        std::int64_t* cursor = at.data() + static_cast<std::size_t>(b) * ranges;
        for (std::int64_t i = blocks.begin(b); i < blocks.begin(b + 1); ++i) {
            const std::int32_t r = row_of[static_cast<std::size_t>(i)];
            const auto to = static_cast<std::size_t>(cursor[static_cast<std::size_t>(r) / kRowsPerRange]++);
            entry[to] = static_cast<std::int32_t>(i);
            row[to] = r;
        }
    }, 0);
    // Each cursor has moved to the end of its block's share: a range ends
    // where its last block's share does, and the next range begins there.
    const std::int64_t* last_block = at.data() + (block_count - 1) * ranges;
    parallel::for_each(threads, static_cast<std::int64_t>(ranges), [&](std::int64_t k) {
        const auto range = static_cast<std::size_t>(k);
        const auto begin = static_cast<std::size_t>(range == 0 ? 0 : last_block[range - 1]);
        const auto end = static_cast<std::size_t>(last_block[range]);
        const std::size_t row0 = range * kRowsPerRange, row_end = std::min(rows, row0 + kRowsPerRange);
        std::array<std::int32_t, kRowsPerRange + 1> cursor{};
        for (std::size_t e = begin; e < end; ++e) ++cursor[static_cast<std::size_t>(row[e]) - row0 + 1];
        cursor[0] = static_cast<std::int32_t>(begin);
        if (range == 0) out.first[0] = 0;
        for (std::size_t r = 0; r + row0 < row_end; ++r) {
            cursor[r + 1] += cursor[r];
            out.first[row0 + r + 1] = cursor[r + 1];
        }
        for (std::size_t e = begin; e < end; ++e)
            out.list[static_cast<std::size_t>(cursor[static_cast<std::size_t>(row[e]) - row0]++)] = entry[e] / per;
    });
    return out;
}

// Triangles around each vertex.
Rows incidence(const Piece& piece, int threads) { return group_by(threads, piece.vertex_count(), piece.triangles, 3); }

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
Rows samples_of(const Piece& piece, int threads) {
    return group_by(threads, piece.triangle_count(), piece.sample_triangle, 1);
}

// Appends sample i of `from` to `to`, held by triangle t.
void append_sample(Piece& to, const Piece& from, std::size_t i, std::int32_t t) {
    to.sample_xyz.insert(to.sample_xyz.end(), from.sample_xyz.begin() + static_cast<std::ptrdiff_t>(3 * i),
                         from.sample_xyz.begin() + static_cast<std::ptrdiff_t>(3 * i + 3));
    to.sample_triangle.push_back(t);
}

// Vertices within `rings` edges of the marked ones (marks set to 1 in
// place), by breadth-first search; returns every vertex reached, the marked
// ones first.
std::vector<std::int32_t> grow(int threads, const Piece& piece, const Rows& around, std::vector<std::uint8_t>& near,
                               int rings) {
    std::vector<std::int32_t> frontier(near.size());
    frontier.resize(static_cast<std::size_t>(parallel::filter(
        threads, static_cast<std::int64_t>(near.size()), [&](std::int64_t v) { return near[static_cast<std::size_t>(v)] != 0; },
        frontier.data())));
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

void keep_samples_near_locked(Piece& piece, int rings, int threads) {
    if (piece.sampled.empty()) return;
    threads = parallel::resolve_threads(threads);
    const auto n = static_cast<std::int64_t>(piece.vertex_count());
    const auto m = static_cast<std::int64_t>(piece.triangle_count());
    std::vector<std::uint8_t> near(piece.vertex_count());
    parallel::for_each(threads, n, [&](std::int64_t v) {
        near[static_cast<std::size_t>(v)] = piece.flags[static_cast<std::size_t>(v)] & kLocked ? 1 : 0;
    });
    if (rings < 0 || parallel::count(threads, n, [&](std::int64_t v) { return near[static_cast<std::size_t>(v)] != 0; }) == 0) {
        piece.sample_xyz = {};
        piece.sample_triangle = {};
        piece.sampled = {};
        return;
    }
    const auto touches = [&](std::int64_t t) {
        const std::int32_t* c = piece.triangles.data() + 3 * t;
        return near[static_cast<std::size_t>(c[0])] || near[static_cast<std::size_t>(c[1])] || near[static_cast<std::size_t>(c[2])];
    };
    // The vertices within `rings` edges of a locked one, ring by ring as
    // passes over the triangles (every corner of a triangle that touches the
    // vertices reached so far), which the threads share without the
    // incidence lists a breadth-first search would need. Marks are set, never
    // counted, so any order of the stores gives the same marks.
    std::vector<std::uint8_t> next;
    for (int ring = 0; ring < rings; ++ring) {
        next = near;
        std::uint8_t grew = 0;
        parallel::for_each(threads, m, [&](std::int64_t t) {
            if (!touches(t)) return;
            for (int k = 0; k < 3; ++k) {
                const auto v = static_cast<std::size_t>(piece.triangles[static_cast<std::size_t>(3 * t + k)]);
                if (near[v]) continue;
                hd::atomic_store(&next[v], std::uint8_t{1});
                hd::atomic_store(&grew, std::uint8_t{1});
            }
        });
        near.swap(next);
        if (!grew) break;
    }
    parallel::for_each(threads, m, [&](std::int64_t t) {
        if (!touches(t)) piece.sampled[static_cast<std::size_t>(t)] = 0;
    });
    const auto samples = static_cast<std::int64_t>(piece.sample_count());
    std::vector<std::int32_t> at(piece.sample_count());
    const std::int32_t kept = parallel::rank(threads, samples, [&](std::int64_t i) {
        return piece.sampled[static_cast<std::size_t>(piece.sample_triangle[static_cast<std::size_t>(i)])] != 0;
    }, at.data());
    std::vector<float> xyz(3 * static_cast<std::size_t>(kept));
    std::vector<std::int32_t> holder(static_cast<std::size_t>(kept));
    parallel::for_each(threads, samples, [&](std::int64_t i) {
        const auto from = static_cast<std::size_t>(i);
        if (at[from] < 0) return;
        const auto to = static_cast<std::size_t>(at[from]);
        for (std::size_t c = 0; c < 3; ++c) xyz[3 * to + c] = piece.sample_xyz[3 * from + c];
        holder[to] = piece.sample_triangle[from];
    });
    piece.sample_xyz = std::move(xyz);
    piece.sample_triangle = std::move(holder);
}

Piece reduce_near(const Piece& piece, const std::vector<std::uint8_t>& seed, const SeamOptions& options,
                  SeamReport* report) {
    auto clock = std::chrono::steady_clock::now();
    // The passes over the whole piece (finding the region, its obstacles,
    // the splice) on the reduction's threads; the steps within the region
    // stay on one, as they are as small as the region is.
    const int threads = parallel::resolve_threads(options.reduce_options.threads);
    const std::size_t n = piece.vertex_count();
    const Rows around = incidence(piece, threads);

    std::vector<std::uint8_t> near(n);
    parallel::for_each(threads, static_cast<std::int64_t>(n),
                       [&](std::int64_t v) { near[static_cast<std::size_t>(v)] = seed[static_cast<std::size_t>(v)] ? 1 : 0; });
    const std::vector<std::int32_t> reached = grow(threads, piece, around, near, options.rings);

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
    const Rows held = samples_of(piece, threads);
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
        const auto corner = [&piece](std::size_t t, int k) {
            return static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)]);
        };
        const auto obstacle = [&](std::int64_t ti) {
            const auto t = static_cast<std::size_t>(ti);
            if (in_region[t]) return false;
            for (int c = 0; c < 3; ++c) {
                float low = std::numeric_limits<float>::max(), high = -low;
                for (int k = 0; k < 3; ++k) {
                    const auto v = corner(t, k);
                    const float q = c == 0 ? piece.x[v] : c == 1 ? piece.y[v] : piece.z[v];
                    low = std::min(low, q);
                    high = std::max(high, q);
                }
                if (low > hi[c] || high < lo[c]) return false;
            }
            return true;
        };
        std::vector<std::int32_t> near_box(piece.triangle_count());
        near_box.resize(static_cast<std::size_t>(
            parallel::filter(threads, static_cast<std::int64_t>(piece.triangle_count()), obstacle, near_box.data())));
        auto& obstacles = reduce_options.obstacles;
        const std::size_t before = obstacles.size();
        obstacles.resize(before + 9 * near_box.size());
        parallel::for_each(threads, static_cast<std::int64_t>(near_box.size()), [&](std::int64_t i) {
            float* to = obstacles.data() + before + 9 * static_cast<std::size_t>(i);
            for (int k = 0; k < 3; ++k) {
                const auto v = corner(static_cast<std::size_t>(near_box[static_cast<std::size_t>(i)]), k);
                *to++ = piece.x[v];
                *to++ = piece.y[v];
                *to++ = piece.z[v];
            }
        });
    }
    const Piece reduced = options.reducer ? options.reducer(sub, reduce_options, &reduce_report)
                                          : reduce(sub, reduce_options, &reduce_report);
    const double reduce_seconds = lap(clock);

    // Splice: vertices of the sub-piece that the reduction removed are dropped,
    // those it kept take their new positions; both lists are in key order.
    // The rest of the piece is copied in its order, each element to the place
    // a count of the kept elements before it gives (parallel::rank), so the
    // threads write the serial loop's arrays.
    std::vector<std::uint8_t> keep(n, 1);
    std::vector<std::int32_t> from_reduced(reduced.vertex_count(), -1);
    std::vector<std::int32_t> in_reduced(members.size(), -1); // by local index
    for (std::size_t i = 0, r = 0; i < members.size(); ++i) {
        const auto v = static_cast<std::size_t>(members[i]);
        if (r < reduced.vertex_count() && reduced.key[r] == piece.key[v]) {
            in_reduced[i] = static_cast<std::int32_t>(r);
            from_reduced[r++] = members[i];
        } else {
            keep[v] = 0;
        }
    }
    std::vector<std::int32_t> renumber(n);
    const std::int32_t kept_vertices = parallel::rank(
        threads, static_cast<std::int64_t>(n), [&](std::int64_t v) { return keep[static_cast<std::size_t>(v)] != 0; },
        renumber.data());
    Piece out;
    out.domains = piece.domains;
    out.x.resize(static_cast<std::size_t>(kept_vertices));
    out.y.resize(static_cast<std::size_t>(kept_vertices));
    out.z.resize(static_cast<std::size_t>(kept_vertices));
    out.key.resize(static_cast<std::size_t>(kept_vertices));
    out.flags.resize(static_cast<std::size_t>(kept_vertices));
    parallel::for_each(threads, static_cast<std::int64_t>(n), [&](std::int64_t vi) {
        const auto v = static_cast<std::size_t>(vi);
        if (renumber[v] < 0) return;
        const auto to = static_cast<std::size_t>(renumber[v]);
        const std::int32_t l = local[v];
        const Piece& from = l >= 0 ? reduced : piece;
        const std::size_t at = l >= 0 ? static_cast<std::size_t>(in_reduced[static_cast<std::size_t>(l)]) : v;
        out.x[to] = from.x[at];
        out.y[to] = from.y[at];
        out.z[to] = from.z[at];
        out.key[to] = piece.key[v];
        out.flags[to] = piece.flags[v];
    });

    const auto m = static_cast<std::int64_t>(piece.triangle_count());
    std::vector<std::int32_t> position(piece.triangle_count());
    const auto outside = static_cast<std::size_t>(parallel::rank(
        threads, m, [&](std::int64_t t) { return !in_region[static_cast<std::size_t>(t)]; }, position.data()));
    // held.list holds the samples by triangle, so the outside triangles'
    // samples come in it in the order they are written.
    const auto held_count = static_cast<std::int64_t>(held.list.size());
    std::vector<std::int32_t> sample_at(held.list.size());
    const auto outside_samples = static_cast<std::size_t>(parallel::rank(
        threads, held_count,
        [&](std::int64_t p) {
            const auto i = static_cast<std::size_t>(held.list[static_cast<std::size_t>(p)]);
            return !in_region[static_cast<std::size_t>(piece.sample_triangle[i])];
        },
        sample_at.data()));
    const std::size_t reduced_triangles = reduced.triangle_count();
    out.triangles.resize(3 * (outside + reduced_triangles));
    out.error.resize(outside + reduced.error.size());
    out.sampled.resize(outside + reduced_triangles);
    out.sample_xyz.resize(3 * (outside_samples + reduced.sample_count()));
    out.sample_triangle.resize(outside_samples + reduced.sample_count());
    parallel::for_each(threads, m, [&](std::int64_t ti) {
        const auto t = static_cast<std::size_t>(ti);
        if (position[t] < 0) return;
        const auto to = static_cast<std::size_t>(position[t]);
        for (std::size_t k = 0; k < 3; ++k)
            out.triangles[3 * to + k] = renumber[static_cast<std::size_t>(piece.triangles[3 * t + k])];
        out.error[to] = piece.triangle_error(t);
        out.sampled[to] = piece.triangle_sampled(t) ? 1 : 0;
    });
    parallel::for_each(threads, held_count, [&](std::int64_t p) {
        if (sample_at[static_cast<std::size_t>(p)] < 0) return;
        const auto to = static_cast<std::size_t>(sample_at[static_cast<std::size_t>(p)]);
        const auto i = static_cast<std::size_t>(held.list[static_cast<std::size_t>(p)]);
        for (std::size_t c = 0; c < 3; ++c) out.sample_xyz[3 * to + c] = piece.sample_xyz[3 * i + c];
        out.sample_triangle[to] = position[static_cast<std::size_t>(piece.sample_triangle[i])];
    });
    for (std::size_t c = 0; c < 3 * reduced_triangles; ++c)
        out.triangles[3 * outside + c] =
            renumber[static_cast<std::size_t>(from_reduced[static_cast<std::size_t>(reduced.triangles[c])])];
    std::copy(reduced.error.begin(), reduced.error.end(), out.error.begin() + static_cast<std::ptrdiff_t>(outside));
    for (std::size_t t = 0; t < reduced_triangles; ++t) out.sampled[outside + t] = reduced.triangle_sampled(t) ? 1 : 0;
    if (std::find(out.sampled.begin(), out.sampled.end(), 1) == out.sampled.end()) out.sampled = {};
    std::copy(reduced.sample_xyz.begin(), reduced.sample_xyz.end(),
              out.sample_xyz.begin() + static_cast<std::ptrdiff_t>(3 * outside_samples));
    for (std::size_t i = 0; i < reduced.sample_count(); ++i)
        out.sample_triangle[outside_samples + i] = static_cast<std::int32_t>(outside) + reduced.sample_triangle[i];
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
    const int threads = parallel::resolve_threads(options.reduce_options.threads);
    Piece merged = merge_by_key(a, b, threads);
    std::vector<std::uint8_t> seed(merged.flags);
    const std::size_t unlocked = unlock_settled(merged, domains_of_edge, threads);
    if (report) {
        *report = SeamReport{};
        report->vertices_unlocked = unlocked;
        report->seconds.merge = lap(clock);
    }
    if (!options.reduce || unlocked == 0) return merged;
    parallel::for_each(threads, static_cast<std::int64_t>(seed.size()), [&](std::int64_t vi) {
        const auto v = static_cast<std::size_t>(vi);
        seed[v] = (seed[v] & kLocked) && !(merged.flags[v] & kLocked) ? 1 : 0;
    });
    Piece out = reduce_near(merged, seed, options, report);
    keep_samples_near_locked(out, options.sample_rings, threads);
    return out;
}

} // namespace tetiso
