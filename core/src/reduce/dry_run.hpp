// Speculation's dry runs (selection.hpp, choose_by_reservations): every
// collapse of a round tested at once on the round's state, writing nothing
// the round reads.
#pragma once

#include "../hd.hpp"
#include "selection_state.hpp"

namespace tetiso::reduction {

// The groups of dry_run_all's survivors by leaf faces: one per count below
// it, the rest together.
constexpr i32 kFanGroups = 32;

// The samples of some of the dry runs' survivors, placed one a thread (the
// tests of a collapse are a few hundred steps, its samples' placement as
// many again for each sample, which late rounds have dozens of a face: on
// the GPU one thread placing them all would be the round's slowest): those
// with a sample count (sel.sample_count, by position in sel.by_edge, 0 for
// every other), listed in `items`. Raises sel.worst_bits[rank] to each
// sample's bound, and makes a collapse illegal where one of its samples
// finds no face. The items follow the dry runs' order (by_edge), so that
// neighbouring threads read neighbouring faces.
template <class Exec, class Test>
void place_listed_samples(Exec& exec, Selection<Exec>& sel, SampleItems<Exec>& items, i32 n, const Test& test) {
    const i32* order = sel.order.data();
    const i32* by_edge = sel.by_edge.data();
    const i32* survivors = sel.dry_survivors.data();
    const i32* count = sel.sample_count.data();
    u8* outcome = sel.outcome.data();
    u64* worst = sel.worst_bits.data();
    items.count = exec.exclusive_scan(sel.sample_count, n, items.first);
    for (auto* a : {&items.rank, &items.sample, &items.triangle}) a->resize(static_cast<std::size_t>(items.count));
    const i32* first = items.first.data();
    i32 *item_rank = items.rank.data(), *item_sample = items.sample.data(), *item_triangle = items.triangle.data();
    // Each collapse lists its samples, so that a sample's thread finds its
    // collapse and its face in one read each, rather than by a binary
    // search over the ranks and a walk of the leaves.
    exec.for_each_of(exec.tally_at(kTallyDrySurvivors), n, [=] TETISO_HD(i64 j) {
        const i32 at = survivors[j], k = by_edge[at];
        if (count[at] == 0) return;
        i32 item = first[at];
        test.for_each_sample(order[k], [&](i32 sample, i32 own_slot) {
            item_rank[item] = k;
            item_sample[item] = sample;
            item_triangle[item] = own_slot;
            ++item;
        });
    }, Exec::Grain::kTests);
    // Each sample on the face that replaces its own where that keeps it;
    // the others, listed, on the nearest face: a warp's threads then all
    // measure one face, or all loop over the leaves. (Not Grain::kTests:
    // held to the tests' registers, the device's kernels spilled the
    // distances to local memory.)
    constexpr i32 kFar = -2;
    exec.for_each(items.count, [=] TETISO_HD(i64 item) {
        const i32 k = item_rank[item];
        LeafSamplePlacement placed;
        if (!test.place_on_own(order[k], item_sample[item], item_triangle[item], placed)) {
            item_triangle[item] = kFar;
            return;
        }
        item_triangle[item] = placed.triangle;
        // Bounds are not negative: their bits order as they do.
        hd::atomic_max(worst + k, hd::bits(placed.bound));
    });
    exec.filter_into(items.count, [=] TETISO_HD(i64 item) { return item_triangle[item] == kFar; }, items.far,
                     kTallyFarSamples);
    const i32* far_items = items.far.data();
    exec.for_each_of(exec.tally_at(kTallyFarSamples), items.count, [=] TETISO_HD(i64 j) {
        const i32 item = far_items[j], k = item_rank[item];
        const LeafSamplePlacement placed = test.place_on_nearest(order[k], item_sample[item]);
        item_triangle[item] = placed.triangle;
        if (placed.triangle < 0) hd::atomic_store(outcome + k, kOutcomeIllegal);
        else hd::atomic_max(worst + k, hd::bits(placed.bound));
    });
}

// Speculation's dry runs: every collapse of the round tested on its state.
// outcome[rank]: kOutcomeUndecided where legal, else kOutcomeIllegal. With
// place_samples false, the samples are left for PlacementPasses, and a
// collapse undecided here may still be refused by them. `candidates`: the
// round's n collapses by ascending edge (sel.order is the same by rank), ne
// the round's edges.
template <class Exec, class Test>
void dry_run_all(Exec& exec, Selection<Exec>& sel, const i32* candidates, i32 n, i32 ne, const Test& test,
                 bool place_samples) {
    const i32* order = sel.order.data();
    // The tests run in edge order, not in rank order: edges are grouped by
    // their first end and vertices lie in key order, so a warp's collapses
    // then share fans, faces and positions in the caches. In rank (priority)
    // order every collapse of a warp lies elsewhere on the surface, and each
    // of its loads is a miss of its own (Nsight Compute: the first stage read
    // 2.3 KB of DRAM per collapse). Each rank's verdict is the same in any
    // order.
    sel.rank_of.resize(static_cast<std::size_t>(ne));
    sel.by_edge.resize(static_cast<std::size_t>(n));
    i32* rank_of = sel.rank_of.data();
    i32* by_edge = sel.by_edge.data();
    exec.for_each(n, [=] TETISO_HD(i64 k) { rank_of[order[k]] = static_cast<i32>(k); });
    exec.for_each(n, [=] TETISO_HD(i64 at) { by_edge[at] = rank_of[candidates[at]]; });
    sel.outcome.resize(static_cast<std::size_t>(n));
    u8* outcome = sel.outcome.data();
    const bool samples = test.samples_on();
    if (samples) {
        sel.worst_bits.resize(static_cast<std::size_t>(n));
        sel.sample_count.resize(static_cast<std::size_t>(n));
        if (!place_samples) sel.placed.resize(static_cast<std::size_t>(n));
    }
    u64* worst = sel.worst_bits.data();
    i32* count = sel.sample_count.data();
    u8* placed = sel.placed.data();
    // In two stages, so that the geometric tests, long and with a large
    // scratch each, run only for the collapses that pass the cheap ones,
    // side by side (on the GPU, warps of collapses that all go on).
    exec.for_each(n, [=] TETISO_HD(i64 at) {
        const i32 k = by_edge[at];
        const bool maybe = test.dry_run_connectivity(candidates[at]);
        outcome[k] = maybe ? kOutcomeUndecided : kOutcomeIllegal;
        if (!samples) return;
        worst[k] = hd::bits(0.0);
        count[at] = 0;
        if (!place_samples) placed[k] = 0; // PlacementPasses' record
    });
    exec.filter_into(n, [=] TETISO_HD(i64 at) { return outcome[by_edge[at]] == kOutcomeUndecided; },
                     sel.dry_survivors, kTallyDrySurvivors);
    const i32* survivors = sel.dry_survivors.data();
    // On the device, the survivors grouped by the faces of their leaves (the
    // rest after them), so that a warp's tiles loop over as many faces: the
    // geometric tests' loops run over the fan. (The host's grouping
    // sorts each group's run, made for short runs: these are long, and a
    // host thread gains nothing from the order.)
    const i32* by_fan = survivors;
    if constexpr (!Exec::kHost) {
        exec.group_by_key(n, kFanGroups + 1, [=] TETISO_HD(i64 at) {
            return outcome[by_edge[at]] != kOutcomeUndecided ? kFanGroups
                                                             : std::min(test.leaf_faces(candidates[at]), kFanGroups - 1);
        }, sel.fan_first, sel.by_fan, sel.fan_scratch);
        by_fan = sel.by_fan.data();
    }
    // A tile of threads a collapse (on the GPU, part of a warp), its new
    // faces in memory the tile shares.
    using Tile = typename Exec::Tile;
    exec.template for_each_of_tiled<NewFan>(exec.tally_at(kTallyDrySurvivors), n,
                                            [=] TETISO_HD(i64 j, const Tile& tile, NewFan& fan) {
        const i32 at = by_fan[j], k = by_edge[at], e = candidates[at];
        // Always a place for the bound (the test reads it only with
        // samples): the compiler then leaves out the test's path that places
        // the samples itself, with its registers and stack.
        double deferred = 0.0;
        const bool legal = test.dry_run_rest(tile, e, fan, &deferred) == Verdict::kLegal;
        if (tile.rank() != 0) return;
        outcome[k] = legal ? kOutcomeUndecided : kOutcomeIllegal;
        if (!samples) return;
        worst[k] = hd::bits(deferred);
        if (place_samples && legal) count[at] = test.leaf_samples(e);
    });
    if (samples && place_samples) place_listed_samples(exec, sel, sel.placed_items[0], n, test);
}

// Optimistic placement. Of a collapse's dry-run tests, placing its leaves'
// samples (the error bound) costs the most, yet seldom is the one that
// fails: on the paper surface at N = 60 (reduce_by_reservations), at most
// one collapse in a thousand that passed every other test failed it in the
// first eight rounds, which place 60 % of the samples. And the steps choose
// one legal collapse in ten or fewer. So the steps may first take every collapse
// that passed the other tests as legal, and the samples be placed only for
// those they decide (chosen, or blocked by a corner, whose verdict the
// sweep needs too); if some chosen one then fails, the steps run again
// without it, and place the samples of the collapses they decide that were
// not placed before. The outcome is the eager form's: the steps only ever
// choose among collapses whose tests, all of them, have passed by the end,
// and every collapse the sweep would test has been placed. After
// kPlacementLists - 1 passes that found a chosen collapse illegal, every
// legal collapse not yet placed is, and the steps run a last time. A round
// that needs a third pass makes the reduction's later rounds place eagerly:
// late rounds, near the bound, fail the error test more and more often (up
// to half of the collapses that passed the others in the last rounds of
// that surface), and on the GPU a pass costs about a millisecond.
template <class Exec>
struct PlacementPasses {
    Selection<Exec>& sel;
    i32 n;
    bool optimistic;
    int lists; // the item lists of sel.placed_items this round filled
    bool all_placed;

