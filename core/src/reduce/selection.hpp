// The independent set of a round (paper: "the length of the path between any
// two nodes belonging to any two different edges from G*1 should be not less
// than two"). Operation o touches the vertex set S(o) (the two ends of a
// collapse; the ends and both opposite vertices of a flip); o and o' conflict
// when S(o') lies within path length 1 of S(o). The paper's choice is
// sequential: operations in priority order, each taken when no operation
// taken before conflicts with it and it is legal. Priorities are fixed within
// a round and legality does not depend on what else is chosen, so that set is
// a function of the round alone; ties in priority fall to the vertex keys,
// never to thread or order. Two chosen operations are at path length >= 2, so
// their leaves share no face and the tests of each stay valid whatever the
// others do; an illegal operation never blocks its neighbours.
//
// On one host thread the choice runs as such (choose_in_order); otherwise
// deterministic reservations (choose_by_reservations) make exactly the same
// choices with the tests in parallel, on any backend and for any window
// width, so the set is the same for every thread count and device. The
// collapses are chosen first; the flips, the lowest class, after them, for
// the edges the collapses left clear.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "../hd.hpp"
#include "legality.hpp"
#include "round_view.hpp"

namespace tetiso::reduction {

// chosen[e]: 1 for a chosen operation.
constexpr u8 kChosen = 1;

// The reservations' window: at least kReservationWindowMin operations, or
// 1/kReservationSteps of the round's on the host, so a round takes some tens
// of steps of three parallel loops; with kReservationMin operations or fewer
// the host sweeps on the calling thread. The device takes a window of every
// operation (exec_cuda.cuh): the choice does not depend on the width.
constexpr i64 kReservationWindowMin = 512;
constexpr i64 kReservationSteps = 32;
constexpr i64 kReservationMin = 256;
constexpr i32 kNoReservation = std::numeric_limits<i32>::max();

// An operation in the reservations' window: its rank in the round's order,
// the edge and its ends (read once, when it enters).
struct WindowSlot {
    i32 rank, e, u, w;
    // -1 until computed. The corners themselves are found again when needed
    // (few operations own any): stored here, they made the window four times
    // larger, and the 8-thread selection 1.4x slower.
    i32 owned_count;
};

// What the selection reads of the round, and its claims: claimed[v] ==
// stamp means v lies within path length 1 of a chosen operation.
struct SelectView {
    FansView fans;
    EdgesView edges;
    const Cone* cones;
    i32* claimed;
    i32 stamp;

    TETISO_HD void claim(i32 v) const { hd::atomic_store(claimed + v, stamp); }
    TETISO_HD bool free(i32 v) const { return claimed[v] != stamp; }

