// The reduction's round driver (reduce.hpp), written once against the
// execution backends: the host's OpenMP primitives (exec_host.hpp) and
// CUDA's (exec_cuda.cuh) run the same steps over the same per-element
// functions, so a reduction gives the same bytes on either. One round, each
// step a data-parallel pass over flat arrays (vertex, edge or triangle index
// → values):
//   1. fans:      vertex → its triangles in counter-clockwise order
//                 (adjacency.hpp; the first round validates the input);
//   2. edges:     one record per undirected edge, owned by its smaller end;
//   3. geometry:  unit normal and quality of every triangle; the error
//                 samples sorted by owner (error_bound.hpp); the cones
//                 (legality.hpp);
//   4. classify:  per edge, the collapse branch that applies and the
//                 priority (criterion.hpp), or skipped as quiet (apply.hpp);
//   5. select:    the independent set in priority order (selection.hpp); Φ,
//                 the position and the legality tests are computed here,
//                 only for what could still be chosen; then the flips;
//                 then those chosen whose new faces would meet a face they
//                 share no corner with are dropped (contact_filter.hpp);
//   6. apply:     the chosen operations touch disjoint triangles and
//                 vertices (apply.hpp);
//   7. compact:   drop removed vertices and triangles, keeping their order
//                 (so vertex keys stay sorted).
// Rounds repeat until no candidate is left, two rounds in a row collapse
// nothing, or max_rounds is reached; in a batch (batch.hpp), piece by piece. Every per-element computation depends
// on that element's inputs only and no floating-point value is ever summed
// across elements, so the output is the same for any thread count and
// device.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "../hd.hpp"
#include "adjacency.hpp"
#include "apply.hpp"
#include "contact_filter.hpp"
#include "criterion.hpp"
#include "error_bound.hpp"
#include "legality.hpp"
#include "round_view.hpp"
#include "selection.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::reduction {

// Every array of a reduction, kept from round to round and, on the device,
// from one reduction to the next (a worker's GPU reduces domain after domain
// without allocating).
template <class Exec>
struct ReductionState {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Surface<Exec> s;
    Fans<Exec> fans;
    Edges<Exec> edges;
    Array<FaceGeometry> geometry;
    Array<Cone> cones;
    ContactFilter<Exec> contact;
    Array<u8> kind;
    Array<u32> priority;
    Array<float> px, py, pz, err;
    Array<i32> survivor;
    // Where the selection's dry runs write their proposals (speculation).
    Array<u8> dry_kind;
    Array<float> dry_px, dry_py, dry_pz, dry_err;
    Array<i32> dry_survivor;
    Array<u8> chosen, refused, changed;
    Array<u32> refused_slots;
    Array<i32> candidates, flips, offered, to_move, scratch, rank, list, first, order;
    Samples<Exec> samples;
    Selection<Exec> selection;
    Compaction<Exec> compaction;
    HandedOn<Exec> handed_on;
    // A batch (batch.hpp): pieces side by side in the same arrays, each
    // reduced as it would be alone. vertex_piece[v]: the piece of vertex v
    // (empty with one piece); per piece: this round's collapses and flips
    // (2 entries), its rounds in a row without a collapse, and whether it
    // has finished (frozen: nothing of it changes any more).
    i32 pieces = 1;
    Array<i32> vertex_piece, piece_ops, piece_idle;
    Array<u8> piece_done;

    OpsView ops() {
        return {kind.data(), priority.data(), px.data(), py.data(), pz.data(), err.data(), survivor.data()};
    }
    OpsView dry_ops() {
        return {dry_kind.data(), priority.data(), dry_px.data(), dry_py.data(), dry_pz.data(), dry_err.data(),
                dry_survivor.data()};
    }
};

inline Params make_params(const ReduceOptions& o) {
    return {o.phi,
            std::sin(o.min_angle_degrees * hd::kPi / 180.0),
            std::cos(o.max_normal_turn_degrees * hd::kPi / 180.0),
            std::cos(o.flip_max_dihedral_degrees * hd::kPi / 180.0),
            o.max_error,
            o.short_edge_ratio,
            o.flips};
}

// The most threads a round uses, whatever it is offered: the most measured.
// A round is a dozen short parallel loops with a join after each; with every
// one of them parallel, sixteen threads were as fast as eight or faster at
// every size on a 16-core machine, from small gyroid surfaces to the paper
// surface at N = 100.
constexpr int kMaxRoundThreads = 16;

