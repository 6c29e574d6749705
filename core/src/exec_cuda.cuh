// The CUDA backend of the data-parallel drivers: the members of HostExec
// (exec_host.hpp) over device memory, each one kernel or one CUB primitive on
// the backend's stream. Every primitive has one result whatever the launch
// configuration (integer sums and counts, CUB's stable radix sort and
// order-keeping select), so a driver gives the host's bytes here.
//
// The host reads a scalar back only where a driver needs a size to go on (a
// count, the new length of a list): each such read waits for the stream.
// Counts the driver needs only later (a round's statistics, a list's length
// that a loop of the device reads) stay on the device in a tally, read all
// at once; stage times are events on the stream, read when the round is over.
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>

#include "cuda_support.cuh"
#include "exec_cuda_detail.cuh"
#include "hd.hpp"
#include "parallel.hpp"

namespace tetiso {

class CudaExec {
public:
    using i32 = std::int32_t;
    using i64 = std::int64_t;
    using u32 = std::uint32_t;
    using u64 = std::uint64_t;
    using Grain = parallel::Grain;
    static constexpr bool kHost = false;

    template <class T>
    using Array = cuda::DeviceArray<T>;

    explicit CudaExec(cudaStream_t stream) : stream_(stream) {
        int device = 0, processors = 0;
        cuda::check(cudaGetDevice(&device), "cudaGetDevice");
        cuda::check(cudaDeviceGetAttribute(&processors, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute");
        // 2048 threads a multiprocessor: 8 blocks of kBlock.
        processors_ = static_cast<unsigned>(std::max(1, processors));
        resident_blocks_ = processors_ * (2048 / cuda::kBlock);
        test_blocks_ = static_cast<unsigned>(std::max(1, processors)) * tests_blocks_per_processor();
        cuda::check(cudaMallocHost(reinterpret_cast<void**>(&pinned_), sizeof(i64) * (kScalars + kTallySlots)),
                    "cudaMallocHost");
        scalars_.resize(kScalars);
        tally_.resize(kTallySlots);
    }
    ~CudaExec() {
        for (cudaEvent_t event : marks_) cudaEventDestroy(event);
        cudaFreeHost(pinned_);
    }
    CudaExec(const CudaExec&) = delete;
    CudaExec& operator=(const CudaExec&) = delete;

    cudaStream_t stream() const { return stream_; }

    // Times one primitive for the profile (see cuda_exec::Profile).
    class Timed {
    public:
        Timed(const CudaExec& exec, const char* what, const char* file, int line)
            : exec_(exec), what_(what), file_(file), line_(line) {
            if (!exec_.profile_.on()) return;
            cudaStreamSynchronize(exec_.stream_);
            start_ = std::chrono::steady_clock::now();
        }
        ~Timed() {
            if (!exec_.profile_.on()) return;
            cudaStreamSynchronize(exec_.stream_);
            exec_.profile_.add(what_, file_, line_,
                               std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
        }

    private:
        const CudaExec& exec_;
        const char *what_, *file_;
        int line_;
        std::chrono::steady_clock::time_point start_;
    };

    template <class Function>
    void for_each(i64 n, const Function& function, Grain grain = Grain::kCheap, const char* file = __builtin_FILE(),
                  int line = __builtin_LINE()) const {
        const Timed timed(*this, "for_each", file, line);
        if (grain != Grain::kTests || n <= 0) return cuda::for_each(stream_, n, function);
        // One wave of blocks, each thread striding: how many stay resident
        // on a multiprocessor decides how much of the tests' per-thread
        // scratch (local memory) the caches hold.
        cuda::for_each_heavy_kernel<<<std::min(cuda::blocks_for(n), test_blocks_), cuda::kBlock, 0, stream_>>>(n, function);
        cuda::check_launch("for_each (tests)");
    }

    // function(i) for i < max(*n, min_n), n in device memory and at most
    // max_n: a loop whose size the device set, launched without the host
    // reading it. The grid is what the device holds at once, at most, each
    // thread striding over the indices: a loop of a few elements costs a
    // small launch whatever max_n is.
    template <class Function>
    void for_each_of(const i64* n, i64 max_n, const Function& function, Grain grain = Grain::kCheap, i64 min_n = 0,
                     const char* file = __builtin_FILE(), int line = __builtin_LINE()) const {
        const Timed timed(*this, "for_each_of", file, line);
        const i64 most = std::max(max_n, min_n);
        if (most <= 0) return;
        if (grain == Grain::kTests) {
            const unsigned blocks = std::min<unsigned>(cuda::blocks_for(most), test_blocks_);
            cuda_exec::for_each_of_heavy_kernel<<<blocks, cuda::kBlock, 0, stream_>>>(n, min_n, function);
        } else {
            const unsigned blocks = std::min<unsigned>(cuda::blocks_for(most), resident_blocks_);
            cuda::for_each_of_kernel<<<blocks, cuda::kBlock, 0, stream_>>>(n, min_n, function);
        }
        cuda::check_launch("for_each_of");
    }

    // The tile that runs one task of for_each_of_tiled (tile.hpp): a
    // legality test's loops over the new faces of a collapse (a dozen early
    // on) and over their corners (twice that) spread over the tile, the
    // faces shared in shared memory rather than kept in each thread's local
    // memory. Sixteen: a warp of 32 per collapse left more threads idle than
    // it saved (batches of 32 domains on an H200: 3.9 against 4.9 M raw
    // triangles/s). TETISO_TEST_TILE sets it at build time, for measuring.
#ifdef TETISO_TEST_TILE
    static constexpr int kTileSize = TETISO_TEST_TILE;
#else
    static constexpr int kTileSize = 16;
#endif
    using Tile = cuda_exec::DeviceTile<kTileSize>;
    // Eight tiles a block, each with its scratch. The tests' kernel held to
    // the registers of five blocks a multiprocessor (96): uncapped (160,
    // three blocks), its warps waited on the caches with no other warp to
    // run; it spills a little at 96, and gains from more warps more than
    // that costs; at six blocks (85) it spills more than it gains (batches of 32
    // domains on an H200: 5.1-5.2, 5.0-5.1 and 4.9-5.0 M raw triangles/s).
    // TETISO_TEST_TILE_BLOCKS sets it at build time, for measuring.
    static constexpr int kTilesPerBlock = 8;
#ifdef TETISO_TEST_TILE_BLOCKS
    static constexpr int kTileBlocksPerProcessor = TETISO_TEST_TILE_BLOCKS;
#else
    static constexpr int kTileBlocksPerProcessor = 5;
#endif

    // function(i, tile, scratch) for i < *n (at most max_n), each i a task
    // of a tile of kTileSize threads sharing `scratch` in shared memory.
    template <class Scratch, class Function>
    void for_each_of_tiled(const i64* n, i64 max_n, const Function& function, const char* file = __builtin_FILE(),
                           int line = __builtin_LINE()) const {
        const Timed timed(*this, "for_each_of_tiled", file, line);
        if (max_n <= 0) return;
        const i64 blocks = std::min<i64>((max_n + kTilesPerBlock - 1) / kTilesPerBlock, i64{processors_} * 8);
        cuda_exec::for_each_of_tiled_kernel<kTileSize, kTileSize * kTilesPerBlock, kTileBlocksPerProcessor, Scratch>
            <<<static_cast<unsigned>(blocks), kTileSize * kTilesPerBlock, 0, stream_>>>(n, function);
        cuda::check_launch("for_each_of_tiled");
    }

    // Steps of a device-side loop between two reads of its state by the host:
    // a read waits for the device, a step past the loop's end costs a few
    // empty launches.
    static int steps_between_checks() { return 8; }

    // Whether run_steps runs a loop whose lists hold up to `capacity`: where
    // they fit the threads the device holds at once. (A surface's first
    // rounds, with windows of hundreds of thousands, were slower with the
    // loop on the device; its later rounds, and small pieces, faster.)
    // TETISO_GPU_HOST_STEPS set: never, for measuring.
    bool steps_on_device(i64 capacity) const {
        static const bool host_steps = std::getenv("TETISO_GPU_HOST_STEPS") != nullptr;
        return !host_steps && capacity <= static_cast<i64>(resident_blocks_) * cuda::kBlock;
    }

    // The steps of a device-side loop (choose_by_reservations), run to its
    // end without the host: first(i, step, current) for every i below
    // sizes[current], then second(i, step, current), then current = 1 -
    // current, step + 1 each time, until sizes[current] is 0 (the passes
    // keep the sizes). capacity: the most a list holds. The steps run are
    // left in tally slot `slot`. Returns false where the device does not
    // run the loop as one cooperative grid (not steps_on_device(capacity),
    // or a launch refused): the caller then steps from the host.
    template <class First, class Second>
    bool run_steps(i64* sizes, int current, u32 step, i64 capacity, const First& first, const Second& second, int slot,
                   const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "run_steps", file, line);
        if (!steps_on_device(capacity)) return false;
        const auto kernel = cuda_exec::steps_kernel<First, Second>;
        static const int per_processor = [&] {
            int blocks = 0;
            if (cudaOccupancyMaxActiveBlocksPerMultiprocessor(&blocks, kernel, cuda::kBlock, 0) != cudaSuccess) return 0;
            return blocks;
        }();
        if (per_processor <= 0) return false;
        // Every block that fits: the grid is all the threads the loop has.
        const unsigned blocks = std::max(1u, std::min<unsigned>(cuda::blocks_for(std::max<i64>(capacity, 1)),
                                                               static_cast<unsigned>(per_processor) * processors_));
        i64* steps_run = tally_.data() + slot;
        void* arguments[] = {&sizes, &current, &step, const_cast<First*>(&first), const_cast<Second*>(&second), &steps_run};
        const cudaError_t launched = cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(blocks),
                                                                 dim3(cuda::kBlock), arguments, 0, stream_);
        if (launched == cudaSuccess) return true;
        cudaGetLastError(); // a refused launch leaves no error behind
        return false;
    }

    template <class Keep>
    i32 filter(i64 n, const Keep& keep, Array<i32>& out, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "filter", file, line);
        out.resize(static_cast<std::size_t>(n));
        if (n == 0) return 0;
        i64* count = scalars_.data();
        const thrust::counting_iterator<i64> indices(0);
        std::size_t bytes = 0;
        cuda::check(cub::DeviceSelect::If(nullptr, bytes, indices, out.data(), count, n,
                                          cuda_exec::IndexPredicate<Keep>{keep}, stream_),
                    "select");
        cuda::check(cub::DeviceSelect::If(temp(bytes), bytes, indices, out.data(), count, n,
                                          cuda_exec::IndexPredicate<Keep>{keep}, stream_),
                    "selecting indices");
        const auto kept = static_cast<i32>(read(count));
        out.resize(static_cast<std::size_t>(kept));
        return kept;
    }

