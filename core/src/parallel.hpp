// The OpenMP loops, scans, filters and counting sort that extraction and
// reduction run on the host. Each splits its range into contiguous blocks,
// sums integers only, and writes in block order, so its result is the serial
// loop's for any thread count: the surface never depends on threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hd.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace tetiso::parallel {

using i32 = std::int32_t;
using i64 = std::int64_t;

// threads <= 0: OpenMP's default (all cores), or 1 without OpenMP. Throws
// tetiso::Error above kMaxThreads.
inline int resolve_threads(int threads) {
    if (threads > kMaxThreads)
        throw Error(std::to_string(threads) + " threads: at most " + std::to_string(kMaxThreads) + " are allowed");
#ifdef _OPENMP
    if (threads <= 0) return omp_get_max_threads();
#endif
    return threads < 1 ? 1 : threads;
}

// Below this many elements a loop runs on the calling thread: a fork and join
// costs more than the work, and far more on an oversubscribed machine.
constexpr i64 kMinParallel = 16384;
// The same for loops of legality tests, which cost microseconds each and
// most in a reduction's late rounds, where the candidates are few: with the
// threshold above, a domain's late rounds ran on one thread whatever the
// count, and the selection and proposals of a domain-sized surface gained
// far less from many threads than they do with this one.
constexpr i64 kMinParallelTests = 64;
// For the reservations' window: a few thousand cheap elements per loop, in
// contiguous blocks (a static schedule) so that threads do not share the
// cache lines of a per-element byte array.
constexpr i64 kMinParallelWindow = 2048;

// How a loop's elements cost: the same (static blocks), or unevenly
// (legality tests: dynamic chunks), and from what size it forks.
enum class Grain { kCheap, kTests, kWindow };

constexpr i64 min_parallel(Grain grain) {
    return grain == Grain::kTests ? kMinParallelTests : (grain == Grain::kWindow ? kMinParallelWindow : kMinParallel);
}

// function(i) for i in [0, n); min_parallel: the size below which the loop
// stays on the calling thread.
template <class Function>
void for_each(int threads, i64 n, const Function& function, i64 min_parallel = kMinParallel) {
#ifdef _OPENMP
    if (threads > 1 && n > min_parallel) {
#pragma omp parallel for num_threads(threads) schedule(static)
        for (i64 i = 0; i < n; ++i) function(i);
        return;
    }
#endif
    (void)threads;
    for (i64 i = 0; i < n; ++i) function(i);
}

// for_each for loops of legality tests (or sample moves, which cost as
// much): few elements, uneven costs, so a low threshold and dynamic chunks.
template <class Function>
void for_each_test(int threads, i64 n, const Function& function) {
#ifdef _OPENMP
    if (threads > 1 && n > kMinParallelTests) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 16)
        for (i64 i = 0; i < n; ++i) function(i);
        return;
    }
#endif
    (void)threads;
    for (i64 i = 0; i < n; ++i) function(i);
}

template <class Function>
void for_each(int threads, i64 n, Grain grain, const Function& function) {
    if (grain == Grain::kTests) for_each_test(threads, n, function);
    else for_each(threads, n, function, min_parallel(grain));
}

// offsets[i] = sum of counts[0..i), offsets has n + 1 entries; throws when
// the sum does not fit an int32 index.
inline void exclusive_scan(const i32* counts, i64 n, i32* offsets) {
    i64 sum = 0;
    for (i64 i = 0; i < n; ++i) {
        offsets[i] = static_cast<i32>(sum);
        sum += counts[i];
    }
    if (sum > std::numeric_limits<i32>::max()) throw Error("tetiso: mesh too large for 32-bit indices");
    offsets[n] = static_cast<i32>(sum);
}

// A stable counting sort's offsets, from counts kept per block,
// counts[block * buckets + bucket]: each replaced by where that block's share
// of that bucket starts, the buckets one after another and, within one, the
// blocks in order. Returns the total.
template <class T>
T offsets_by_bucket_then_block(T* counts, std::size_t buckets, std::size_t blocks) {
    T sum = 0;
    for (std::size_t bucket = 0; bucket < buckets; ++bucket)
        for (std::size_t b = 0; b < blocks; ++b) {
            const T here = counts[b * buckets + bucket];
            counts[b * buckets + bucket] = sum;
            sum += here;
        }
    return sum;
}

// The scans and filters below split [0, n) into one contiguous block per
// thread: each block counts its share, the counts are summed in block order,
// and each block writes its part from there.
struct Blocks {
    i64 n, count;
    Blocks(int threads, i64 size) : n(size), count(threads > 1 && size > kMinParallel ? threads : 1) {}
    i64 begin(i64 b) const { return n * b / count; }
    bool parallel() const { return count > 1; }
};

