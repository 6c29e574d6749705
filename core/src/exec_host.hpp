// The host backend of the data-parallel drivers (reduction's rounds): arrays
// in host memory and OpenMP primitives (parallel.hpp). The CUDA backend
// (exec_cuda.cuh) offers the same members over device memory; a driver
// written against them runs on either, calling the same per-element
// functions, so the two give the same bytes wherever the primitives do (every
// primitive here has one result for any thread count or device: integer
// sums, stable orders).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "parallel.hpp"
#include "tile.hpp"

namespace tetiso {

// std::allocator that leaves trivially constructible elements uninitialised
// on resize: the drivers size an array and then write every element, so the
// zero fill would be a second pass over it.
template <class T>
struct NoInitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = NoInitAllocator<U>;
    };
    NoInitAllocator() = default;
    template <class U>
    NoInitAllocator(const NoInitAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* at) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(at)) U;
    }
    template <class U, class... Args>
    void construct(U* at, Args&&... args) {
        ::new (static_cast<void*>(at)) U(std::forward<Args>(args)...);
    }
};

struct HostExec {
    using i32 = std::int32_t;
    using i64 = std::int64_t;
    using Grain = parallel::Grain;
    static constexpr bool kHost = true;

    template <class T>
    using Array = std::vector<T, NoInitAllocator<T>>;

    int threads = 1;

    template <class Function>
    void for_each(i64 n, const Function& function, Grain grain = Grain::kCheap) const {
        parallel::for_each(threads, n, grain, function);
    }

    // function(i) for i < max(*n, min_n): a size the backend keeps where its
    // loops run (here, host memory), at most max(max_n, min_n).
    template <class Function>
    void for_each_of(const i64* n, i64 /*max_n*/, const Function& function, Grain grain = Grain::kCheap,
                     i64 min_n = 0) const {
        parallel::for_each(threads, std::max(*n, min_n), grain, function);
    }

    // The tile that runs one task of for_each_of_tiled (tile.hpp).
    using Tile = SequentialTile;

    // function(i, tile, scratch) for i < *n (at most max_n), each i a task
    // of a tile of threads sharing `scratch`: here each a thread's, its
    // scratch on its stack.
    template <class Scratch, class Function>
    void for_each_of_tiled(const i64* n, i64 /*max_n*/, const Function& function) const {
        parallel::for_each(threads, *n, Grain::kTests, [&](i64 i) {
            Scratch scratch;
            function(i, Tile{}, scratch);
        });
    }

    // Steps of a device-side loop run between two reads of its state by the
    // host: here every step, as reading costs nothing.
    static int steps_between_checks() { return 1; }

    // out = every i < n with keep(i), ascending; returns their number.
    template <class Keep>
    i32 filter(i64 n, const Keep& keep, Array<i32>& out) const {
        out.resize(static_cast<std::size_t>(n));
        const i32 kept = parallel::filter(threads, n, keep, out.data());
        out.resize(static_cast<std::size_t>(kept));
        return kept;
    }

    // The elements of `in` (n of them) at which keep(i) holds, in order.
    template <class T, class Keep>
    i32 copy_if(const Array<T>& in, i64 n, const Keep& keep, Array<T>& out) const {
        out.resize(static_cast<std::size_t>(n));
        i32 kept = 0;
        if (!parallel::Blocks(threads, n).parallel()) {
            for (i64 i = 0; i < n; ++i)
                if (keep(i)) out[static_cast<std::size_t>(kept++)] = in[static_cast<std::size_t>(i)];
        } else {
            Array<i32> at(static_cast<std::size_t>(n));
            kept = parallel::rank(threads, n, keep, at.data());
            parallel::for_each(threads, n, [&](i64 i) {
                const i32 r = at[static_cast<std::size_t>(i)];
                if (r >= 0) out[static_cast<std::size_t>(r)] = in[static_cast<std::size_t>(i)];
            });
        }
        out.resize(static_cast<std::size_t>(kept));
        return kept;
    }

    // rank[i] = the number of kept elements before i, for each kept i, -1
    // for the others; returns the number kept.
    template <class Keep>
    i32 rank(i64 n, const Keep& keep, Array<i32>& rank) const {
        rank.resize(static_cast<std::size_t>(n));
        return parallel::rank(threads, n, keep, rank.data());
    }

    template <class Counted>
    i64 count(i64 n, const Counted& counted) const {
        return parallel::count(threads, n, counted);
    }