    template <class T, class Keep>
    i32 copy_if(const Array<T>& in, i64 n, const Keep& keep, Array<T>& out, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "copy_if", file, line);
        out.resize(static_cast<std::size_t>(n));
        if (n == 0) return 0;
        flags_.resize(static_cast<std::size_t>(n));
        char* flags = flags_.data();
        cuda::for_each(stream_, n, [=] __device__(i64 i) { flags[i] = keep(i) ? 1 : 0; });
        i64* count = scalars_.data();
        std::size_t bytes = 0;
        cuda::check(cub::DeviceSelect::Flagged(nullptr, bytes, in.data(), flags, out.data(), count, n, stream_), "select");
        cuda::check(cub::DeviceSelect::Flagged(temp(bytes), bytes, in.data(), flags, out.data(), count, n, stream_),
                    "selecting elements");
        const auto kept = static_cast<i32>(read(count));
        out.resize(static_cast<std::size_t>(kept));
        return kept;
    }

    // rank's and rank_into's common part: flag[i] = keep(i), and rank (n + 1
    // entries) their exclusive sum, so that rank[n] is the number kept.
    // (Public: CUDA's extended lambdas may not live in a private member.)
    template <class Keep>
    const i32* flag_and_rank(i64 n, const Keep& keep, Array<i32>& rank) {
        rank.resize(static_cast<std::size_t>(n) + 1);
        counts_.resize(static_cast<std::size_t>(n) + 1);
        i32* flag = counts_.data();
        cuda::for_each(stream_, n + 1, [=] __device__(i64 i) { flag[i] = i < n && keep(i) ? 1 : 0; });
        scan(flag, rank.data(), n + 1);
        return flag;
    }