// Samples made on the host (those a reduced piece carries) into the state.
template <class Exec>
void upload_samples(Exec& exec, const HostSamples& h, ReductionState<Exec>& st) {
    exec.upload(h.point, st.samples.point);
    exec.upload(h.owner, st.samples.owner);
    exec.upload(h.far, st.samples.far);
    exec.upload(h.far_point, st.samples.far_point);
    st.samples.count = static_cast<i32>(h.point.size());
    st.samples.on = true;
}

// Loads a piece (checked by the caller) into the state: its surface and,
// with an error bound, its samples.
template <class Exec>
void load_piece(Exec& exec, const Piece& in, bool bounded, ReductionState<Exec>& st) {
    const std::size_t nv = in.vertex_count(), nt = in.triangle_count();
    std::vector<float> xyz(3 * nv);
    for (std::size_t v = 0; v < nv; ++v) {
        xyz[3 * v] = in.x[v];
        xyz[3 * v + 1] = in.y[v];
        xyz[3 * v + 2] = in.z[v];
    }
    Surface<Exec>& s = st.s;
    exec.upload(xyz, s.xyz);
    exec.upload(in.key, s.key);
    if (in.flags.empty()) exec.assign(s.flags, static_cast<i64>(nv), u8{0});
    else exec.upload(in.flags, s.flags);
    exec.upload(in.triangles, s.tri);
    if (in.error.empty()) exec.assign(s.err, static_cast<i64>(nt), 0.0f);
    else exec.upload(in.error, s.err);
    s.nv = static_cast<i32>(nv);
    s.nt = static_cast<i32>(nt);
    st.pieces = 1;
    st.samples.on = false;
    if (!bounded) return;
    if (in.error.empty()) {
        build_raw_samples(exec, s.view(), st.samples, st.scratch, st.rank);
        return;
    }
    upload_samples(exec, samples_of_reduced_input(in), st);
}