    // offsets[i] = counts[0] + ... + counts[i-1] for i <= n; returns the sum.
    i32 exclusive_scan(const Array<i32>& counts, i64 n, Array<i32>& offsets) const {
        offsets.resize(static_cast<std::size_t>(n) + 1);
        parallel::exclusive_scan(counts.data(), n, offsets.data());
        return offsets[static_cast<std::size_t>(n)];
    }

    // Counts a driver needs only later (CudaExec keeps them on the device):
    // count_into and filter_into leave theirs in a slot of the tally, which
    // tally_at points to and read_tally returns whole.
    static constexpr int kTallySlots = 16;
    // rank() and exclusive_scan() with the number kept or the sum in a slot
    // of the tally (rank.size() is then n, as on the device).
    template <class Keep>
    void rank_into(i64 n, const Keep& keep, Array<i32>& rank, int slot) {
        tally_[static_cast<std::size_t>(slot)] = this->rank(n, keep, rank);
    }
    void offsets_into(const Array<i32>& counts, i64 n, Array<i32>& offsets, int slot) {
        tally_[static_cast<std::size_t>(slot)] = exclusive_scan(counts, n, offsets);
    }
    template <class Counted>
    void count_into(i64 n, const Counted& counted, int slot) {
        tally_[static_cast<std::size_t>(slot)] = count(n, counted);
    }
    template <class Keep>
    void filter_into(i64 n, const Keep& keep, Array<i32>& out, int slot) {
        tally_[static_cast<std::size_t>(slot)] = filter(n, keep, out);
    }
    const i64* tally_at(int slot) const { return tally_.data() + slot; }
    std::array<i64, kTallySlots> read_tally() const { return tally_; }

    // Stage times: mark() notes the time, seconds_between(a, b) the time
    // from mark a to mark b; clear_marks() forgets them.
    int mark() {
        marks_.push_back(std::chrono::steady_clock::now());
        return static_cast<int>(marks_.size()) - 1;
    }
    double seconds_between(int a, int b) const {
        return std::chrono::duration<double>(marks_[static_cast<std::size_t>(b)] - marks_[static_cast<std::size_t>(a)])
            .count();
    }
    void clear_marks() { marks_.clear(); }

    // A stable grouping of 0 .. n-1 by key(i) < groups (parallel.hpp).
    template <class Key>
    void group_by_key(i64 n, i64 groups, const Key& key, Array<i32>& first, Array<i32>& order,
                      Array<i32>& scratch) const {
        first.resize(static_cast<std::size_t>(groups) + 1);
        order.resize(static_cast<std::size_t>(n));
        scratch.resize(static_cast<std::size_t>(groups));
        parallel::group_by_key(threads, n, groups, key, first.data(), order.data(), scratch.data());
    }

    // order = ops (n edge ids) by descending priority, ties by descending
    // first end, then by descending second end (vertex indices, which follow
    // the keys). A stable LSD radix sort of the complemented priorities,
    // skipping the digits all share, then each run of equal priorities in
    // that order. On one thread, digits of 16 bits for large rounds (two
    // passes) and of 8 for small ones, where clearing and scanning
    // 65,536-entry counters cost more than the sort (late rounds have tens of
    // operations). On
    // several, each thread counts and scatters its own block of the keys,
    // with 11-bit digits so that the per-block counters stay small and their
    // scan cheap; every stable sort by the same key gives the same order.
    void order_by_priority(const Array<i32>& ops, i64 n, const std::uint32_t* priority, const i32* v0, const i32* v1,
                           Array<i32>& order) {
        if (n < (i64{1} << 14)) radix_order<8>(ops, n, priority, order, 1);
        else if (threads > 1 && n >= kParallelSortMin) radix_order<11>(ops, n, priority, order, threads);
        else radix_order<16>(ops, n, priority, order, 1);
        const auto before = [&](i32 a, i32 b) {
            const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
            return v0[ia] != v0[ib] ? v0[ia] > v0[ib] : v1[ia] > v1[ib];
        };
        const std::size_t size = static_cast<std::size_t>(n);
        for (std::size_t i = 0; i + 1 < size;) {
            std::size_t j = i + 1;
            while (j < size && sort_key_[j] == sort_key_[i]) ++j;
            if (j - i > 1)
                std::sort(order.begin() + static_cast<std::ptrdiff_t>(i), order.begin() + static_cast<std::ptrdiff_t>(j),
                          before);
            i = j;
        }
    }