    template <class Keep>
    i32 rank(i64 n, const Keep& keep, Array<i32>& rank, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "rank", file, line);
        const i32* flag = flag_and_rank(n, keep, rank);
        i32* r = rank.data();
        const i32 kept = get(rank, n);
        cuda::for_each(stream_, n, [=] __device__(i64 i) {
            if (!flag[i]) r[i] = -1;
        });
        rank.resize(static_cast<std::size_t>(n));
        return kept;
    }

    // rank() with the number kept left in tally slot `slot` rather than
    // read: rank.size() is then n, an upper bound.
    template <class Keep>
    void rank_into(i64 n, const Keep& keep, Array<i32>& rank, int slot, const char* file = __builtin_FILE(),
                   int line = __builtin_LINE()) {
        const Timed timed(*this, "rank_into", file, line);
        const i32* flag = flag_and_rank(n, keep, rank);
        i32* r = rank.data();
        i64* kept = tally_.data() + slot;
        cuda::for_each(stream_, std::max<i64>(n, 1), [=] __device__(i64 i) {
            if (i == 0) *kept = r[n];
            if (i < n && !flag[i]) r[i] = -1;
        });
        rank.resize(static_cast<std::size_t>(n));
    }

    template <class Counted>
    i64 count(i64 n, const Counted& counted, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "count", file, line);
        if (n == 0) return 0;
        i64* total = scalars_.data();
        const auto counts = thrust::make_transform_iterator(thrust::counting_iterator<i64>(0),
                                                            cuda_exec::IndexCount<Counted>{counted});
        std::size_t bytes = 0;
        cuda::check(cub::DeviceReduce::Sum(nullptr, bytes, counts, total, n, stream_), "sum");
        cuda::check(cub::DeviceReduce::Sum(temp(bytes), bytes, counts, total, n, stream_), "counting");
        return read(total);
    }

    i32 exclusive_scan(const Array<i32>& counts, i64 n, Array<i32>& offsets, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "exclusive_scan", file, line);
        offsets_of(counts, n, offsets);
        return get(offsets, n);
    }

    // offsets[i] = counts[0] + ... + counts[i-1] for i <= n, left on the device
    // (exclusive_scan without reading the sum).
    void offsets_of(const Array<i32>& counts, i64 n, Array<i32>& offsets) {
        offsets.resize(static_cast<std::size_t>(n) + 1);
        if (n > 0) scan(counts.data(), offsets.data(), n);
        const i32* c = counts.data();
        i32* o = offsets.data();
        cuda::for_each(stream_, 1, [=] __device__(i64) { o[n] = n > 0 ? o[n - 1] + c[n - 1] : 0; });
    }

    // offsets_of, the sum left in tally slot `slot`.
    void offsets_into(const Array<i32>& counts, i64 n, Array<i32>& offsets, int slot) {
        offsets.resize(static_cast<std::size_t>(n) + 1);
        if (n > 0) scan(counts.data(), offsets.data(), n);
        const i32* c = counts.data();
        i32* o = offsets.data();
        i64* sum = tally_.data() + slot;
        cuda::for_each(stream_, 1, [=] __device__(i64) {
            o[n] = n > 0 ? o[n - 1] + c[n - 1] : 0;
            *sum = o[n];
        });
    }

    // The counts a driver needs only later: count_into and filter_into leave
    // theirs in a slot of the tally, on the device, for a loop of the device
    // to read (tally_at, with for_each_of) or for the host to read with the
    // others in one wait (read_tally).
    static constexpr int kTallySlots = 16;
    template <class Counted>
    void count_into(i64 n, const Counted& counted, int slot, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "count_into", file, line);
        i64* total = tally_.data() + slot;
        if (n == 0) return cuda::for_each(stream_, 1, [=] __device__(i64) { *total = 0; });
        const auto counts = thrust::make_transform_iterator(thrust::counting_iterator<i64>(0),
                                                            cuda_exec::IndexCount<Counted>{counted});
        std::size_t bytes = 0;
        cuda::check(cub::DeviceReduce::Sum(nullptr, bytes, counts, total, n, stream_), "sum");
        cuda::check(cub::DeviceReduce::Sum(temp(bytes), bytes, counts, total, n, stream_), "counting");
    }
    // out[0 .. tally slot) = every i < n with keep(i), ascending (out holds
    // n entries).
    template <class Keep>
    void filter_into(i64 n, const Keep& keep, Array<i32>& out, int slot, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "filter_into", file, line);
        out.resize(static_cast<std::size_t>(n));
        i64* count = tally_.data() + slot;
        if (n == 0) return cuda::for_each(stream_, 1, [=] __device__(i64) { *count = 0; });
        const thrust::counting_iterator<i64> indices(0);
        std::size_t bytes = 0;
        cuda::check(cub::DeviceSelect::If(nullptr, bytes, indices, out.data(), count, n,
                                          cuda_exec::IndexPredicate<Keep>{keep}, stream_),
                    "select");
        cuda::check(cub::DeviceSelect::If(temp(bytes), bytes, indices, out.data(), count, n,
                                          cuda_exec::IndexPredicate<Keep>{keep}, stream_),
                    "selecting indices");
    }
    const i64* tally_at(int slot) const { return tally_.data() + slot; }
    std::array<i64, kTallySlots> read_tally(const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "read_tally", file, line);
        i64* host = pinned_ + kScalars;
        cuda::check(cudaMemcpyAsync(host, tally_.data(), sizeof(i64) * kTallySlots, cudaMemcpyDeviceToHost, stream_),
                    "reading the tally");
        cuda::check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
        std::array<i64, kTallySlots> values;
        std::copy(host, host + kTallySlots, values.begin());
        return values;
    }

    // Stage times: mark() records an event where the stream has got to;
    // seconds_between(a, b) waits for b. clear_marks() lets the next marks
    // reuse the events.
    int mark() {
        if (next_mark_ == marks_.size()) {
            cudaEvent_t event;
            cuda::check(cudaEventCreate(&event), "cudaEventCreate");
            marks_.push_back(event);
        }
        cuda::check(cudaEventRecord(marks_[next_mark_], stream_), "cudaEventRecord");
        return static_cast<int>(next_mark_++);
    }
    double seconds_between(int a, int b) const {
        cuda::check(cudaEventSynchronize(marks_[static_cast<std::size_t>(b)]), "cudaEventSynchronize");
        float ms = 0;
        cuda::check(cudaEventElapsedTime(&ms, marks_[static_cast<std::size_t>(a)], marks_[static_cast<std::size_t>(b)]),
                    "cudaEventElapsedTime");
        return 1e-3 * ms;
    }
    void clear_marks() { next_mark_ = 0; }

    // A stable grouping by key (HostExec::group_by_key): the counts by
    // atomic increments (an integer sum, the same in any order), the order
    // by CUB's stable radix sort of (key, index).
    template <class Key>
    void group_by_key(i64 n, i64 groups, const Key& key, Array<i32>& first, Array<i32>& order, Array<i32>& scratch, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "group_by_key", file, line);
        scratch.resize(static_cast<std::size_t>(groups));
        i32* count = scratch.data();
        cuda::for_each(stream_, groups, [=] __device__(i64 g) { count[g] = 0; });
        sort_keys_.resize(static_cast<std::size_t>(n));
        sort_values_.resize(static_cast<std::size_t>(n));
        i32* keys = sort_keys_.data();
        i32* values = sort_values_.data();
        cuda::for_each(stream_, n, [=] __device__(i64 i) {
            const i32 k = key(i);
            keys[i] = k;
            values[i] = static_cast<i32>(i);
            hd::atomic_add(count + k, 1);
        });
        offsets_of(scratch, groups, first);
        order.resize(static_cast<std::size_t>(n));
        if (n == 0) return;
        sorted_keys_.resize(static_cast<std::size_t>(n));
        const int bits = bits_for(groups);
        std::size_t bytes = 0;
        cuda::check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys, sorted_keys_.data(), values, order.data(), n, 0,
                                                    bits, stream_),
                    "sort");
        cuda::check(cub::DeviceRadixSort::SortPairs(temp(bytes), bytes, keys, sorted_keys_.data(), values, order.data(), n,
                                                    0, bits, stream_),
                    "grouping by key");
    }

    // order = ops (n edge ids) by descending priority, ties by descending
    // first end, then descending second end: one radix sort of
    // (~priority, ~first end), then the runs that still tie (two edges of
    // one vertex with one priority: rare, and short) put in order.
    void order_by_priority(const Array<i32>& ops, i64 n, const u32* priority, const i32* v0, const i32* v1,
                           Array<i32>& order, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "order_by_priority", file, line);
        order.resize(static_cast<std::size_t>(n));
        if (n == 0) return;
        wide_keys_.resize(static_cast<std::size_t>(n));
        sorted_wide_keys_.resize(static_cast<std::size_t>(n));
        u64* keys = wide_keys_.data();
        const i32* list = ops.data();
        cuda::for_each(stream_, n, [=] __device__(i64 k) {
            const i32 e = list[k];
            keys[k] = (static_cast<u64>(~priority[e]) << 32) | static_cast<u32>(~static_cast<u32>(v0[e]));
        });
        std::size_t bytes = 0;
        cuda::check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys, sorted_wide_keys_.data(), list, order.data(), n,
                                                    0, 64, stream_),
                    "sort");
        cuda::check(cub::DeviceRadixSort::SortPairs(temp(bytes), bytes, keys, sorted_wide_keys_.data(), list,
                                                    order.data(), n, 0, 64, stream_),
                    "sorting by priority");
        const u64* sorted = sorted_wide_keys_.data();
        i32* o = order.data();
        cuda::for_each(stream_, n, [=] __device__(i64 i) {
            if ((i > 0 && sorted[i - 1] == sorted[i]) || i + 1 == n || sorted[i + 1] != sorted[i]) return;
            i64 end = i + 1;
            while (end < n && sorted[end] == sorted[i]) ++end;
            for (i64 a = i + 1; a < end; ++a) { // insertion sort by descending second end
                const i32 e = o[a];
                i64 b = a;
                for (; b > i && v1[o[b - 1]] < v1[e]; --b) o[b] = o[b - 1];
                o[b] = e;
            }
        });
    }

    // Every operation enters the window at once: the choice does not depend
    // on the width, and the device is filled best by all of them.
    static i64 reservation_window(i64 n) { return n > 0 ? n : 1; }

    template <class T>
    void assign(Array<T>& a, i64 n, T value, const char* file = __builtin_FILE(), int line = __builtin_LINE()) const {
        const Timed timed(*this, "assign", file, line);
        a.resize(static_cast<std::size_t>(n));
        T* data = a.data();
        cuda::for_each(stream_, n, [=] __device__(i64 i) { data[i] = value; });
    }

    template <class T>
    T get(const Array<T>& a, i64 i, const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
        const Timed timed(*this, "get", file, line);
        T value;
        cuda::check(cudaMemcpyAsync(pinned_, a.data() + i, sizeof(T), cudaMemcpyDeviceToHost, stream_), "reading a value");
        cuda::check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
        std::memcpy(&value, pinned_, sizeof(T));
        return value;
    }
    template <class T>
    void set(Array<T>& a, i64 i, T value) {
        T* at = a.data() + i;
        cuda::for_each(stream_, 1, [=] __device__(i64) { *at = value; });
    }

    template <class T, class Allocator>
    void upload(const std::vector<T, Allocator>& host, Array<T>& a, const char* file = __builtin_FILE(), int line = __builtin_LINE()) const {
        const Timed timed(*this, "upload", file, line);
        a.resize(host.size());
        if (!host.empty())
            cuda::check(cudaMemcpyAsync(a.data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice, stream_),
                        "uploading");
        // Pageable host memory: the copy is staged, and `host` may go once
        // this returns.
        cuda::check(cudaStreamSynchronize(stream_), "uploading");
    }
    template <class T, class Allocator>
    void download(const Array<T>& a, i64 n, std::vector<T, Allocator>& host, const char* file = __builtin_FILE(), int line = __builtin_LINE()) const {
        const Timed timed(*this, "download", file, line);
        host.resize(static_cast<std::size_t>(n));
        if (n > 0)
            cuda::check(cudaMemcpyAsync(host.data(), a.data(), static_cast<std::size_t>(n) * sizeof(T),
                                        cudaMemcpyDeviceToHost, stream_),
                        "downloading");
        cuda::check(cudaStreamSynchronize(stream_), "downloading");
    }

    void sync(const char* file = __builtin_FILE(), int line = __builtin_LINE()) const {
        const Timed timed(*this, "sync", file, line); cuda::check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize"); }

    // The primitives marching tetrahedra adds (marching_tets.hpp; see
    // HostExec's).

    template <class Count>
    u64 exclusive_sum(i64 n, const Count& count, Array<u32>& offsets, const char* file = __builtin_FILE(),
                      int line = __builtin_LINE()) {
        const Timed timed(*this, "exclusive_sum", file, line);
        offsets.resize(static_cast<std::size_t>(n) + 1);
        const auto in = thrust::make_transform_iterator(thrust::counting_iterator<i64>(0),
                                                        cuda_exec::IndexSum<Count>{count, n});
        std::size_t bytes = 0;
        cuda::check(cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, offsets.data(), n + 1, stream_), "scan");
        cuda::check(cub::DeviceScan::ExclusiveSum(temp(bytes), bytes, in, offsets.data(), n + 1, stream_), "scanning");
        return get(offsets, n);
    }

    i64 sort_unique(Array<u64>& keys, i64 n, int bits, Array<u64>& out, const char* file = __builtin_FILE(),
                    int line = __builtin_LINE()) {
        const Timed timed(*this, "sort_unique", file, line);
        out.resize(static_cast<std::size_t>(n));
        if (n == 0) return 0;
        sorted_wide_keys_.resize(static_cast<std::size_t>(n));
        std::size_t bytes = 0;
        cuda::check(cub::DeviceRadixSort::SortKeys(nullptr, bytes, keys.data(), sorted_wide_keys_.data(), n, 0, bits,
                                                   stream_),
                    "sort");
        cuda::check(cub::DeviceRadixSort::SortKeys(temp(bytes), bytes, keys.data(), sorted_wide_keys_.data(), n, 0,
                                                   bits, stream_),
                    "sorting keys");
        i64* kept = scalars_.data();
        bytes = 0;
        cuda::check(cub::DeviceSelect::Unique(nullptr, bytes, sorted_wide_keys_.data(), out.data(), kept, n, stream_),
                    "unique");
        cuda::check(cub::DeviceSelect::Unique(temp(bytes), bytes, sorted_wide_keys_.data(), out.data(), kept, n,
                                              stream_),
                    "dropping repeated keys");
        const i64 count = read(kept);
        out.resize(static_cast<std::size_t>(count));
        return count;
    }

    void order_by_key(const Array<u64>& keys, i64 n, Array<i32>& order, const char* file = __builtin_FILE(),
                      int line = __builtin_LINE()) {
        const Timed timed(*this, "order_by_key", file, line);
        order.resize(static_cast<std::size_t>(n));
        if (n == 0) return;
        sort_values_.resize(static_cast<std::size_t>(n));
        sorted_wide_keys_.resize(static_cast<std::size_t>(n));
        i32* values = sort_values_.data();
        cuda::for_each(stream_, n, [=] __device__(i64 i) { values[i] = static_cast<i32>(i); });
        std::size_t bytes = 0;
        cuda::check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys.data(), sorted_wide_keys_.data(), values,
                                                    order.data(), n, 0, 64, stream_),
                    "sort");
        cuda::check(cub::DeviceRadixSort::SortPairs(temp(bytes), bytes, keys.data(), sorted_wide_keys_.data(), values,
                                                    order.data(), n, 0, 64, stream_),
                    "ordering by key");
    }