// The rounds. threads: what the host may use to begin with (options.
// more_threads may offer more before each round); the device ignores it.
template <class Exec>
void run_rounds(Exec& exec, ReductionState<Exec>& st, const ReduceOptions& options, int threads_available,
                ReduceReport& rep) {
    const Params params = make_params(options);
    Surface<Exec>& s = st.s;
    exec.assign(st.changed, s.nv, u8{0});
    exec.assign(st.refused_slots, s.nv, u32{0});
    st.selection.optimism_spent = false;
    load_obstacles(exec, options.obstacles, st.contact);
    const i32 pieces = st.pieces;
    exec.assign(st.piece_done, pieces, u8{0});
    exec.assign(st.piece_idle, pieces, i32{0});
    u8* piece_done = st.piece_done.data();
    i32* piece_idle = st.piece_idle.data();
    ReduceStageSeconds& seconds = rep.stages;
    // Stage times are marks (on the device, events on its stream), summed
    // once the round is over: timing a stage never waits for the device.
    struct Lap {
        double* into;
        int from, to;
    };
    std::vector<Lap> laps;
    int last_mark = 0;
    const auto lap = [&](double& into) {
        const int now = exec.mark();
        laps.push_back({&into, last_mark, now});
        last_mark = now;
    };
    const auto settle_laps = [&] {
        for (const Lap& l : laps) *l.into += exec.seconds_between(l.from, l.to);
        laps.clear();
    };
    for (int round = 0;; ++round) {
        if constexpr (Exec::kHost) {
            if (options.more_threads)
                if (const int offered = options.more_threads(); offered > 0) threads_available = offered;
            exec.threads = std::min(threads_available, kMaxRoundThreads);
        }
        exec.clear_marks();
        const int round_start = exec.mark();
        last_mark = round_start;
        // The fans, and the edges counted on them before the host looks: one
        // wait for both counts. The rare fan that needs a second pass (or
        // the input's fault) is found then, and the edges counted again.
        const bool validate = round == 0;
        order_all_fans(exec, s, validate, st.fans);
        count_fan_problems(exec, s.nv, st.fans, kTallyFanProblems);
        count_edges(exec, st.fans.view(), st.fans.problem.data(), s.nv, st.edges, kTallyEdges);
        auto sizes = exec.read_tally();
        if (sizes[kTallyFanProblems] > 0) {
            finish_fans(exec, s, validate, sizes[kTallyFanProblems], st.fans);
            count_edges(exec, st.fans.view(), st.fans.problem.data(), s.nv, st.edges, kTallyEdges);
            sizes = exec.read_tally();
        }
        lap(seconds.fans);
        if (round >= options.max_rounds) {
            settle_laps();
            break;
        }
        const FansView fans = st.fans.view();
        write_edges(exec, fans, s.nv, static_cast<i32>(sizes[kTallyEdges]), st.edges);
        lap(seconds.edges);
        build_geometry(exec, s.view(), st.geometry);
        lap(seconds.geometry);
        const i32 ne = st.edges.n;
        const auto edge_count = static_cast<std::size_t>(ne);
        for (auto* a : {&st.px, &st.py, &st.pz, &st.err}) a->resize(edge_count);
        st.kind.resize(edge_count);
        st.priority.resize(edge_count);
        st.survivor.resize(edge_count);
        if (st.selection.speculate) {
            for (auto* a : {&st.dry_px, &st.dry_py, &st.dry_pz, &st.dry_err}) a->resize(edge_count);
            st.dry_kind.resize(edge_count);
            st.dry_survivor.resize(edge_count);
        }
        st.refused.resize(edge_count);
        st.chosen.resize(edge_count);
        if (st.samples.on) st.samples.sort(exec, st.geometry, s.nt);
        build_cones(exec, s.view(), fans, st.geometry.data(), st.cones);
        const EdgesView edges = st.edges.view();
        const RoundView m{s.view(), fans, edges, st.geometry.data(), st.cones.data(), st.samples.view(), params, round};
        const OpsView ops = st.ops();
        // The piece of a vertex: 0 unless this is a batch of several.
        const i32* vertex_piece = pieces > 1 ? st.vertex_piece.data() : nullptr;
        {
            const u32* refused_slots = st.refused_slots.data();
            const u8* changed = st.changed.data();
            u8* refused = st.refused.data();
            u8* chosen = st.chosen.data();
            exec.for_each(ne, [=] TETISO_HD(i64 ei) {
                const i32 e = static_cast<i32>(ei);
                refused[e] = 0;
                chosen[e] = 0;
                // A finished piece of a batch is frozen: its edges offer nothing.
                if (piece_done[vertex_piece ? vertex_piece[edges.v0[e]] : 0]) ops.kind[e] = kQuiet;
                else if (known_refused(refused_slots, edges, e) && unchanged(fans, edges, changed, e)) ops.kind[e] = kQuiet;
                else classify(m, e, ops);
            });
        }
        const u8* kind = st.kind.data();
        const i32 candidates = exec.filter(ne, [=] TETISO_HD(i64 e) {
            return kind[e] == kPending || kind[e] == kCollapse;
        }, st.candidates);
        lap(seconds.propose);
        ReduceRound stats;
        stats.round = round;
        stats.vertices = static_cast<std::size_t>(s.nv);
        stats.triangles = static_cast<std::size_t>(s.nt);

        // Collapses. The selection places a pending collapse (Φ, position)
        // only when it reaches it unblocked: most are blocked by a chosen
        // neighbour and never need their Φ this round.
        u8* chosen = st.chosen.data();
        u8* refused = st.refused.data();
        Selection<Exec>& sel = st.selection;
        exec.assign(sel.claimed, s.nv, i32{0});
        sel.stamp = 0;
        sel.steps = 0;
        sel.placement_repeats = 0;
        sel.device_steps = 0;
        const SelectView select_view{fans, edges, st.cones.data(), sel.claimed.data(), 0};
        i32* owner = st.samples.on ? st.samples.owner.data() : nullptr;
        choose<false>(exec, sel, select_view, st.candidates, candidates, s.nv, st.priority.data(), chosen, refused,
                      CollapseTest{m, ops, owner, st.dry_ops()});
        // Flips: for the interior edges with no collapse that no chosen
        // collapse blocks. refused[e] (set by the selection for a collapse
        // found impossible or illegal) ends as "no operation is possible on
        // e", the answer refused_slots keeps; a blocked edge's answer is
        // unknown.
        claim_chosen(exec, sel, select_view, st.candidates, candidates, chosen);
        const bool flips_on = params.flips;
        exec.for_each(ne, [=] TETISO_HD(i64 ei) {
            const i32 e = static_cast<i32>(ei);
            if (kind[e] == kNone) refused[e] = !flips_on || edges.border(fans, e);
        });
        SelectView clear_view = select_view;
        clear_view.stamp = sel.stamp;
        // The edges offered a flip stay counted on the device: the flips
        // among them are picked from a list read up to that count, and only
        // their number is read.
        exec.filter_into(ne, [=] TETISO_HD(i64 ei) {
            const i32 e = static_cast<i32>(ei);
            return kind[e] == kNone && !refused[e] && clear_view.free(edges.v0[e]) && clear_view.free(edges.v1[e]);
        }, st.offered, kTallyOffered);
        const i64* offered = exec.tally_at(kTallyOffered);
        const i32* offered_list = st.offered.data();
        exec.for_each_of(offered, ne, [=] TETISO_HD(i64 k) {
            const i32 e = offered_list[k];
            if (!propose_flip(m, e, ops)) refused[e] = 1;
        });
        // The host's list is as long as its count; the device's has room
        // for every edge.
        i64 offered_most = ne;
        if constexpr (Exec::kHost) offered_most = *offered;
        const i32 flips = exec.copy_if(st.offered, offered_most, [=] TETISO_HD(i64 k) {
            return k < *offered && kind[offered_list[k]] == kFlip;
        }, st.flips);
        choose<true>(exec, sel, clear_view, st.flips, flips, s.nv, st.priority.data(), chosen, refused, FlipTest{});
        lap(seconds.select);
        if (options.contact_test) drop_contacts(exec, st.contact, m, ops, ne, chosen, owner, vertex_piece);
        lap(seconds.contact);
        // The vertices' answers, and their marks for apply (the round's
        // last reader of the old ones was the classification).
        Compaction<Exec>& c = st.compaction;
        c.vertex_alive.resize(static_cast<std::size_t>(s.nv));
        {
            u32* refused_slots = st.refused_slots.data();
            u8* vertex_alive = c.vertex_alive.data();
            u8* changed = st.changed.data();
            exec.for_each(s.nv, [=] TETISO_HD(i64 v) {
                refused_slots[v] = refused_mask(edges, kind, refused, static_cast<i32>(v));
                vertex_alive[v] = 1;
                changed[v] = 0;
            });
        }
        {
            const i32* list = st.candidates.data();
            exec.count_into(candidates, [=] TETISO_HD(i64 k) { return kind[list[k]] != kPending; }, kTallyEvaluated);
        }
        stats.candidates = static_cast<std::size_t>(candidates) + static_cast<std::size_t>(flips);

        // Samples still to move: those of the flips (a collapse's test moved
        // its samples when it was chosen). A round that chose nothing goes
        // on to the end, changing nothing, and then stops: the next round
        // would find what this one did.
        exec.count_into(ne, [=] TETISO_HD(i64 e) { return chosen[e] && kind[e] == kCollapse; }, kTallyCollapses);
        exec.filter_into(ne, [=] TETISO_HD(i64 e) { return chosen[e] && kind[e] == kFlip; }, st.to_move, kTallyFlips);
        // Each piece of a batch stops as it would alone: its own counts.
        i32* piece_ops = nullptr;
        if (pieces > 1) {
            exec.assign(st.piece_ops, 2 * static_cast<i64>(pieces), i32{0});
            piece_ops = st.piece_ops.data();
            exec.for_each(ne, [=] TETISO_HD(i64 e) {
                if (chosen[e]) hd::atomic_add(piece_ops + 2 * vertex_piece[edges.v0[e]] + (kind[e] == kFlip), i32{1});
            });
        }
        // The samples move first: they are placed on the new faces by reading
        // the fans and positions that their legality test read. Each move
        // costs about what a legality test does.
        if (st.samples.on) {
            const i32* list = st.to_move.data();
            exec.for_each_of(exec.tally_at(kTallyFlips), ne, [=] TETISO_HD(i64 k) { move_flip_samples(m, list[k], owner); },
                             Exec::Grain::kTests);
        }
        exec.assign(c.triangle_alive, s.nt, u8{1});
        const ApplyView applied{c.vertex_alive.data(), c.triangle_alive.data(), st.changed.data()};
        const SurfaceView surface = s.view();
        exec.for_each(ne, [=] TETISO_HD(i64 e) {
            if (chosen[e]) apply_operation(surface, fans, edges, ops, applied, static_cast<i32>(e));
        });
        exec.count_into(s.nv, [=] TETISO_HD(i64 v) { return (applied.changed[v] & applied.vertex_alive[v]) != 0; },
                        kTallyChanged);
        // The stopping rule, piece by piece: a piece finishes after a round
        // that chose nothing for it (which went on to the end changing
        // nothing of it), or after its second round in a row without a
        // collapse. Alone, the piece's counts are the round's.
        {
            const i64* round_collapses = exec.tally_at(kTallyCollapses);
            const i64* round_flips = exec.tally_at(kTallyFlips);
            exec.for_each(pieces, [=] TETISO_HD(i64 p) {
                if (piece_done[p]) return;
                const i64 collapses = piece_ops ? piece_ops[2 * p] : *round_collapses;
                const i64 flips = piece_ops ? piece_ops[2 * p + 1] : *round_flips;
                if (collapses == 0 && flips == 0) {
                    piece_done[p] = 1;
                    return;
                }
                piece_idle[p] = collapses == 0 ? piece_idle[p] + 1 : 0;
                if (piece_idle[p] >= 2) piece_done[p] = 1;
            });
            exec.count_into(pieces, [=] TETISO_HD(i64 p) { return piece_done[p] == 0; }, kTallyActive);
        }
        lap(seconds.apply);
        // Compaction before the host reads the round's counts: one wait for
        // the statistics, the stopping rule and the new sizes. (A round
        // without a collapse compacts nothing away: its copies are the same.)
        compact(exec, s, c, st.changed, st.refused_slots, owner, st.samples.on ? st.samples.count : 0,
                pieces > 1 ? &st.vertex_piece : nullptr, kTallyVertices, kTallyTriangles);
        const auto tally = exec.read_tally(); // the round's one wait for its statistics
        sized_as_compacted(s, tally[kTallyVertices], tally[kTallyTriangles], st.changed, st.refused_slots,
                           pieces > 1 ? &st.vertex_piece : nullptr);
        stats.evaluated = static_cast<std::size_t>(tally[kTallyOffered]) + static_cast<std::size_t>(tally[kTallyEvaluated]);
        stats.collapses = static_cast<std::size_t>(tally[kTallyCollapses]);
        stats.flips = static_cast<std::size_t>(tally[kTallyFlips]);
        stats.changed_vertices = static_cast<std::size_t>(tally[kTallyChanged]);
        stats.selection_steps = sel.steps;
        stats.selection_passes = 1 + sel.placement_repeats;
        if (sel.device_steps & 1) stats.selection_steps += static_cast<std::size_t>(tally[kTallyCollapseSteps]);
        if (sel.device_steps & 2) stats.selection_steps += static_cast<std::size_t>(tally[kTallyFlipSteps]);
        lap(seconds.compact);
        settle_laps();
        stats.seconds = exec.seconds_between(round_start, last_mark);
        rep.rounds.push_back(stats);
        if (tally[kTallyActive] == 0) break;
    }
}

