// The execution backends held to one interface: every member that HostExec
// (exec_host.hpp) and CudaExec (exec_cuda.cuh) both offer, on random inputs
// of fixed seeds and on the edge cases (nothing, one element, all kept, none
// kept, tied sort keys), each result against a plain sequential loop written
// here. The drivers are written once against these members, so a backend
// that answers differently from this reference gives a different surface.
//
// One source, two programs: test_exec runs HostExec on one thread and on
// several (whose blocked and atomic paths start above parallel.hpp's
// thresholds, hence the large sizes); test_exec_gpu compiles it as CUDA
// (test_exec_gpu.cu) and runs CudaExec, skipping where there is no GPU. The
// functions a backend runs per element are TETISO_HD lambdas capturing
// pointers by value, as the drivers' are, and live in free function
// templates (nvcc takes no extended lambda in a private member such as a
// test's body).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "hd.hpp"
#include "tile.hpp"

#ifdef TETISO_TEST_GPU
#include "exec_cuda.cuh"
#else
#include "exec_host.hpp"
#endif

namespace tetiso::test_exec {

using i32 = std::int32_t;
using i64 = std::int64_t;
using u32 = std::uint32_t;
using u64 = std::uint64_t;
using Grain = parallel::Grain;

// 0 and 1, a size below every threshold, and sizes above parallel.hpp's
// kMinParallel (blocked loops, atomic grouping) and HostExec's parallel sort
// (1 << 16).
const std::vector<i64> kSizes = {0, 1, 2, 37, 1000, 20000, 70000};
// Of every hundred elements, how many a predicate keeps: none, some, all.
const std::vector<u32> kKeptPercent = {0, 30, 100};

template <class Exec, class T>
using ArrayOf = typename Exec::template Array<T>;

std::vector<u32> random_values(i64 n, u32 below, u64 seed) {
    std::mt19937_64 random(seed);
    std::uniform_int_distribution<u32> draw(0, below - 1);
    std::vector<u32> values(static_cast<std::size_t>(n));
    for (u32& v : values) v = draw(random);
    return values;
}

// The first n elements of a backend's array, on the host.
template <class Exec, class Array>
auto downloaded(Exec& exec, const Array& array, i64 n) {
    std::vector<std::remove_cv_t<std::remove_pointer_t<decltype(array.data())>>> host;
    exec.download(array, n, host);
    return host;
}

// --- upload, download, assign, get, set

template <class Exec>
void check_transfers(Exec& exec, i64 n, u64 seed) {
    const std::vector<u32> host = random_values(n, 1u << 31, seed);
    ArrayOf<Exec, u32> array;
    exec.upload(host, array);
    EXPECT_EQ(array.size(), host.size());
    EXPECT_EQ(downloaded(exec, array, n), host);
    const i64 part = n / 2;
    EXPECT_EQ(downloaded(exec, array, part), std::vector<u32>(host.begin(), host.begin() + part));

    ArrayOf<Exec, i64> filled;
    exec.assign(filled, n, i64{-5});
    std::vector<i64> expected(static_cast<std::size_t>(n), -5);
    if (n > 0) {
        exec.set(filled, n - 1, i64{42});
        exec.set(filled, 0, i64{7});
        expected[static_cast<std::size_t>(n - 1)] = 42;
        expected[0] = 7;
        EXPECT_EQ(exec.get(filled, 0), 7);
        EXPECT_EQ(exec.get(filled, n - 1), expected.back());
        EXPECT_EQ(exec.get(array, n - 1), host.back());
    }
    EXPECT_EQ(downloaded(exec, filled, n), expected);
}

// --- for_each, for_each_of

template <class Exec>
void check_for_each(Exec& exec, i64 n, Grain grain) {
    ArrayOf<Exec, i64> out;
    exec.assign(out, n, i64{-1});
    i64* o = out.data();
    exec.for_each(n, [=] TETISO_HD(i64 i) { o[i] = 3 * i + 1; }, grain);
    std::vector<i64> expected(static_cast<std::size_t>(n));
    for (i64 i = 0; i < n; ++i) expected[static_cast<std::size_t>(i)] = 3 * i + 1;
    EXPECT_EQ(downloaded(exec, out, n), expected);
}

// for_each_of over max(size, min_n) elements, size in the backend's memory.
template <class Exec>
void check_for_each_of(Exec& exec, i64 n, i64 size, i64 min_n, Grain grain) {
    SCOPED_TRACE("size " + std::to_string(size) + ", min_n " + std::to_string(min_n));
    ArrayOf<Exec, i64> count;
    exec.upload(std::vector<i64>{size}, count);
    ArrayOf<Exec, i64> out;
    exec.assign(out, n, i64{-1});
    i64* o = out.data();
    exec.for_each_of(count.data(), n, [=] TETISO_HD(i64 i) { o[i] = i + 7; }, grain, min_n);
    std::vector<i64> expected(static_cast<std::size_t>(n), -1);
    for (i64 i = 0; i < std::max(size, min_n); ++i) expected[static_cast<std::size_t>(i)] = i + 7;
    EXPECT_EQ(downloaded(exec, out, n), expected);
}

// --- filter, copy_if, rank, count and their tally forms

template <class Exec>
void check_selection(Exec& exec, i64 n, u32 percent, u64 seed) {
    SCOPED_TRACE("keeping " + std::to_string(percent) + " %");
    const std::vector<u32> host = random_values(n, 100, seed);
    ArrayOf<Exec, u32> values;
    exec.upload(host, values);
    const u32* v = values.data();
    const auto keep = [=] TETISO_HD(i64 i) { return v[i] < percent; };

    std::vector<i32> kept_indices, ranks(static_cast<std::size_t>(n), -1);
    std::vector<u32> kept_values;
    for (i64 i = 0; i < n; ++i)
        if (host[static_cast<std::size_t>(i)] < percent) {
            ranks[static_cast<std::size_t>(i)] = static_cast<i32>(kept_indices.size());
            kept_indices.push_back(static_cast<i32>(i));
            kept_values.push_back(host[static_cast<std::size_t>(i)]);
        }
    const auto kept = static_cast<i32>(kept_indices.size());

    ArrayOf<Exec, i32> out;
    EXPECT_EQ(exec.filter(n, keep, out), kept);
    EXPECT_EQ(out.size(), kept_indices.size());
    EXPECT_EQ(downloaded(exec, out, kept), kept_indices);

    ArrayOf<Exec, u32> copied;
    EXPECT_EQ(exec.copy_if(values, n, keep, copied), kept);
    EXPECT_EQ(copied.size(), kept_values.size());
    EXPECT_EQ(downloaded(exec, copied, kept), kept_values);

    ArrayOf<Exec, i32> rank;
    EXPECT_EQ(exec.rank(n, keep, rank), kept);
    EXPECT_EQ(rank.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(downloaded(exec, rank, n), ranks);

    EXPECT_EQ(exec.count(n, keep), kept);

    // The tally's slots are independent: two counts, a filter and a rank,
    // read at once.
    const auto drop = [=] TETISO_HD(i64 i) { return !(v[i] < percent); };
    ArrayOf<Exec, i32> into;
    exec.count_into(n, keep, 0);
    exec.count_into(n, drop, Exec::kTallySlots - 1);
    exec.filter_into(n, keep, into, 3);
    ArrayOf<Exec, i32> rank_kept_later;
    exec.rank_into(n, drop, rank_kept_later, 4);
    const auto tally = exec.read_tally();
    EXPECT_EQ(tally[0], kept);
    EXPECT_EQ(tally[Exec::kTallySlots - 1], n - kept);
    EXPECT_EQ(tally[3], kept);
    EXPECT_EQ(tally[4], n - kept);
    EXPECT_EQ(downloaded(exec, into, kept), kept_indices);
    std::vector<i32> drop_ranks(static_cast<std::size_t>(n), -1);
    for (i64 i = 0, r = 0; i < n; ++i)
        if (ranks[static_cast<std::size_t>(i)] < 0) drop_ranks[static_cast<std::size_t>(i)] = static_cast<i32>(r++);
    EXPECT_EQ(rank_kept_later.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(downloaded(exec, rank_kept_later, n), drop_ranks);

    // A loop sized by a tally slot, without the host reading it.
    ArrayOf<Exec, i64> marked;
    exec.assign(marked, n, i64{0});
    i64* m = marked.data();
    const i32* selected = into.data();
    exec.for_each_of(exec.tally_at(3), n, [=] TETISO_HD(i64 k) { m[selected[k]] = k + 1; });
    std::vector<i64> expected(static_cast<std::size_t>(n), 0);
    for (std::size_t k = 0; k < kept_indices.size(); ++k)
        expected[static_cast<std::size_t>(kept_indices[k])] = static_cast<i64>(k) + 1;
    EXPECT_EQ(downloaded(exec, marked, n), expected);
}

// --- exclusive_scan, exclusive_sum

template <class Exec>
void check_sums(Exec& exec, i64 n, u64 seed) {
    const std::vector<u32> host = random_values(n, 10, seed);
    std::vector<i32> counts(host.begin(), host.end());
    std::vector<i32> offsets(static_cast<std::size_t>(n) + 1, 0);
    std::vector<u32> wide_offsets(static_cast<std::size_t>(n) + 1, 0);
    for (std::size_t i = 0; i < host.size(); ++i) {
        offsets[i + 1] = offsets[i] + counts[i];
        wide_offsets[i + 1] = wide_offsets[i] + host[i];
    }

    ArrayOf<Exec, i32> device_counts, device_offsets;
    exec.upload(counts, device_counts);
    EXPECT_EQ(exec.exclusive_scan(device_counts, n, device_offsets), offsets.back());
    EXPECT_EQ(downloaded(exec, device_offsets, n + 1), offsets);
    ArrayOf<Exec, i32> offsets_left;
    exec.offsets_into(device_counts, n, offsets_left, 2);
    EXPECT_EQ(exec.read_tally()[2], offsets.back());
    EXPECT_EQ(downloaded(exec, offsets_left, n + 1), offsets);

    ArrayOf<Exec, u32> values, sums;
    exec.upload(host, values);
    const u32* v = values.data();
    const u64 total = exec.exclusive_sum(n, [=] TETISO_HD(i64 i) { return v[i]; }, sums);
    EXPECT_EQ(total, u64{wide_offsets.back()});
    EXPECT_EQ(downloaded(exec, sums, n + 1), wide_offsets);
}

// --- group_by_key

template <class Exec>
void check_group_by_key(Exec& exec, i64 n, i64 groups, u64 seed) {
    SCOPED_TRACE(std::to_string(groups) + " groups");
    const std::vector<u32> keys = random_values(n, static_cast<u32>(groups), seed);
    // A stable counting sort, by the book.
    std::vector<i32> first(static_cast<std::size_t>(groups) + 1, 0);
    for (const u32 k : keys) ++first[k + 1];
    for (std::size_t g = 0; g < static_cast<std::size_t>(groups); ++g) first[g + 1] += first[g];
    std::vector<i32> next(first.begin(), first.end() - 1), order(static_cast<std::size_t>(n));
    for (i64 i = 0; i < n; ++i) order[static_cast<std::size_t>(next[keys[static_cast<std::size_t>(i)]]++)] = static_cast<i32>(i);

    ArrayOf<Exec, u32> device_keys;
    exec.upload(keys, device_keys);
    const u32* k = device_keys.data();
    ArrayOf<Exec, i32> device_first, device_order, scratch;
    exec.group_by_key(n, groups, [=] TETISO_HD(i64 i) { return static_cast<i32>(k[i]); }, device_first, device_order,
                      scratch);
    EXPECT_EQ(downloaded(exec, device_first, groups + 1), first);
    EXPECT_EQ(downloaded(exec, device_order, n), order);
}

// --- order_by_priority: n of `edges` edge ids, in a random order, sorted by
// descending priority, then descending first end, then descending second
// end. Each edge joins its own pair of vertices, as in a mesh (a repeated
// pair would tie on all three keys, an order the drivers never ask for).

template <class Exec>
void check_order_by_priority(Exec& exec, i64 n, u32 priorities, u64 seed) {
    SCOPED_TRACE(std::to_string(priorities) + " priorities");
    std::mt19937_64 random(seed);
    const i64 edges = n + n / 3 + 1;
    // Few vertices, so that first ends tie often among equal priorities.
    const auto vertices = static_cast<u32>(2 + 2 * static_cast<i64>(std::sqrt(static_cast<double>(edges))));
    std::uniform_int_distribution<u32> vertex(0, vertices - 1);
    std::set<std::pair<i32, i32>> pairs;
    std::vector<i32> v0, v1;
    while (static_cast<i64>(v0.size()) < edges) {
        const auto a = static_cast<i32>(vertex(random)), b = static_cast<i32>(vertex(random));
        if (a == b || !pairs.insert({a, b}).second) continue;
        v0.push_back(a);
        v1.push_back(b);
    }
    const std::vector<u32> priority = random_values(edges, priorities, seed + 1);
    std::vector<i32> ops(static_cast<std::size_t>(edges));
    std::iota(ops.begin(), ops.end(), 0);
    std::shuffle(ops.begin(), ops.end(), random);
    ops.resize(static_cast<std::size_t>(n));

    std::vector<i32> expected = ops;
    std::sort(expected.begin(), expected.end(), [&](i32 a, i32 b) {
        const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
        if (priority[ia] != priority[ib]) return priority[ia] > priority[ib];
        if (v0[ia] != v0[ib]) return v0[ia] > v0[ib];
        return v1[ia] > v1[ib];
    });

    ArrayOf<Exec, i32> device_ops, device_v0, device_v1, order;
    ArrayOf<Exec, u32> device_priority;
    exec.upload(ops, device_ops);
    exec.upload(v0, device_v0);
    exec.upload(v1, device_v1);
    exec.upload(priority, device_priority);
    exec.order_by_priority(device_ops, n, device_priority.data(), device_v0.data(), device_v1.data(), order);
    EXPECT_EQ(order.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(downloaded(exec, order, n), expected);
}

// --- sort_unique, order_by_key

template <class Exec>
void check_sort_unique(Exec& exec, i64 n, int bits, u64 seed) {
    SCOPED_TRACE(std::to_string(bits) + " bits");
    std::mt19937_64 random(seed);
    const u64 mask = bits == 64 ? ~u64{0} : (u64{1} << bits) - 1;
    // Half the keys repeat an earlier one.
    std::vector<u64> keys;
    for (i64 i = 0; i < n; ++i)
        keys.push_back(i > 0 && random() % 2 ? keys[random() % keys.size()] : random() & mask);
    std::vector<u64> expected = keys;
    std::sort(expected.begin(), expected.end());
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());

    ArrayOf<Exec, u64> device_keys, out;
    exec.upload(keys, device_keys);
    const i64 distinct = exec.sort_unique(device_keys, n, bits, out);
    EXPECT_EQ(distinct, static_cast<i64>(expected.size()));
    EXPECT_EQ(out.size(), expected.size());
    EXPECT_EQ(downloaded(exec, out, distinct), expected);
}

template <class Exec>
void check_order_by_key(Exec& exec, i64 n, u64 below, u64 seed) {
    SCOPED_TRACE("keys below " + std::to_string(below));
    std::mt19937_64 random(seed);
    std::vector<u64> keys(static_cast<std::size_t>(n));
    for (u64& k : keys) k = below == 0 ? random() : random() % below;
    std::vector<i32> expected(static_cast<std::size_t>(n));
    std::iota(expected.begin(), expected.end(), 0);
    std::stable_sort(expected.begin(), expected.end(), [&](i32 a, i32 b) {
        return keys[static_cast<std::size_t>(a)] < keys[static_cast<std::size_t>(b)];
    });

    ArrayOf<Exec, u64> device_keys;
    exec.upload(keys, device_keys);
    ArrayOf<Exec, i32> order;
    exec.order_by_key(device_keys, n, order);
    EXPECT_EQ(order.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(downloaded(exec, order, n), expected);
    // The keys are read, never reordered.
    EXPECT_EQ(downloaded(exec, device_keys, n), keys);
}

// --- for_each_of_tiled and tile.hpp's loops

// A task's scratch: where each member of its loop was enumerated.
struct TileScratch {
    static constexpr int kMax = 80;
    i32 index_at[kMax];
};

// What one task's loops found: each against a plain loop over the task's
// indices. member(i) and value(i) are functions of (task, i); the ordered
// fold is not commutative, so it holds only in order.
struct TileResult {
    i32 any, first, sum, members, stopped, in_order;
    u64 fold;
    bool operator==(const TileResult& o) const {
        return any == o.any && first == o.first && sum == o.sum && members == o.members && stopped == o.stopped &&
               in_order == o.in_order && fold == o.fold;
    }
};

TETISO_HD inline u32 tile_hash(i64 task, int i) {
    u64 h = static_cast<u64>(task) * 0x9E3779B97F4A7C15ull + static_cast<u64>(i) * 0xC2B2AE3D27D4EB4Full;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    return static_cast<u32>(h >> 32);
}

template <class Tile>
TETISO_HD TileResult run_tile_loops(const Tile& tile, i64 task, TileScratch& scratch) {
    const int n = static_cast<int>(tile_hash(task, -1) % TileScratch::kMax); // 0..79: up to 5 passes of 16
    const u32 keep = tile_hash(task, -2) % 4;                                  // none, some, most, all
    const auto member = [&](int i) { return keep == 3 || (keep > 0 && tile_hash(task, i) % 4 < keep); };
    const auto value = [&](int i) { return static_cast<int>(tile_hash(task, i) % 1000); };
    TileResult r{};
    r.any = tile_any(tile, n, member);
    r.first = tile_first(tile, n, member);
    r.sum = tile_sum(tile, n, value);
    bool stopped = false;
    // Stops at a member whose value is below 5: half the tasks have none.
    const u32 stop_below = task % 2 ? 5 : 0;
    const int members = tile_enumerate(tile, n, member, [&](int i, int place) {
        scratch.index_at[place] = i;
        return value(i) < static_cast<int>(stop_below);
    }, &stopped);
    tile.sync();
    r.stopped = stopped;
    r.members = stopped ? -1 : members; // where it stopped, the count is the tile's passes'
    r.in_order = 1;
    if (!stopped)
        for (int i = 0, place = 0; i < n; ++i)
            if (member(i) && scratch.index_at[place++] != i) r.in_order = 0;
    u64 fold = 7;
    tile_fold(tile, n, member, [&](int i) { return static_cast<u64>(value(i)); },
              [&](u64 v) { fold = fold * 1000003u + v; });
    r.fold = fold;
    return r;
}

template <class Exec>
void check_tiled(Exec& exec, i64 tasks) {
    ArrayOf<Exec, i64> count;
    exec.upload(std::vector<i64>{tasks}, count);
    ArrayOf<Exec, TileResult> out;
    exec.assign(out, std::max<i64>(tasks, 1), TileResult{});
    TileResult* o = out.data();
    using Tile = typename Exec::Tile;
    exec.template for_each_of_tiled<TileScratch>(count.data(), tasks, [=] TETISO_HD(i64 task, const Tile& tile,
                                                                                     TileScratch& scratch) {
        const TileResult r = run_tile_loops(tile, task, scratch);
        if (tile.rank() == 0) o[task] = r;
    });
    const std::vector<TileResult> got = downloaded(exec, out, tasks);
    for (i64 task = 0; task < tasks; ++task) {
        // Plain loops.
        const int n = static_cast<int>(tile_hash(task, -1) % TileScratch::kMax);
        const u32 keep = tile_hash(task, -2) % 4;
        const auto member = [&](int i) { return keep == 3 || (keep > 0 && tile_hash(task, i) % 4 < keep); };
        const auto value = [&](int i) { return static_cast<int>(tile_hash(task, i) % 1000); };
        TileResult expected{0, n, 0, 0, 0, 1, 7};
        for (int i = 0; i < n; ++i) {
            expected.sum += value(i);
            if (!member(i)) continue;
            expected.any = 1;
            expected.first = std::min(expected.first, i);
            ++expected.members;
            if (task % 2 && value(i) < 5) expected.stopped = 1;
            expected.fold = expected.fold * 1000003u + static_cast<u64>(value(i));
        }
        if (expected.stopped) expected.members = -1;
        const TileResult& r = got[static_cast<std::size_t>(task)];
        ASSERT_TRUE(r == expected) << "task " << task << ": any " << r.any << " first " << r.first << " sum " << r.sum
                                   << " members " << r.members << " stopped " << r.stopped << " in order "
                                   << r.in_order << " fold " << r.fold;
    }
}

// --- the backends

#ifdef TETISO_TEST_GPU

// CudaExec::run_steps: a loop of steps on the device alone. List `current`
// holds values; a step's second pass counts a visit to each and carries on
// those whose low `step` bits are all 1 (a set, whatever order the passes
// append in), the first pass emptying the other list. A value v with t
// trailing ones is visited in steps 1 .. t + 1; the loop ends after the
// step that carries nothing on.
template <class Exec>
void check_run_steps(Exec& exec, i64 n) {
    std::vector<i64> values(static_cast<std::size_t>(n));
    std::iota(values.begin(), values.end(), i64{0});
    ArrayOf<Exec, i64> list0, list1, sizes, visits;
    exec.upload(values, list0);
    exec.assign(list1, std::max<i64>(n, 1), i64{-1});
    exec.upload(std::vector<i64>{n, 7}, sizes);
    exec.assign(visits, n, i64{0});
    i64 *l0 = list0.data(), *l1 = list1.data(), *size = sizes.data(), *visited = visits.data();
    const auto first = [=] TETISO_HD(i64 i, u32, int current) {
        if (i == 0) size[1 - current] = 0;
    };
    const auto second = [=] TETISO_HD(i64 i, u32 step, int current) {
        const i64 value = (current == 0 ? l0 : l1)[i];
        hd::atomic_add(visited + value, i64{1});
        const i64 mask = (i64{1} << step) - 1;
        if ((value & mask) == mask) (current == 0 ? l1 : l0)[hd::atomic_add(size + 1 - current, i64{1})] = value;
    };
    // A device too small for the loop declines it (the caller steps).
    ASSERT_EQ(exec.run_steps(size, 0, 0, n, first, second, 6), exec.steps_on_device(n));
    if (!exec.steps_on_device(n)) return;
    std::vector<i64> expected(static_cast<std::size_t>(n));
    i64 steps = 0;
    for (i64 v = 0; v < n; ++v) {
        i64 ones = 0;
        while ((v >> ones) & 1) ++ones;
        expected[static_cast<std::size_t>(v)] = ones + 1;
        steps = std::max(steps, ones + 1);
    }
    EXPECT_EQ(exec.read_tally()[6], steps);
    EXPECT_EQ(downloaded(exec, visits, n), expected);
}

struct OnCuda {
    using Exec = CudaExec;
    static constexpr bool kHost = false;
    cudaStream_t stream = nullptr;
    std::unique_ptr<CudaExec> exec;
    bool start() {
        int devices = 0;
        if (cudaGetDeviceCount(&devices) != cudaSuccess || devices == 0) {
            cudaGetLastError(); // clear the error the query left
            return false;
        }
        cuda::check(cudaStreamCreate(&stream), "cudaStreamCreate");
        exec = std::make_unique<CudaExec>(stream);
        return true;
    }
    ~OnCuda() {
        exec.reset();
        if (stream) cudaStreamDestroy(stream);
    }
};
using Backends = ::testing::Types<OnCuda>;

#else

template <int kThreads>
struct OnHost {
    using Exec = HostExec;
    static constexpr bool kHost = true;
    std::unique_ptr<HostExec> exec;
    bool start() {
        exec = std::make_unique<HostExec>();
        exec->threads = kThreads;
        return true;
    }
};
using Backends = ::testing::Types<OnHost<1>, OnHost<4>>;

#endif

template <class Backend>
class ExecConformance : public ::testing::Test {
protected:
    void SetUp() override {
        if (!backend_.start()) GTEST_SKIP() << "no GPU";
    }
    typename Backend::Exec& exec() { return *backend_.exec; }

private:
    Backend backend_;
};
TYPED_TEST_SUITE(ExecConformance, Backends);

template <class Check>
void at_every_size(const Check& check) {
    for (const i64 n : kSizes) {
        SCOPED_TRACE("n = " + std::to_string(n));
        check(n);
    }
}

TYPED_TEST(ExecConformance, TransfersAssignGetSet) {
    u64 seed = 11;
    at_every_size([&](i64 n) { check_transfers(this->exec(), n, seed++); });
}

TYPED_TEST(ExecConformance, ForEachAtEveryGrain) {
    for (const Grain grain : {Grain::kCheap, Grain::kTests, Grain::kWindow})
        at_every_size([&](i64 n) { check_for_each(this->exec(), n, grain); });
}

TYPED_TEST(ExecConformance, ForEachOfSizeFromBackendMemory) {
    for (const Grain grain : {Grain::kCheap, Grain::kTests})
        at_every_size([&](i64 n) {
            check_for_each_of(this->exec(), n, n / 2, 0, grain);
            check_for_each_of(this->exec(), n, 0, 0, grain);
            check_for_each_of(this->exec(), n, n, 0, grain);
            check_for_each_of(this->exec(), n, 0, n, grain);
            check_for_each_of(this->exec(), n, n / 3, n / 2, grain);
        });
}

TYPED_TEST(ExecConformance, FilterCopyIfRankCountAndTally) {
    u64 seed = 21;
    for (const u32 percent : kKeptPercent) at_every_size([&](i64 n) { check_selection(this->exec(), n, percent, seed++); });
}

TYPED_TEST(ExecConformance, ExclusiveScanAndSum) {
    u64 seed = 31;
    at_every_size([&](i64 n) { check_sums(this->exec(), n, seed++); });
}

TYPED_TEST(ExecConformance, GroupByKeyIsStable) {
    u64 seed = 41;
    for (const i64 groups : {i64{1}, i64{5}, i64{1000}}) at_every_size([&](i64 n) { check_group_by_key(this->exec(), n, groups, seed++); });
}

TYPED_TEST(ExecConformance, OrderByPriorityBreaksTiesByEnds) {
    u64 seed = 51;
    // One priority for all (every order decided by the ends), a few, any.
    for (const u32 priorities : {1u, 4u, 0xffffffffu}) at_every_size([&](i64 n) { check_order_by_priority(this->exec(), n, priorities, seed++); });
}

TYPED_TEST(ExecConformance, SortUnique) {
    u64 seed = 61;
    for (const int bits : {1, 13, 40, 64}) at_every_size([&](i64 n) { check_sort_unique(this->exec(), n, bits, seed++); });
}

TYPED_TEST(ExecConformance, OrderByKeyIsStable) {
    u64 seed = 71;
    // One key for all, many ties, few ties.
    for (const u64 below : {u64{1}, u64{7}, u64{0}}) at_every_size([&](i64 n) { check_order_by_key(this->exec(), n, below, seed++); });
}

#ifdef TETISO_TEST_GPU
TYPED_TEST(ExecConformance, RunStepsToTheEndOnTheDevice) {
    at_every_size([&](i64 n) { check_run_steps(this->exec(), n); });
}
#endif

// The members whose values are each backend's own (the steps, the window,
// the times) promise only what a driver relies on.
TYPED_TEST(ExecConformance, TiledLoopsGiveTheSequentialLoopsResults) {
    at_every_size([&](i64 n) { check_tiled(this->exec(), n); });
}

TYPED_TEST(ExecConformance, MarksStepsWindowAndSync) {
    using Exec = typename TypeParam::Exec;
    auto& exec = this->exec();
    EXPECT_EQ(Exec::kHost, TypeParam::kHost);
    EXPECT_GE(Exec::steps_between_checks(), 1);
    for (const i64 n : {i64{0}, i64{1}, i64{1000}, i64{1} << 20}) EXPECT_GE(Exec::reservation_window(n), 1) << n;

    const int a = exec.mark();
    check_for_each(exec, 1000, Grain::kCheap);
    const int b = exec.mark();
    EXPECT_EQ(b, a + 1);
    EXPECT_GE(exec.seconds_between(a, b), 0.0);
    exec.sync();
    exec.clear_marks();
    EXPECT_EQ(exec.mark(), 0);
}

} // namespace tetiso::test_exec
