// What the selection of a round keeps and reads (selection.hpp): the
// reservations' constants, the window's slots, the views of the round, the
// tests it runs, and the tallies the device keeps between passes.
#pragma once

#include <algorithm>
#include <array>
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
    // illegal); the second, only after a first that passed, the rest, by a
    // tile of threads sharing the new faces in `fan` (legal_geometry).
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
    template <class Tile>
    TETISO_HD Verdict dry_run_rest(const Tile& tile, i32 e, NewFan& fan, double* deferred) const {
        return legal_geometry(tile, m, e, dry, fan, deferred);
    }
    TETISO_HD bool samples_on() const { return m.samples.on; }
    TETISO_HD i32 leaf_samples(i32 e) const { return leaf_sample_count(m, slots(m, e)); }
    // The faces of both ends' fans of collapse e.
    TETISO_HD i32 leaf_faces(i32 e) const { return m.fans.k(m.edges.v0[e]) + m.fans.k(m.edges.v1[e]); }
    // visit(sample, own_slot) for the samples of the leaves of collapse e.
    template <class Visit>
    TETISO_HD void for_each_sample(i32 e, const Visit& visit) const {
        for_each_leaf_sample(m, slots(m, e), visit);
    }
    // A sample of the leaves of dry-run collapse e, placed on the face that
    // replaces its own (false: too far from it), or on the nearest.
    TETISO_HD bool place_on_own(i32 e, i32 sample, i32 own_slot, LeafSamplePlacement& placed) const {
        return place_on_own_face(m, {dry.px[e], dry.py[e], dry.pz[e]}, sample, own_slot, placed);
    }
    TETISO_HD LeafSamplePlacement place_on_nearest(i32 e, i32 sample) const {
        return place_on_nearest_face(m, e, {dry.px[e], dry.py[e], dry.pz[e]}, sample);
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

// The most lists of placements a round fills (PlacementPasses, dry_run.hpp),
// and the operations from which the device places samples optimistically.
constexpr int kPlacementLists = 4;
constexpr i32 kOptimisticMin = 1 << 14;

// Samples to place, one item each: per position in Selection::by_edge its
// first item; per item its rank, the sample and where it goes (before it is
// placed: the slot of the face it lies on, -1 for a face the collapse
// removes); the items their own face does not keep.
template <class Exec>
struct SampleItems {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<i32> first, rank, sample, triangle, far;
    i32 count = 0;
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
    // The dry runs' order (dry_run_all): the ranks by ascending edge, and
    // per edge its rank (read only for the round's candidates).
    Array<i32> by_edge, rank_of;
    // Positions in by_edge: those whose dry run passed its first stage, and
    // the same grouped by the faces of their leaves.
    Array<i32> dry_survivors;
    Array<i32> by_fan, fan_first, fan_scratch;
    // How many samples the leaves hold where they are to be placed (per
    // position in by_edge); per rank, the largest of their bounds and
    // whether they were placed.
    Array<i32> sample_count;
    Array<u64> worst_bits;
    Array<u8> placed;
    // The placements of a round, one list per pass that placed samples
    // (PlacementPasses); each rank's in one list at most.
    std::array<SampleItems<Exec>, kPlacementLists> placed_items;
    // Optimistic placement from this many operations up (PlacementPasses;
    // the host's tests set 0 to exercise it), and how many times a round's
    // steps ran again since the counter was reset.
    i32 optimistic_min = Exec::kHost ? std::numeric_limits<i32>::max() : kOptimisticMin;
    std::size_t placement_repeats = 0;
    // Set once a round needed a third pass: the rounds after it, whose
    // collapses fail the error test ever more often, place eagerly.
    bool optimism_spent = false;
    bool speculate = !Exec::kHost;
    i32 stamp = 0;
    // Tests only: the reservations on one host thread too, with this window
    // (0: the backend's), and speculate as chosen.
    bool always_reservations = false;
    i64 window_override = 0;
    std::size_t steps = 0; // reservation steps since the counter was reset, run from the host
    // Bit 0 (collapses), bit 1 (flips): the choice's steps ran on the
    // device (Exec::run_steps), counted in kTallyCollapseSteps,
    // kTallyFlipSteps.
    int device_steps = 0;
};

// The counts of a round that CudaExec keeps on the device (the slots of
// Exec::count_into, filter_into).
// kTallyActive: the pieces of a batch not finished after the round.
// kTallyFarSamples: the dry runs' samples too far from their own face.
// kTallyFanProblems, kTallyEdges: the fans not ordered, the edges (read
// together, before the edges are written). kTallyOffered: the edges offered
// a flip. kTallyVertices, kTallyTriangles: the surface's after compaction.
// kTallyEntrants: the collapses found legal by the dry runs.
// kTallyRefusedChoices: chosen collapses whose samples, placed after the
// steps, found no face (PlacementPasses).
enum TallySlot : int {
    kTallyEvaluated,
    kTallyCollapses,
    kTallyFlips,
    kTallyChanged,
    kTallyDrySurvivors,
    kTallyActive,
    kTallyFarSamples,
    kTallyFanProblems,
    kTallyEdges,
    kTallyOffered,
    kTallyCollapseSteps,
    kTallyFlipSteps,
    kTallyVertices,
    kTallyTriangles,
    kTallyEntrants,
    kTallyRefusedChoices
};

} // namespace tetiso::reduction