// The reduced surface, and with keep_samples the samples handed on.
template <class Exec>
Piece unload_piece(Exec& exec, ReductionState<Exec>& st, bool keep_samples) {
    Surface<Exec>& s = st.s;
    Piece out;
    const auto nv = static_cast<std::size_t>(s.nv);
    std::vector<float> xyz;
    exec.download(s.xyz, 3 * static_cast<i64>(nv), xyz);
    out.x.resize(nv);
    out.y.resize(nv);
    out.z.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) {
        out.x[v] = xyz[3 * v];
        out.y[v] = xyz[3 * v + 1];
        out.z[v] = xyz[3 * v + 2];
    }
    exec.download(s.key, s.nv, out.key);
    exec.download(s.flags, s.nv, out.flags);
    exec.download(s.tri, 3 * static_cast<i64>(s.nt), out.triangles);
    exec.download(s.err, s.nt, out.error);
    if (keep_samples && st.samples.on) {
        HandedOn<Exec>& h = st.handed_on;
        hand_on(exec, st.samples, s.nt, h, st.list, st.first, st.order, st.scratch);
        exec.download(h.xyz, 3 * static_cast<i64>(h.count), out.sample_xyz);
        exec.download(h.triangle, h.count, out.sample_triangle);
        exec.download(h.sampled, s.nt, out.sampled);
    }
    return out;
}

} // namespace tetiso::reduction