    // The vertices operation e touches: its ends, and for a flip both
    // opposite vertices.
    template <bool Flips>
    TETISO_HD int touched(i32 e, i32 u, i32 w, i32* out) const {
        out[0] = u;
        out[1] = w;
        if (!Flips) return 2;
        const EdgeFaces f = edges.faces(fans, e);
        out[2] = f.c;
        out[3] = f.d;
        return 4;
    }
    // A collapse's owned corners (owned_corners); flips own none (they are
    // dropped where a cone does not decide).
    template <bool Flips>
    TETISO_HD int owned(i32 e, i32* out) const {
        if (Flips) return 0;
        const i32 u = edges.v0[e], w = edges.v1[e];
        const bool border_edge = fans.border[u] && fans.border[w] && edges.border(fans, e);
        return owned_corners(fans, cones, u, w, border_edge, out);
    }
    TETISO_HD bool all_free(const i32* vs, int n) const {
        for (int k = 0; k < n; ++k)
            if (!free(vs[k])) return false;
        return true;
    }
    // Claims the closed 1-ring of every vertex chosen operation e touches and
    // of every corner it owns.
    template <bool Flips>
    TETISO_HD void claim_around(i32 e) const {
        i32 vs[4 + kMaxOwned];
        int n = touched<Flips>(e, edges.v0[e], edges.v1[e], vs);
        const int owned_n = owned<Flips>(e, vs + n);
        n += owned_n > 0 ? owned_n : 0;
        for (int i = 0; i < n; ++i) {
            claim(vs[i]);
            for (i32 j = 0, m = fans.nn(vs[i]); j < m; ++j) claim(fans.nbr(vs[i], j));
        }
    }
    // A window operation's touched vertices, then its owned corners.
    template <bool Flips, class F>
    TETISO_HD void for_each_footprint(const WindowSlot& slot, const F& f) const {
        i32 vs[4];
        const int n = touched<Flips>(slot.e, slot.u, slot.w, vs);
        for (int k = 0; k < n; ++k) f(vs[k]);
        if (slot.owned_count <= 0) return;
        i32 owned_vs[kMaxOwned];
        const int m = owned<Flips>(slot.e, owned_vs);
        for (int k = 0; k < m; ++k) f(owned_vs[k]);
    }
};

// The tests the selection asks: a collapse's legality (legality.hpp, which
// also moves the samples of one it finds legal), or none for a flip, fully
// tested when proposed.
struct CollapseTest {
    RoundView m;
    OpsView ops;
    i32* owner; // the samples' owners; null without samples
    template <class FreeCorners>
    TETISO_HD Verdict operator()(i32 e, const FreeCorners& free_corners) const {
        return legal(m, e, ops, owner, free_corners);
    }
};
struct FlipTest {
    template <class FreeCorners>
    TETISO_HD Verdict operator()(i32, const FreeCorners&) const {
        return Verdict::kLegal;
    }
};

template <class Exec>
struct Selection {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<i32> claimed, order, reservation;
    Array<i32> ends; // the sweep's operations' ends, in its order
    Array<WindowSlot> window, waiting;
    Array<u8> state;
    Array<i64> held; // the sizes of window and waiting (choose_by_reservations)
    i32 stamp = 0;
    // Tests only: the reservations on one host thread too, with this window
    // (0: the backend's).
    bool always_reservations = false;
    i64 window_override = 0;
    std::size_t steps = 0; // reservation steps since the counter was reset
};

// The sequential greedy choice on the host: operations in descending
// priority, each taken when it is clear of those taken before and legal.
// The sweep visits the surface in random order, and most operations are
// dropped at the first look, their ends claimed: that look was a chain of
// two cache misses (the edge's ends, then their claims) that nothing could
// overlap. The ends are gathered first, in a loop whose loads are
// independent, and the claims are prefetched a few operations ahead.
template <bool Flips, class Exec, class Test>
void choose_in_order(Selection<Exec>& sel, const SelectView& v, i32 n, u8* chosen, u8* refused, const Test& test) {
    const i32* order = sel.order.data();
    auto& ends = sel.ends;
    ends.resize(2 * static_cast<std::size_t>(n));
    for (i32 k = 0; k < n; ++k) {
        ends[2 * static_cast<std::size_t>(k)] = v.edges.v0[order[k]];
        ends[2 * static_cast<std::size_t>(k) + 1] = v.edges.v1[order[k]];
    }
    constexpr i32 kAhead = 16;
    for (i32 k = 0; k < n; ++k) {
        if (k + kAhead < n) {
            __builtin_prefetch(v.claimed + ends[2 * static_cast<std::size_t>(k + kAhead)]);
            __builtin_prefetch(v.claimed + ends[2 * static_cast<std::size_t>(k + kAhead) + 1]);
        }
        const i32 e = order[k];
        i32 vs[4];
        const int nt = v.touched<Flips>(e, ends[2 * static_cast<std::size_t>(k)], ends[2 * static_cast<std::size_t>(k) + 1], vs);
        if (!v.all_free(vs, nt)) continue;
        const Verdict verdict = test(e, [&](const i32* owned, int count) { return count >= 0 && v.all_free(owned, count); });
        if (verdict == Verdict::kIllegal) refused[e] = 1;
        if (verdict != Verdict::kLegal) continue;
        chosen[e] = kChosen;
        v.claim_around<Flips>(e);
    }
}

// The same sequential greedy choice by deterministic reservations:
// operations enter a window in priority order; in each step every window
// operation not yet blocked by a chosen one reserves its footprint with its
// rank (an atomic minimum), and one that finds no earlier rank anywhere
// within path length 1 of its footprint has no undecided earlier operation in
// conflict with it. Its turn in the sequential order has come: it is tested,
// and chosen if legal, exactly as the sweep would; those decided in one step
// are pairwise clear of each other. The others wait for the next step, ahead
// of the operations entering behind them. Each operation is tested at most
// once, the tests run in parallel, and the set is the sweep's for any thread
// count, window width and backend. On the 16-core device this chose
// 1.16-1.25x faster than the passes it replaced (local maxima of the
// priority, with a bulk test of what was left after 16 passes) at 4 and 8
// threads on the N = 100 paper surface.
template <bool Flips, class Exec, class Test>
void choose_by_reservations(Exec& exec, Selection<Exec>& sel, const SelectView& v, i32 n, i32 nv, u8* chosen,
                            u8* refused, const Test& test) {
    using Grain = typename Exec::Grain;
    exec.assign(sel.reservation, nv, kNoReservation);
    i32* reservation = sel.reservation.data();
    const i64 width = sel.window_override > 0 ? sel.window_override : exec.reservation_window(n);
    const i64 capacity = std::min<i64>(width, n);
    sel.window.resize(static_cast<std::size_t>(capacity));
    sel.waiting.resize(static_cast<std::size_t>(capacity));
    sel.state.resize(static_cast<std::size_t>(capacity));
    // The window's size lives where its loops run (on the device, so that
    // several steps go by without the host reading it): held[0] the
    // window's, held[1] the waiting list's, swapped with them each step.
    exec.assign(sel.held, 2, i64{0});
    // kTestOnly: blocked by a corner it would own, claimed by an earlier
    // choice (or owning too many); tested only to tell refused from blocked,
    // as the sweep does.
    constexpr u8 kReserved = 1, kDecided = 2, kTaken = 4, kTestOnly = 8;
    i64 next = 0, held = 0; // held: the window's size, as the host last read it
    int current = 0;        // which of held[0], held[1] is the window's
    while (next < n || held > 0) {
        if (next < n && held < width) {
            const i64 entering = std::min<i64>(width - held, n - next);
            WindowSlot* window = current == 0 ? sel.window.data() : sel.waiting.data();
            WindowSlot* at = window + held;
            const i32* order = sel.order.data() + next;
            const i32 first_rank = static_cast<i32>(next);
            exec.for_each(entering, [=] TETISO_HD(i64 k) {
                at[k] = {first_rank + static_cast<i32>(k), order[k], -1, -1, -1};
            });
            next += entering;
            held += entering;
            exec.set(sel.held, current, held);
        }
        // While operations still wait to enter, the host must know the
        // window's size after each step; once all are in, the backend may run
        // several steps before it looks.
        const int steps = next < n ? 1 : exec.steps_between_checks();
        for (int step = 0; step < steps; ++step) {
            ++sel.steps;
            WindowSlot* window = current == 0 ? sel.window.data() : sel.waiting.data();
            WindowSlot* waiting = current == 0 ? sel.waiting.data() : sel.window.data();
            i64* size = sel.held.data() + current;
            i64* waiting_size = sel.held.data() + (1 - current);
            u8* state = sel.state.data();
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) {
                WindowSlot& slot = window[wi];
                state[wi] = 0;
                if (slot.u < 0) {
                    slot.u = v.edges.v0[slot.e];
                    slot.w = v.edges.v1[slot.e];
                }
                i32 vs[4];
                if (!v.all_free(vs, v.touched<Flips>(slot.e, slot.u, slot.w, vs))) return; // blocked: decided for good
                i32 owned[kMaxOwned];
                slot.owned_count = v.owned<Flips>(slot.e, owned);
                if (slot.owned_count < 0 || !v.all_free(owned, slot.owned_count)) {
                    state[wi] = kTestOnly;
                    return;
                }
                state[wi] = kReserved;
                v.for_each_footprint<Flips>(slot, [&](i32 x) { hd::atomic_min(reservation + x, slot.rank); });
            }, Grain::kWindow);
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) {
                u8& st = state[wi];
                if (!st) return;
                const WindowSlot& slot = window[wi];
                const bool test_only = st == kTestOnly;
                if (!test_only) {
                    // Its own vertices first: a shared end is the commonest conflict.
                    bool first = true;
                    v.for_each_footprint<Flips>(slot, [&](i32 x) { first = first && reservation[x] == slot.rank; });
                    if (!first) return;
                    bool nearby = false; // an earlier operation nearby is undecided
                    v.for_each_footprint<Flips>(slot, [&](i32 x) {
                        for (i32 j = 0, m = v.fans.nn(x); j < m && !nearby; ++j)
                            nearby = reservation[v.fans.nbr(x, j)] < slot.rank;
                    });
                    if (nearby) return;
                    st |= kDecided;
                }
                // A decided operation's owned corners were clear when it
                // reserved them, and only an earlier operation, all decided
                // now, could have claimed them; a test-only one's were
                // claimed. One call of the test either way (on the GPU each
                // inlined copy of it costs every thread its stack frame).
                const Verdict verdict = test(slot.e, [=](const i32*, int) { return !test_only; });
                if (test_only) {
                    if (verdict == Verdict::kIllegal) refused[slot.e] = 1;
                    return;
                }
                if (verdict != Verdict::kLegal) {
                    refused[slot.e] = 1;
                    return;
                }
                chosen[slot.e] = kChosen;
                st |= kTaken;
            }, Grain::kTests);
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) {
                const u8 st = state[wi];
                if (!st || st == kTestOnly) return;
                const WindowSlot& slot = window[wi];
                v.for_each_footprint<Flips>(slot, [&](i32 x) { hd::atomic_store(reservation + x, kNoReservation); });
                if (st & kTaken) v.claim_around<Flips>(slot.e);
            }, Grain::kWindow);
            // The waiting go on to the next step; their order in the window
            // does not matter, each knows its rank.
            exec.compact(window, size, capacity, [=] TETISO_HD(i64 wi) { return state[wi] == kReserved; }, waiting,
                         waiting_size);
            current = 1 - current;
        }
        held = exec.get(sel.held, current);
    }
}

