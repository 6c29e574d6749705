// A group of threads that runs one task together (on the GPU a tile of a
// warp, cooperative_groups' thread_block_tile, exec_cuda_detail.cuh's
// DeviceTile; on the host SequentialTile, a single thread), and the loops
// such a task is written with: each index of [0, n) is one thread's, the
// threads striding, and the loop's result is the tile's whole. Every thread
// of the tile calls each loop with the same n and gets the same result, so
// that a task's control flow stays uniform across its tile.
//
// A tile's interface: size(), rank() (this thread's place in it), ballot(b)
// (a mask of the threads whose b holds, bit i for rank i), sum(x) (over the
// tile), shfl(value, rank) (rank's value, to every thread), sync() (a
// barrier of the tile, after which what one thread wrote to memory the tile
// shares the others see), and the static lowest(mask) (the lowest rank in
// mask) and count(mask).
#pragma once

#include "hd.hpp"

namespace tetiso {

// The host's tile: one thread, which runs every loop in order (and stops a
// search at the first hit, as a plain loop would).
struct SequentialTile {
    static constexpr int kSize = 1;
    TETISO_HD static constexpr int size() { return 1; }
    TETISO_HD static constexpr int rank() { return 0; }
    TETISO_HD static unsigned ballot(bool b) { return b ? 1u : 0u; }
    TETISO_HD static int sum(int x) { return x; }
    TETISO_HD static int lowest(unsigned mask) { return mask ? 0 : -1; }
    TETISO_HD static int count(unsigned mask) { return mask ? 1 : 0; }
    TETISO_HD static void sync() {}
    template <class T>
    TETISO_HD static T shfl(const T& value, int) {
        return value;
    }
};

// Whether pred(i) holds for some i < n.
template <class Tile, class Pred>
TETISO_HD bool tile_any(const Tile& tile, int n, const Pred& pred) {
    for (int base = 0; base < n; base += tile.size()) {
        const int i = base + tile.rank();
        if (tile.ballot(i < n && pred(i))) return true;
    }
    return false;
}

// The smallest i < n at which pred(i) holds, else n.
template <class Tile, class Pred>
TETISO_HD int tile_first(const Tile& tile, int n, const Pred& pred) {
    for (int base = 0; base < n; base += tile.size()) {
        const int i = base + tile.rank();
        const unsigned mask = tile.ballot(i < n && pred(i));
        if (mask) return base + Tile::lowest(mask);
    }
    return n;
}

// The sum of value(i) over i < n.
template <class Tile, class Value>
TETISO_HD int tile_sum(const Tile& tile, int n, const Value& value) {
    int sum = 0;
    for (int base = 0; base < n; base += tile.size()) {
        const int i = base + tile.rank();
        sum += tile.sum(i < n ? value(i) : 0);
    }
    return sum;
}

// fold(value(i)) for each i < n at which member(i) holds, in order, by every
// thread of the tile: each value read by its own thread (the reads in flight
// together rather than one after another), then handed round. Value: at most
// 32 bytes, trivially copyable.
template <class Tile, class Member, class Value, class Fold>
TETISO_HD void tile_fold(const Tile& tile, int n, const Member& member, const Value& value, const Fold& fold) {
    for (int base = 0; base < n; base += tile.size()) {
        const int i = base + tile.rank();
        const bool in = i < n && member(i);
        const auto mine = in ? value(i) : decltype(value(i)){};
        for (unsigned mask = tile.ballot(in); mask; mask &= mask - 1u) fold(tile.shfl(mine, Tile::lowest(mask)));
    }
}

// visit(i, place) for each i < n at which member(i) holds, place counting
// the members before i; stops after the first pass (of tile.size() indices)
// in which a visit returned true. Returns the members visited (all of them
// where none returned true); *stopped: whether one did.
template <class Tile, class Member, class Visit>
TETISO_HD int tile_enumerate(const Tile& tile, int n, const Member& member, const Visit& visit, bool* stopped) {
    int places = 0;
    for (int base = 0; base < n; base += tile.size()) {
        const int i = base + tile.rank();
        const bool in = i < n && member(i);
        const unsigned mask = tile.ballot(in);
        const int place = places + Tile::count(mask & ((1u << tile.rank()) - 1u));
        const bool stop = in && visit(i, place);
        places += Tile::count(mask);
        if (tile.ballot(stop)) {
            *stopped = true;
            return places;
        }
    }
    *stopped = false;
    return places;
}

} // namespace tetiso