    PlacementPasses(Selection<Exec>& selection, i32 ranks, bool optimistic_)
        : sel(selection), n(ranks), optimistic(optimistic_), lists(optimistic_ ? 0 : 1), all_placed(!optimistic_) {}

    // After the steps: places the samples the steps' decisions need; true
    // when they must run again.
    template <class Test>
    bool verify(Exec& exec, const Test& test, const u8* chosen) {
        if (all_placed) return false;
        const bool every_one = lists == kPlacementLists - 1;
        const i32* order = sel.order.data();
        const i32* by_edge = sel.by_edge.data();
        const i32* survivors = sel.dry_survivors.data();
        const u8* outcome = sel.outcome.data();
        u8* placed = sel.placed.data();
        i32* count = sel.sample_count.data();
        exec.for_each_of(exec.tally_at(kTallyDrySurvivors), n, [=] TETISO_HD(i64 j) {
            const i32 at = survivors[j], k = by_edge[at];
            const u8 what = outcome[k];
            const bool now = !placed[k] && (every_one ? what != kOutcomeIllegal
                                                      : what == kOutcomeChosen || what == kOutcomeBlockedByCorner);
            count[at] = now ? test.leaf_samples(order[k]) : 0;
            if (now) placed[k] = 1;
        });
        place_listed_samples(exec, sel, sel.placed_items[static_cast<std::size_t>(lists++)], n, test);
        if (every_one) {
            all_placed = true;
            sel.optimism_spent = true;
            return true;
        }
        exec.count_into(n, [=] TETISO_HD(i64 k) { return chosen[order[k]] == kChosen && outcome[k] == kOutcomeIllegal; },
                        kTallyRefusedChoices);
        const auto tally = exec.read_tally();
        if (tally[kTallyRefusedChoices] == 0) return false;
        // The device's steps of this pass, which the next overwrites.
        if (sel.device_steps & 1) sel.steps += static_cast<std::size_t>(tally[kTallyCollapseSteps]);
        ++sel.placement_repeats;
        // A third pass costs about what placing eagerly would have.
        if (lists >= 2) sel.optimism_spent = true;
        return true;
    }
};

} // namespace tetiso::reduction
