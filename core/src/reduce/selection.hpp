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
constexpr u64 kNoReservation = std::numeric_limits<u64>::max();
constexpr i32 kNoClaim = std::numeric_limits<i32>::max();

// What became of an operation under speculation (choose_by_reservations),
// by rank.
constexpr u8 kOutcomeUndecided = 0, kOutcomeIllegal = 1, kOutcomeChosen = 2, kOutcomeBlockedByCorner = 3;

// An operation in the reservations' window: its rank in the round's order,
// the edge and its ends (read once, when it enters).
struct WindowSlot {
    i32 rank, e, u, w;
    // -1 until computed. The corners themselves are found again when needed
    // (few operations own any): stored here, they made the window four times
    // larger, and the selection on several threads slower.
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
    // of every corner it owns; with claim_rank, also records there the
    // lowest rank that claimed each vertex.
    template <bool Flips>
    TETISO_HD void claim_around(i32 e, i32* claim_rank = nullptr, i32 rank = 0) const {
        i32 vs[4 + kMaxOwned];
        int n = touched<Flips>(e, edges.v0[e], edges.v1[e], vs);
        const int owned_n = owned<Flips>(e, vs + n);
        n += owned_n > 0 ? owned_n : 0;
        const auto mark = [&](i32 x) {
            claim(x);
            if (claim_rank) hd::atomic_min(claim_rank + x, rank);
        };
        for (int i = 0; i < n; ++i) {
            mark(vs[i]);
            for (i32 j = 0, m = fans.nn(vs[i]); j < m; ++j) mark(fans.nbr(vs[i], j));
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
    // Scratch arrays beside ops (the priorities are the round's, read only):
    // where a dry run writes its proposal.
    OpsView dry;
    template <class FreeCorners>
    TETISO_HD Verdict operator()(i32 e, const FreeCorners& free_corners) const {
        return legal(m, e, ops, owner, free_corners);
    }
    // The verdict of the tests on the round's state, its corners taken as
    // free, with nothing written that the round reads and the samples left
    // for place() (their starting bound in *deferred), in two stages: the
    // first places the collapse and runs the tests of connectivity (false:
    // illegal); the second, only after a first that passed, the rest.
    TETISO_HD bool dry_run_connectivity(i32 e) const {
        dry.kind[e] = ops.kind[e];
        dry.px[e] = ops.px[e];
        dry.py[e] = ops.py[e];
        dry.pz[e] = ops.pz[e];
        dry.survivor[e] = ops.survivor[e];
        const EdgeSlots r = slots(m, e);
        if (dry.kind[e] == kPending && !place_collapse(m, r, dry, e)) return false;
        return connectivity_allows(m, r, dry, e);
    }
    TETISO_HD Verdict dry_run_rest(i32 e, double* deferred) const {
        return legal(m, e, dry, nullptr, [](const i32*, int) { return true; }, deferred);
    }
    TETISO_HD bool samples_on() const { return m.samples.on; }
    TETISO_HD i32 leaf_samples(i32 e) const { return leaf_sample_count(m, slots(m, e)); }
    // Sample j of the leaves of dry-run collapse e.
    TETISO_HD LeafSamplePlacement place(i32 e, i32 j) const {
        return place_leaf_sample(m, slots(m, e), {dry.px[e], dry.py[e], dry.pz[e]}, j);
    }
    // What the real test of e would have written of its proposal: the dry
    // run's, with the new faces' bound where it chose e.
    TETISO_HD void adopt(i32 e, bool chosen) const {
        ops.kind[e] = dry.kind[e];
        ops.px[e] = dry.px[e];
        ops.py[e] = dry.py[e];
        ops.pz[e] = dry.pz[e];
        ops.survivor[e] = dry.survivor[e];
        if (chosen) ops.err[e] = dry.err[e];
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
    Array<i32> claimed, order;
    Array<u64> reservation;
    Array<i32> ends; // the sweep's operations' ends, in its order
    Array<WindowSlot> window, waiting;
    Array<u8> state;
    Array<i64> held; // the sizes of window and waiting (choose_by_reservations)
    // Speculation: each rank's outcome, the ranks of a list, and per vertex
    // the lowest rank of a chosen operation that claimed it.
    Array<u8> outcome;
    Array<i32> entrants, claim_rank;
    Array<i32> dry_survivors; // the ranks whose dry run passed its first stage
    // The samples of the dry runs' leaves, one item each: per rank its
    // first item and bound, per item the sample and where it goes.
    Array<i32> sample_count, sample_first, item_sample, item_triangle;
    Array<u64> worst_bits;
    i32 items = 0;
    bool speculate = !Exec::kHost;
    i32 stamp = 0;
    // Tests only: the reservations on one host thread too, with this window
    // (0: the backend's), and speculate as chosen.
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

// The rank whose items (sample_first, an exclusive scan of n + 1 entries)
// hold item.
TETISO_HD inline i32 rank_of_item(const i32* first, i32 n, i32 item) {
    i32 low = 0, high = n; // first[low] <= item < first[high]
    while (high - low > 1) {
        const i32 mid = low + (high - low) / 2;
        if (first[mid] <= item) low = mid;
        else high = mid;
    }
    return low;
}

// The counts of a round that CudaExec keeps on the device (the slots of
// Exec::count_into, filter_into).
// kTallyActive: the pieces of a batch not finished after the round.
enum TallySlot : int { kTallyEvaluated, kTallyCollapses, kTallyFlips, kTallyChanged, kTallyDrySurvivors, kTallyActive };

// Speculation's dry runs: every collapse of the round tested on its state,
// its samples placed one a thread (the tests of a collapse are a few hundred
// steps, its samples' placement as many again for each sample, which late
// rounds have dozens of a face: on the GPU one thread placing them all
// would be the round's slowest). outcome[rank]: kOutcomeUndecided where
// legal, else kOutcomeIllegal; the dry proposal's bound in dry.err.
template <class Exec, class Test>
void dry_run_all(Exec& exec, Selection<Exec>& sel, i32 n, const Test& test) {
    using Grain = typename Exec::Grain;
    const i32* order = sel.order.data();
    sel.outcome.resize(static_cast<std::size_t>(n));
    u8* outcome = sel.outcome.data();
    const bool samples = test.samples_on();
    if (samples) {
        sel.worst_bits.resize(static_cast<std::size_t>(n));
        sel.sample_count.resize(static_cast<std::size_t>(n));
    }
    u64* worst = sel.worst_bits.data();
    i32* count = sel.sample_count.data();
    // In two stages, so that the geometric tests, long and with a large
    // scratch each, run only for the collapses that pass the cheap ones,
    // side by side (on the GPU, warps of collapses that all go on).
    exec.for_each(n, [=] TETISO_HD(i64 k) {
        const bool maybe = test.dry_run_connectivity(order[k]);
        outcome[k] = maybe ? kOutcomeUndecided : kOutcomeIllegal;
        if (!samples) return;
        worst[k] = hd::bits(0.0);
        count[k] = 0;
    });
    exec.filter_into(n, [=] TETISO_HD(i64 k) { return outcome[k] == kOutcomeUndecided; }, sel.dry_survivors,
                     kTallyDrySurvivors);
    const i32* survivors = sel.dry_survivors.data();
    exec.for_each_of(exec.tally_at(kTallyDrySurvivors), n, [=] TETISO_HD(i64 j) {
        const i32 k = survivors[j], e = order[k];
        double deferred = 0.0;
        const bool legal = test.dry_run_rest(e, samples ? &deferred : nullptr) == Verdict::kLegal;
        outcome[k] = legal ? kOutcomeUndecided : kOutcomeIllegal;
        if (!samples) return;
        worst[k] = hd::bits(deferred);
        count[k] = legal ? test.leaf_samples(e) : 0;
    }, Grain::kTests);
    sel.items = 0;
    if (!samples) return;
    sel.items = exec.exclusive_scan(sel.sample_count, n, sel.sample_first);
    sel.item_sample.resize(static_cast<std::size_t>(sel.items));
    sel.item_triangle.resize(static_cast<std::size_t>(sel.items));
    const i32* first = sel.sample_first.data();
    i32 *item_sample = sel.item_sample.data(), *item_triangle = sel.item_triangle.data();
    exec.for_each(sel.items, [=] TETISO_HD(i64 item) {
        const i32 k = rank_of_item(first, n, static_cast<i32>(item));
        const LeafSamplePlacement placed = test.place(order[k], static_cast<i32>(item) - first[k]);
        item_sample[item] = placed.sample;
        item_triangle[item] = placed.triangle;
        // Bounds are not negative: their bits order as they do.
        if (placed.triangle < 0) hd::atomic_store(outcome + k, kOutcomeIllegal);
        else hd::atomic_max(worst + k, hd::bits(placed.bound));
    }, Grain::kTests);
    exec.for_each(n, [=] TETISO_HD(i64 k) {
        if (outcome[k] == kOutcomeUndecided) test.dry.err[order[k]] = static_cast<float>(hd::from_bits(worst[k]));
    });
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
void choose_by_reservations(Exec& exec, Selection<Exec>& sel, const SelectView& v, i32 n, i32 nv, u8* chosen,
                            u8* refused, const Test& test) {
    using Grain = typename Exec::Grain;
    const bool speculate = sel.speculate && !Flips;
    exec.assign(sel.reservation, nv, kNoReservation);
    u64* reservation = sel.reservation.data();
    const i32* order = sel.order.data();
    // The ranks that take part, ascending: all, or the legal ones.
    i64 entrants = n;
    const i32* entrant_rank = nullptr;
    u8* outcome = nullptr;
    i32* claim_rank = nullptr;
    if (speculate) {
        if constexpr (!Flips) dry_run_all(exec, sel, n, test);
        outcome = sel.outcome.data();
        entrants = exec.filter(n, [=] TETISO_HD(i64 k) { return outcome[k] == kOutcomeUndecided; }, sel.entrants);
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
    while (next < entrants || held > 0) {
        if (next < entrants && held < width) {
            const i64 entering = std::min<i64>(width - held, entrants - next);
            WindowSlot* at = (current == 0 ? sel.window.data() : sel.waiting.data()) + held;
            const i32 first = static_cast<i32>(next);
            exec.for_each(entering, [=] TETISO_HD(i64 k) {
                const i32 rank = entrant_rank ? entrant_rank[first + k] : first + static_cast<i32>(k);
                at[k] = {rank, order[rank], -1, -1, -1};
            });
            next += entering;
            held += entering;
            exec.set(sel.held, current, held);
        }
        // While operations still wait to enter, the host must know the
        // window's size after each step; once all are in, the backend may run
        // several steps before it looks.
        const int steps = next < entrants ? 1 : exec.steps_between_checks();
        for (int s = 0; s < steps; ++s) {
            ++sel.steps;
            ++step;
            const u64 stamp = static_cast<u64>(~step) << 32;
            WindowSlot* window = current == 0 ? sel.window.data() : sel.waiting.data();
            WindowSlot* waiting = current == 0 ? sel.waiting.data() : sel.window.data();
            i64* size = sel.held.data() + current;
            i64* waiting_size = sel.held.data() + (1 - current);
            u8* state = sel.state.data();
            // Index 0 runs even in an empty window: it empties the waiting
            // list, last read (as the window) by the previous step's loops.
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) {
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
            }, Grain::kWindow, 1);
            exec.for_each_of(size, capacity, [=] TETISO_HD(i64 wi) {
                const u8 st = state[wi];
                if (!st) return;
                const WindowSlot& slot = window[wi];
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
            }, Grain::kTests);
            current = 1 - current;
        }
        held = exec.get(sel.held, current);
    }
    if constexpr (!Flips) {
        if (!speculate) return;
        // What the sweep's tests wrote, as the dry runs found it: the Φ and
        // position of every operation it tested, a refusal for the illegal
        // ones, the bound and the samples' new owners for the chosen ones.
        exec.for_each(n, [=] TETISO_HD(i64 k) {
            const i32 rank = static_cast<i32>(k);
            const i32 e = order[rank];
            const u8 what = outcome[rank];
            if (what == kOutcomeIllegal) {
                // The sweep skips it where an earlier choice claimed one of its ends.
                i32 vs[4];
                const int count = v.touched<Flips>(e, v.edges.v0[e], v.edges.v1[e], vs);
                for (int j = 0; j < count; ++j)
                    if (claim_rank[vs[j]] < rank) return;
                refused[e] = 1;
            } else if (what != kOutcomeChosen && what != kOutcomeBlockedByCorner) {
                return; // blocked: never tested
            }
            test.adopt(e, what == kOutcomeChosen);
        });
        if (sel.items > 0 && test.samples_on()) {
            const i32* first = sel.sample_first.data();
            const i32 *item_sample = sel.item_sample.data(), *item_triangle = sel.item_triangle.data();
            i32* owner = test.owner;
            exec.for_each(sel.items, [=] TETISO_HD(i64 item) {
                if (outcome[rank_of_item(first, n, static_cast<i32>(item))] == kOutcomeChosen)
                    owner[item_sample[item]] = item_triangle[item];
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
