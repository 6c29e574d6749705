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
    // On the device, the survivors grouped by the faces of their leaves (the
    // rest after them), so that a warp's threads loop over as many faces:
    // the geometric tests' loops run over the fan. (The host's grouping
    // sorts each group's run, made for short runs: these are long, and a
    // host thread gains nothing from the order.)
    const i32* by_fan = survivors;
    if constexpr (!Exec::kHost) {
        exec.group_by_key(n, kFanGroups + 1, [=] TETISO_HD(i64 k) {
            return outcome[k] != kOutcomeUndecided ? kFanGroups : std::min(test.leaf_faces(order[k]), kFanGroups - 1);
        }, sel.fan_first, sel.by_fan, sel.fan_scratch);
        by_fan = sel.by_fan.data();
    }
    exec.for_each_of(exec.tally_at(kTallyDrySurvivors), n, [=] TETISO_HD(i64 j) {
        const i32 k = by_fan[j], e = order[k];
        // Always a place for the bound (the test reads it only with
        // samples): the compiler then leaves out the test's path that places
        // the samples itself, with its registers and stack.
        double deferred = 0.0;
        const bool legal = test.dry_run_rest(e, &deferred) == Verdict::kLegal;
        outcome[k] = legal ? kOutcomeUndecided : kOutcomeIllegal;
        if (!samples) return;
        worst[k] = hd::bits(deferred);
        count[k] = legal ? test.leaf_samples(e) : 0;
    }, Grain::kTests);
    sel.items = 0;
    if (!samples) return;
    sel.items = exec.exclusive_scan(sel.sample_count, n, sel.sample_first);
    for (auto* items : {&sel.item_rank, &sel.item_sample, &sel.item_triangle})
        items->resize(static_cast<std::size_t>(sel.items));
    const i32* first = sel.sample_first.data();
    i32 *item_rank = sel.item_rank.data(), *item_sample = sel.item_sample.data(),
        *item_triangle = sel.item_triangle.data();
    // Each legal collapse lists its samples, so that a sample's thread finds
    // its collapse and its face in one read each, rather than by a binary
    // search over the ranks and a walk of the leaves.
    exec.for_each_of(exec.tally_at(kTallyDrySurvivors), n, [=] TETISO_HD(i64 j) {
        const i32 k = survivors[j];
        if (count[k] == 0) return;
        i32 item = first[k];
        test.for_each_sample(order[k], [&](i32 sample, i32 own_slot) {
            item_rank[item] = k;
            item_sample[item] = sample;
            item_triangle[item] = own_slot;
            ++item;
        });
    }, Grain::kTests);
    // Each sample on the face that replaces its own where that keeps it;
    // the others, listed, on the nearest face: a warp's threads then all
    // measure one face, or all loop over the leaves. (Not Grain::kTests:
    // held to the tests' registers, the device's kernels spilled the
    // distances to local memory.)
    constexpr i32 kFar = -2;
    exec.for_each(sel.items, [=] TETISO_HD(i64 item) {
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
    exec.filter_into(sel.items, [=] TETISO_HD(i64 item) { return item_triangle[item] == kFar; }, sel.far_items,
                     kTallyFarSamples);
    const i32* far_items = sel.far_items.data();
    exec.for_each_of(exec.tally_at(kTallyFarSamples), sel.items, [=] TETISO_HD(i64 j) {
        const i32 item = far_items[j], k = item_rank[item];
        const LeafSamplePlacement placed = test.place_on_nearest(order[k], item_sample[item]);
        item_triangle[item] = placed.triangle;
        if (placed.triangle < 0) hd::atomic_store(outcome + k, kOutcomeIllegal);
        else hd::atomic_max(worst + k, hd::bits(placed.bound));
    });
    exec.for_each(n, [=] TETISO_HD(i64 k) {
        if (outcome[k] == kOutcomeUndecided) test.dry.err[order[k]] = static_cast<float>(hd::from_bits(worst[k]));
    });
}

} // namespace tetiso::reduction
