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

#include "../hd.hpp"
#include "dry_run.hpp"
#include "selection_state.hpp"

namespace tetiso::reduction {

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

// One run of the reservation steps over the round's operations (all, or
// with speculation those not found illegal), as choose_by_reservations
// describes: chosen[e] for those chosen and, with speculation, each rank's
// outcome and the lowest rank that claimed each vertex (sel.claim_rank).
template <bool Flips, class Exec, class Test>
void run_reservation_steps(Exec& exec, Selection<Exec>& sel, const SelectView& v, i32 n, i32 nv, u8* chosen,
                           u8* refused, const Test& test, bool speculate) {
    using Grain = typename Exec::Grain;
    const i32* order = sel.order.data();
    u8* outcome = speculate ? sel.outcome.data() : nullptr;
    exec.assign(sel.reservation, nv, kNoReservation);
    u64* reservation = sel.reservation.data();
    // The ranks that take part, ascending: all, or the legal ones.
    i64 entrants = n;
    const i32* entrant_rank = nullptr;
    i32* claim_rank = nullptr;
    // On the device, with a window of every entrant that the device steps
    // through alone, their number is never needed on the host: they enter,
    // and the steps run, up to the count the device keeps (entrants is then
    // n, the most there can be).
    bool entrants_on_device = false;
    if (speculate) {
        const auto legal = [=] TETISO_HD(i64 k) { return outcome[k] == kOutcomeUndecided; };
        if constexpr (!Exec::kHost) entrants_on_device = sel.window_override == 0 && exec.steps_on_device(n);
        if (entrants_on_device) exec.filter_into(n, legal, sel.entrants, kTallyEntrants);
        else entrants = exec.filter(n, legal, sel.entrants);
        entrant_rank = sel.entrants.data();
        exec.assign(sel.claim_rank, nv, kNoClaim);
        claim_rank = sel.claim_rank.data();
    }
    const i64 width = sel.window_override > 0 ? sel.window_override : exec.reservation_window(entrants);
    const i64 capacity = std::max<i64>(1, std::min<i64>(width, entrants));
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
    constexpr u8 kReserved = 1, kTestOnly = 2;
    i64 next = 0, held = 0; // held: the window's size, as the host last read it
    int current = 0;        // which of held[0], held[1] is the window's
    u32 step = 0;
    WindowSlot* const list0 = sel.window.data();
    WindowSlot* const list1 = sel.waiting.data();
    i64* const sizes = sel.held.data();
    u8* const state = sel.state.data();
    // A step's two passes, over the window (list `current`, its size in
    // sizes[current]); the waiting list is the other one. Index 0 of the
    // first runs even in an empty window: it empties the waiting list, last
    // read (as the window) by the previous step's passes.
    const auto reserve = [=] TETISO_HD(i64 wi, u32 at_step, int at) {
        WindowSlot* window = at == 0 ? list0 : list1;
        const i64* size = sizes + at;
        i64* waiting_size = sizes + (1 - at);
        const u64 stamp = static_cast<u64>(~at_step) << 32;
        if (wi == 0) *waiting_size = 0;
        if (wi >= *size) return;
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
        const u64 key = stamp | static_cast<u32>(slot.rank);
        v.for_each_footprint<Flips>(slot, [&](i32 x) { hd::atomic_min(reservation + x, key); });
    };
    const auto decide = [=] TETISO_HD(i64 wi, u32 at_step, int at) {
        const u8 st = state[wi];
        if (!st) return;
        const WindowSlot& slot = (at == 0 ? list0 : list1)[wi];
        WindowSlot* waiting = at == 0 ? list1 : list0;
        i64* waiting_size = sizes + (1 - at);
        const u64 stamp = static_cast<u64>(~at_step) << 32;
        const bool test_only = st == kTestOnly;
        if (!test_only) {
            // An earlier rank reserved this step is below the key; an
            // older step's reservation is above it. Its own vertices
            // first: a shared end is the commonest conflict.
            const u64 key = stamp | static_cast<u32>(slot.rank);
            bool first = true;
            v.for_each_footprint<Flips>(slot, [&](i32 x) { first = first && reservation[x] == key; });
            bool nearby = false; // an earlier operation nearby is undecided
            if (first)
                v.for_each_footprint<Flips>(slot, [&](i32 x) {
                    for (i32 j = 0, m = v.fans.nn(x); j < m && !nearby; ++j)
                        nearby = reservation[v.fans.nbr(x, j)] < key;
                });
            if (!first || nearby) {
                waiting[hd::atomic_add(waiting_size, i64{1})] = slot;
                return;
            }
        }
        if (speculate) { // tested after the steps
            if (test_only) {
                outcome[slot.rank] = kOutcomeBlockedByCorner;
                return;
            }
            outcome[slot.rank] = kOutcomeChosen;
            chosen[slot.e] = kChosen;
            v.claim_around<Flips>(slot.e, claim_rank, slot.rank);
            return;
        }
        // The device always speculates for collapses: the test is not
        // compiled into its steps, whose every thread would otherwise
        // reserve the test's registers and stack. (The casts capture
        // what only that branch uses: CUDA's extended lambdas may not
        // capture inside an if constexpr.)
        (void)test;
        (void)refused;
        if constexpr (Exec::kHost || Flips) {
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
        v.claim_around<Flips>(slot.e, nullptr, 0);
        }
    };
    if constexpr (!Exec::kHost) {
        if (entrants_on_device) {
            const i64* count = exec.tally_at(kTallyEntrants);
            exec.for_each_of(count, n, [=] TETISO_HD(i64 k) {
                if (k == 0) sizes[0] = *count;
                if (k >= *count) return;
                const i32 rank = entrant_rank[k];
                list0[k] = {rank, order[rank], -1, -1, -1};
            }, Grain::kCheap, 1);
            if (exec.run_steps(sizes, 0, 0, capacity, reserve, decide, kTallyCollapseSteps)) {
                sel.device_steps |= 1;
                next = held = entrants = 0;
            } else {
                next = held = entrants = exec.read_tally()[kTallyEntrants];
            }
        }
    }
    while (next < entrants || held > 0) {
        if (next < entrants && held < width) {
            const i64 entering = std::min<i64>(width - held, entrants - next);
            WindowSlot* at = (current == 0 ? list0 : list1) + held;
            const i32 first = static_cast<i32>(next);
            exec.for_each(entering, [=] TETISO_HD(i64 k) {
                const i32 rank = entrant_rank ? entrant_rank[first + k] : first + static_cast<i32>(k);
                at[k] = {rank, order[rank], -1, -1, -1};
            });
            next += entering;
            held += entering;
            exec.set(sel.held, current, held);
        }
        // Once all operations are in, the device runs the remaining steps
        // without the host (steps that find the window empty change nothing,
        // so ending there is ending where the host would have).
        if constexpr (!Exec::kHost) {
            const int slot = Flips ? kTallyFlipSteps : kTallyCollapseSteps;
            if (next == entrants && exec.run_steps(sizes, current, step, capacity, reserve, decide, slot)) {
                sel.device_steps |= 1 << (Flips ? 1 : 0);
                break;
            }
        }
        // While operations still wait to enter, the host must know the
        // window's size after each step; once all are in, the backend may run
        // several steps before it looks.
        const int steps = next < entrants ? 1 : exec.steps_between_checks();
        for (int s = 0; s < steps; ++s) {
            ++sel.steps;
            ++step;
            const u32 at_step = step;
            const int at = current;
            const i64* size = sizes + current;
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) { reserve(wi, at_step, at); }, Grain::kWindow, 1);
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) { decide(wi, at_step, at); }, Grain::kTests);
            current = 1 - current;
        }
        held = exec.get(sel.held, current);
    }
}