private:
    static constexpr int kScalars = 4;

    // Blocks of the legality tests' loops a multiprocessor holds at once
    // (TETISO_GPU_TEST_BLOCKS_PER_SM, for measuring, else what the kernel's
    // registers allow).
    static unsigned tests_blocks_per_processor() {
        const char* text = std::getenv("TETISO_GPU_TEST_BLOCKS_PER_SM");
        const int blocks = text ? std::atoi(text) : 0;
        return blocks > 0 ? static_cast<unsigned>(blocks) : 3;
    }

    static int bits_for(i64 groups) {
        int bits = 1;
        while (bits < 31 && (i64{1} << bits) < groups) ++bits;
        return bits;
    }

    void* temp(std::size_t bytes) {
        temp_.resize(bytes > 0 ? bytes : 1);
        return temp_.data();
    }

    void scan(const i32* in, i32* out, i64 n) {
        std::size_t bytes = 0;
        cuda::check(cub::DeviceScan::ExclusiveSum(nullptr, bytes, in, out, n, stream_), "scan");
        cuda::check(cub::DeviceScan::ExclusiveSum(temp(bytes), bytes, in, out, n, stream_), "scanning");
    }

    i64 read(const i64* device_scalar) {
        cuda::check(cudaMemcpyAsync(pinned_, device_scalar, sizeof(i64), cudaMemcpyDeviceToHost, stream_),
                    "reading a count");
        cuda::check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
        return *pinned_;
    }

    cudaStream_t stream_;
    unsigned processors_ = 1, resident_blocks_ = 1, test_blocks_ = 1;
    std::vector<cudaEvent_t> marks_;
    std::size_t next_mark_ = 0;
    mutable cuda_exec::Profile profile_;
    i64* pinned_ = nullptr;
    Array<i64> scalars_, tally_;
    Array<std::byte> temp_;
    Array<char> flags_;
    Array<i32> counts_, sort_keys_, sort_values_, sorted_keys_;
    Array<u64> wide_keys_, sorted_wide_keys_;
};

} // namespace tetiso