// first[b] = the number of kept elements in the blocks before block b, for
// b = 0 .. blocks.count (the last: all of them). keep runs once per element.
template <class Keep>
std::vector<i64> block_starts(int threads, const Blocks& blocks, const Keep& keep) {
    std::vector<i64> first(static_cast<std::size_t>(blocks.count) + 1, 0);
    for_each(blocks.parallel() ? threads : 1, blocks.count, [&](i64 b) {
        i64 c = 0;
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i) c += keep(i) ? 1 : 0;
        first[static_cast<std::size_t>(b) + 1] = c;
    }, 0);
    for (std::size_t b = 0; b < static_cast<std::size_t>(blocks.count); ++b) first[b + 1] += first[b];
    return first;
}

// out = every i < n with keep(i), ascending; returns their number. keep runs
// twice per element on several threads (count, then write), so it must be
// cheap and pure. `out` must hold n elements.
template <class Keep>
i32 filter(int threads, i64 n, const Keep& keep, i32* out) {
    const Blocks blocks(threads, n);
    if (!blocks.parallel()) {
        i32 kept = 0;
        for (i64 i = 0; i < n; ++i)
            if (keep(i)) out[kept++] = static_cast<i32>(i);
        return kept;
    }
    const std::vector<i64> first = block_starts(threads, blocks, keep);
    for_each(threads, blocks.count, [&](i64 b) {
        i64 at = first[static_cast<std::size_t>(b)];
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i)
            if (keep(i)) out[at++] = static_cast<i32>(i);
    }, 0);
    return static_cast<i32>(first.back());
}

// rank[i] = the number of kept elements before i, for each kept i; -1 for
// the others. Returns the number kept.
template <class Keep>
i32 rank(int threads, i64 n, const Keep& keep, i32* rank) {
    const Blocks blocks(threads, n);
    if (!blocks.parallel()) {
        i32 next = 0;
        for (i64 i = 0; i < n; ++i) rank[i] = keep(i) ? next++ : -1;
        return next;
    }
    const std::vector<i64> first = block_starts(threads, blocks, keep);
    for_each(threads, blocks.count, [&](i64 b) {
        i64 next = first[static_cast<std::size_t>(b)];
        for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i) rank[i] = keep(i) ? static_cast<i32>(next++) : -1;
    }, 0);
    return static_cast<i32>(first.back());
}

// The number of i < n with counted(i) (an integer sum).
template <class Counted>
i64 count(int threads, i64 n, const Counted& counted) {
    return block_starts(threads, Blocks(threads, n), counted).back();
}

// Sorts a short run in place (a vertex's corners, a face's samples): an
// insertion sort, which costs nothing on a run already in order and beats
// std::sort's call on the few elements these runs hold.
inline void sort_short_run(i32* first, i32* last) {
    for (i32* i = first + (first != last); i < last; ++i) {
        const i32 value = *i;
        i32* j = i;
        for (; j > first && *(j - 1) > value; --j) *j = *(j - 1);
        *j = value;
    }
}

// A stable counting sort of the indices 0 .. n-1 by key(i) in 0 .. groups-1:
// group g is order[first[g]] .. order[first[g + 1]], its indices ascending.
// On several threads the counters are atomic, which leaves each group in any
// order, so each is sorted back afterwards: the result is one thread's for
// any count. first: groups + 1 entries; order: n; count: groups, scratch.
template <class Key>
void group_by_key(int threads, i64 n, i64 groups, const Key& key, i32* first, i32* order, i32* count) {
    const bool atomic = threads > 1 && n > kMinParallel;
    for_each(threads, groups, [&](i64 g) { count[g] = 0; });
    if (atomic) for_each(threads, n, [&](i64 i) { hd::atomic_add(count + key(i), 1); });
    else
        for (i64 i = 0; i < n; ++i) ++count[key(i)];
    exclusive_scan(count, groups, first);
    for_each(threads, groups, [&](i64 g) { count[g] = first[g]; });
    if (!atomic) {
        for (i64 i = 0; i < n; ++i) order[count[key(i)]++] = static_cast<i32>(i);
        return;
    }
    for_each(threads, n, [&](i64 i) { order[hd::atomic_add(count + key(i), 1)] = static_cast<i32>(i); });
    for_each(threads, groups, [&](i64 g) { sort_short_run(order + first[g], order + first[g + 1]); });
}

} // namespace tetiso::parallel