// Chooses among `list` (n edges with an operation, ascending): sets chosen[e]
// for those chosen, refused[e] for those found illegal. Flips: the round's
// flips, after the collapses (their claims stand).
template <bool Flips, class Exec, class Test>
void choose(Exec& exec, Selection<Exec>& sel, SelectView v, const typename Exec::template Array<i32>& list, i32 n,
            i32 nv, const u32* priority, u8* chosen, u8* refused, const Test& test) {
    if (!Flips) ++sel.stamp;
    v.stamp = sel.stamp;
    exec.order_by_priority(list, n, priority, v.edges.v0, v.edges.v1, sel.order);
    if constexpr (Exec::kHost) {
        if (!sel.always_reservations && (exec.threads <= 1 || n <= kReservationMin || Flips)) {
            choose_in_order<Flips>(sel, v, n, chosen, refused, test);
            return;
        }
    }
    choose_by_reservations<Flips>(exec, sel, v, n, nv, chosen, refused, test);
}

// After the collapses are chosen: stamps the closed neighbourhoods of those
// chosen afresh, so that what the flips may still take is what their claims
// leave clear.
template <class Exec>
void claim_chosen(Exec& exec, Selection<Exec>& sel, SelectView v, const typename Exec::template Array<i32>& candidates,
                  i32 n, const u8* chosen) {
    v.stamp = ++sel.stamp;
    const i32* list = candidates.data();
    exec.for_each(n, [=] TETISO_HD(i64 k) {
        const i32 e = list[k];
        if (chosen[e]) v.claim_around<false>(e);
    });
}

} // namespace tetiso::reduction