// The same sequential greedy choice by deterministic reservations:
// operations enter a window in priority order; in each step every window
// operation not yet blocked by a chosen one reserves its footprint with its
// rank (an atomic minimum), and one that finds no earlier rank anywhere
// within path length 1 of its footprint has no undecided earlier operation in
// conflict with it. Its turn in the sequential order has come: it is tested,
// and chosen if legal, exactly as the sweep would; those decided in one step
// are pairwise clear of each other. The others wait for the next step. Each
// operation is tested at most once, the tests run in parallel, and the set
// is the sweep's for any thread count, window width and backend.
//
// A reservation is stamped with its step (the step in the high word, counted
// down, so that a reservation of this step is below every older one): the
// reservations never need clearing, and a step is two parallel loops, one to
// reserve and one to decide and claim, with no pass of the host between
// them.
//
// Speculation (sel.speculate, the device's choice): every operation is
// tested first, all at once, on the round's state and writing nothing the
// round reads (test.dry_run). An operation found illegal then never enters
// the window: it could block no one, so no one waits for it, and the chains
// of waiting, which the steps follow one link a step, are those of the legal
// operations alone (late rounds, where most candidates are illegal, take
// several times fewer steps). What the sweep does with each operation
// is then settled after the steps, from the ranks that claimed each vertex:
// an illegal one whose ends no earlier choice claimed is refused (and its Φ
// written, as the sweep's test writes it), and the chosen ones are tested
// for real last, moving their samples; an operation that the sweep tests
// finds its leaves as the round left them, since a chosen operation whose
// leaves share a face with it would have blocked it, so the verdict is the
// dry run's.
template <bool Flips, class Exec, class Test>
void choose_by_reservations(Exec& exec, Selection<Exec>& sel, const SelectView& view, const i32* list, i32 n, i32 nv,
                            u8* chosen, u8* refused, const Test& test) {
    const bool speculate = sel.speculate && !Flips;
    const i32* order = sel.order.data();
    u8* outcome = nullptr;
    // Optimistic placement (PlacementPasses): the samples of a collapse are
    // placed only once the steps decide it.
    bool samples = false;
    if constexpr (!Flips) samples = test.samples_on();
    PlacementPasses<Exec> placement(sel, n, speculate && samples && n >= sel.optimistic_min && !sel.optimism_spent);
    if (speculate) {
        if constexpr (!Flips) dry_run_all(exec, sel, list, n, view.edges.count, test, !placement.optimistic);
        outcome = sel.outcome.data();
    }
    for (int pass = 0;; ++pass) {
        SelectView v = view;
        if (pass > 0) {
            // Only the illegal ones found so far keep their outcome.
            v.stamp = ++sel.stamp;
            exec.for_each(n, [=] TETISO_HD(i64 k) {
                if (outcome[k] != kOutcomeIllegal) outcome[k] = kOutcomeUndecided;
                chosen[order[k]] = 0;
            });
        }
        run_reservation_steps<Flips>(exec, sel, v, n, nv, chosen, refused, test, speculate);
        if constexpr (Flips) break;
        else if (!placement.verify(exec, test, chosen)) break;
    }
    if constexpr (!Flips) {
        if (!speculate) return;
        i32* claim_rank = sel.claim_rank.data();
        const u64* worst = sel.worst_bits.data();
        // What the sweep's tests wrote, as the dry runs found it: the Φ and
        // position of every operation it tested, a refusal for the illegal
        // ones, the bound and the samples' new owners for the chosen ones
        // (in the dry runs' edge order, for the caches).
        const i32* by_edge = sel.by_edge.data();
        exec.for_each(n, [=] TETISO_HD(i64 at) {
            const i32 rank = by_edge[at], e = list[at];
            const u8 what = outcome[rank];
            if (what == kOutcomeIllegal) {
                // The sweep skips it where an earlier choice claimed one of its ends.
                i32 vs[4];
                const int count = view.touched<Flips>(e, view.edges.v0[e], view.edges.v1[e], vs);
                for (int j = 0; j < count; ++j)
                    if (claim_rank[vs[j]] < rank) return;
                refused[e] = 1;
            } else if (what != kOutcomeChosen && what != kOutcomeBlockedByCorner) {
                return; // blocked: never tested
            }
            if (what == kOutcomeChosen && samples) test.dry.err[e] = static_cast<float>(hd::from_bits(worst[rank]));
            test.adopt(e, what == kOutcomeChosen);
        });
        if (samples)
            for (int list = 0; list < placement.lists; ++list) {
                const SampleItems<Exec>* items = &sel.placed_items[static_cast<std::size_t>(list)];
                if (items->count == 0) continue;
                const i32 *item_rank = items->rank.data(), *item_sample = items->sample.data(),
                          *item_triangle = items->triangle.data();
                i32* owner = test.owner;
                exec.for_each(items->count, [=] TETISO_HD(i64 item) {
                    if (outcome[item_rank[item]] == kOutcomeChosen) owner[item_sample[item]] = item_triangle[item];
                });
            }
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
    choose_by_reservations<Flips>(exec, sel, v, list.data(), n, nv, chosen, refused, test);
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