    // The reservations' window (reduce/selection.hpp): at least 512
    // operations, or 1/32 of the round's, so that a round takes some tens of
    // steps, each three parallel loops.
    static i64 reservation_window(i64 n) { return std::max<i64>(512, n / 32); }

    template <class T>
    void assign(Array<T>& a, i64 n, T value) const {
        a.resize(static_cast<std::size_t>(n));
        T* data = a.data();
        for_each(n, [=](i64 i) { data[i] = value; });
    }

    template <class T>
    T get(const Array<T>& a, i64 i) const {
        return a[static_cast<std::size_t>(i)];
    }
    template <class T>
    void set(Array<T>& a, i64 i, T value) const {
        a[static_cast<std::size_t>(i)] = value;
    }

    template <class T, class Allocator>
    void upload(const std::vector<T, Allocator>& host, Array<T>& a) const {
        a.assign(host.begin(), host.end());
    }
    template <class T, class Allocator>
    void download(const Array<T>& a, i64 n, std::vector<T, Allocator>& host) const {
        host.assign(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(n));
    }

    void sync() const {}

    // The primitives marching tetrahedra adds (marching_tets.hpp).

    // offsets[i] = count(0) + ... + count(i-1) for i <= n, a total below
    // 2^32; returns the total. count runs twice per element on several
    // threads (sum, then write), so it must be cheap and pure.
    template <class Count>
    std::uint64_t exclusive_sum(i64 n, const Count& count, Array<std::uint32_t>& offsets) const {
        offsets.resize(static_cast<std::size_t>(n) + 1);
        const parallel::Blocks blocks(threads, n);
        std::vector<std::uint64_t> start(static_cast<std::size_t>(blocks.count) + 1, 0);
        const int block_threads = blocks.parallel() ? threads : 1;
        parallel::for_each(block_threads, blocks.count, [&](i64 b) {
            std::uint64_t sum = 0;
            for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i) sum += count(i);
            start[static_cast<std::size_t>(b) + 1] = sum;
        }, 0);
        for (std::size_t b = 0; b < static_cast<std::size_t>(blocks.count); ++b) start[b + 1] += start[b];
        std::uint32_t* out = offsets.data();
        parallel::for_each(block_threads, blocks.count, [&](i64 b) {
            std::uint64_t sum = start[static_cast<std::size_t>(b)];
            for (i64 i = blocks.begin(b); i < blocks.begin(b + 1); ++i) {
                out[i] = static_cast<std::uint32_t>(sum);
                sum += count(i);
            }
        }, 0);
        const std::uint64_t total = start.back();
        out[n] = static_cast<std::uint32_t>(total);
        return total;
    }

    // out = the distinct values of keys[0, n), ascending; every key is below
    // 2^bits. keys is left in an unspecified order. Returns their number.
    i64 sort_unique(Array<std::uint64_t>& keys, i64 n, int bits, Array<std::uint64_t>& out) {
        out.resize(static_cast<std::size_t>(n));
        if (n == 0) return 0;
        radix_sort_keys(keys, n, bits, out);
        std::uint64_t* k = keys.data();
        std::uint64_t* o = out.data();
        i64 kept = 0;
        for (i64 i = 0; i < n; ++i)
            if (i == 0 || k[i] != k[i - 1]) o[kept++] = k[i];
        out.resize(static_cast<std::size_t>(kept));
        return kept;
    }

    // order = 0 .. n-1 by ascending keys[i], stably.
    void order_by_key(const Array<std::uint64_t>& keys, i64 n, Array<i32>& order) const {
        order.resize(static_cast<std::size_t>(n));
        for (i64 i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = static_cast<i32>(i);
        std::stable_sort(order.begin(), order.end(), [&](i32 a, i32 b) {
            return keys[static_cast<std::size_t>(a)] < keys[static_cast<std::size_t>(b)];
        });
    }

private:
    // keys[0, n) sorted by their low `bits` bits (the rest 0), by an LSD
    // radix sort whose blocks count and scatter on their own threads;
    // spare: a buffer of n.
    void radix_sort_keys(Array<std::uint64_t>& keys, i64 count, int bits, Array<std::uint64_t>& spare) const {
        constexpr int kDigitBits = 11;
        constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
        const auto n = static_cast<std::size_t>(count);
        spare.resize(n);
        const parallel::Blocks split(threads, count);
        const auto blocks = static_cast<std::size_t>(split.count);
        const int block_threads = split.parallel() ? threads : 1;
        std::vector<std::uint32_t> histogram(blocks * kBuckets);
        for (int shift = 0; shift < bits; shift += kDigitBits) {
            const std::uint64_t* from = keys.data();
            std::uint64_t* to = spare.data();
            const auto digit = [&](std::uint64_t k) { return static_cast<std::size_t>((k >> shift) & (kBuckets - 1)); };
            parallel::for_each(block_threads, split.count, [&](i64 b) {
                std::uint32_t* c = histogram.data() + static_cast<std::size_t>(b) * kBuckets;
                std::fill(c, c + kBuckets, 0u);
                for (i64 i = split.begin(b); i < split.begin(b + 1); ++i) ++c[digit(from[i])];
            }, 0);
            std::size_t shared = 0;
            for (std::size_t b = 0; b < blocks; ++b) shared += histogram[b * kBuckets + digit(from[0])];
            if (shared == n) continue;
            parallel::offsets_by_bucket_then_block(histogram.data(), kBuckets, blocks);
            parallel::for_each(block_threads, split.count, [&](i64 b) {
                std::uint32_t* c = histogram.data() + static_cast<std::size_t>(b) * kBuckets;
                for (i64 i = split.begin(b); i < split.begin(b + 1); ++i) to[c[digit(from[i])]++] = from[i];
            }, 0);
            keys.swap(spare);
        }
    }

    // From this many operations a sort by priority runs on several threads
    // (below it, one thread sorts in a millisecond or less).
    static constexpr i64 kParallelSortMin = i64{1} << 16;

    // blocks: the number of blocks, each counted and scattered by one
    // iteration of a parallel loop; 1 sorts on the calling thread.
    template <int kDigitBits>
    void radix_order(const Array<i32>& ops, i64 count, const std::uint32_t* priority, Array<i32>& order, int blocks_in) {
        using u32 = std::uint32_t;
        const std::size_t n = static_cast<std::size_t>(count);
        Array<u32>& key = sort_key_;
        key.resize(n);
        sort_key_spare_.resize(n);
        order.resize(n);
        order_spare_.resize(n);
        if (n == 0) return;
        parallel::for_each(blocks_in, count, [&](i64 i) {
            const auto k = static_cast<std::size_t>(i);
            order[k] = ops[k];
            key[k] = ~priority[static_cast<std::size_t>(ops[k])];
        });
        const auto blocks = static_cast<std::size_t>(blocks_in);
        const auto block_begin = [&](std::size_t b) { return n * b / blocks; };
        constexpr int kDigits = (32 + kDigitBits - 1) / kDigitBits;
        constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
        histogram_.resize(blocks * kBuckets);
        u32* histogram = histogram_.data();
        for (int d = 0; d < kDigits; ++d) {
            const int shift = d * kDigitBits;
            const auto digit = [&](u32 k) { return (k >> shift) & (kBuckets - 1); };
            parallel::for_each(blocks_in, static_cast<i64>(blocks), [&](i64 b) {
                u32* c = histogram + static_cast<std::size_t>(b) * kBuckets;
                std::fill(c, c + kBuckets, 0u);
                for (std::size_t i = block_begin(static_cast<std::size_t>(b)); i < block_begin(static_cast<std::size_t>(b) + 1); ++i)
                    ++c[digit(key[i])];
            }, 0);
            std::size_t shared = 0;
            for (std::size_t b = 0; b < blocks; ++b) shared += histogram[b * kBuckets + digit(key[0])];
            if (shared == n) continue;
            // The scatter keeps the keys' order among equal digits (stable).
            parallel::offsets_by_bucket_then_block(histogram, kBuckets, blocks);
            parallel::for_each(blocks_in, static_cast<i64>(blocks), [&](i64 b) {
                u32* c = histogram + static_cast<std::size_t>(b) * kBuckets;
                for (std::size_t i = block_begin(static_cast<std::size_t>(b)); i < block_begin(static_cast<std::size_t>(b) + 1); ++i) {
                    const u32 at = c[digit(key[i])]++;
                    sort_key_spare_[at] = key[i];
                    order_spare_[at] = order[i];
                }
            }, 0);
            key.swap(sort_key_spare_);
            order.swap(order_spare_);
        }
    }

    std::array<i64, kTallySlots> tally_{};
    std::vector<std::chrono::steady_clock::time_point> marks_;
    Array<std::uint32_t> sort_key_, sort_key_spare_, histogram_;
    Array<i32> order_spare_;
};

} // namespace tetiso
