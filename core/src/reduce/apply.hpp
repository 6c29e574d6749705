// Applying a round's chosen operations, and compacting the surface after
// them. The chosen operations share no triangle and no vertex (selection.hpp),
// so each writes only its own elements. Compaction drops removed vertices and
// triangles and keeps the order of the rest, so vertex keys stay sorted.
//
// Also here: which edges a round may skip ("quiet" edges). An edge's answer
// (its proposal and legality) reads the fans of its two ends — their faces,
// those faces' corners' positions and error bounds — and the fans of the two
// opposite vertices (valences, the flip's diagonal). A collapse changes the
// fans of exactly the vertices of its two leaves' faces and moves only the
// survivor, whose neighbours are among them; a flip changes the fans of its
// four corners. So an edge none of whose four vertices apply() marked has the
// answer it had last round. An unchanged vertex keeps its triangles and their
// order, so its fan comes out the same and an edge it owns keeps its slot:
// refused_slots[v] has bit j set when the edge v owns at slot j (v its smaller
// end) was found to have no possible operation (Φ not above Φ*, illegal, no
// flip). An edge so marked whose four vertices are unchanged is skipped; an
// edge blocked before its answer was known is not marked. Once most of the
// surface is as reduced as the criterion and the bounds allow, a round costs
// what the last one changed rather than a full evaluation. Slots past the
// mask's width are never marked: their edges are re-tested.
#pragma once

#include <cstddef>

#include "../hd.hpp"
#include "round_view.hpp"
#include "selection.hpp"

namespace tetiso::reduction {

constexpr i32 kRefusedSlots = 32;

TETISO_HD inline bool known_refused(const u32* refused_slots, const EdgesView& edges, i32 e) {
    const i32 j = edges.s0[e];
    return j < kRefusedSlots && (refused_slots[edges.v0[e]] >> j & 1u);
}

TETISO_HD inline bool unchanged(const FansView& fans, const EdgesView& edges, const u8* changed, i32 e) {
    const i32 u = edges.v0[e], w = edges.v1[e];
    if (changed[u] || changed[w]) return false;
    const EdgeFaces f = edges.faces(fans, e);
    for (const i32 o : {f.c, f.d})
        if (o >= 0 && changed[o]) return false;
    return true;
}

// The refusals vertex v keeps for the next round: bit j for its edge at slot
// j that had no possible operation (or was skipped as quiet).
TETISO_HD inline u32 refused_mask(const EdgesView& edges, const u8* kind, const u8* refused, i32 v) {
    u32 mask = 0;
    for (i32 e = edges.first[v]; e < edges.first[v + 1]; ++e)
        if ((kind[e] == kQuiet || refused[e]) && edges.s0[e] < kRefusedSlots) mask |= u32{1} << edges.s0[e];
    return mask;
}

// What applying the chosen operations writes besides the surface: which
// vertices and triangles outlive the round, and changed[v] for every vertex
// whose fan, or a face of it, was altered (the vertices of every face of both
// leaves of a collapse, the four corners of a flip). Two operations may mark
// the same vertex, hence the atomic store.
struct ApplyView {
    u8 *vertex_alive, *triangle_alive, *changed;
};

TETISO_HD inline void apply_operation(const SurfaceView& s, const FansView& fans, const EdgesView& edges,
                                      const OpsView& ops, const ApplyView& out, i32 e) {
    const i32 u = edges.v0[e], w = edges.v1[e];
    const EdgeFaces ef = edges.faces(fans, e);
    const i32 f1 = ef.f1, f2 = ef.f2;
    const float err = ops.err[e];
    auto mark = [&](i32 v) { hd::atomic_store(out.changed + v, u8{1}); };
    if (ops.kind[e] == kFlip) {
        const i32 c = ef.c, d = ef.d;
        for (const i32 v : {u, w, c, d}) mark(v);
        // f1 = (u, w, c), f2 = (w, u, d) → (c, u, d), (d, w, c).
        const i32 g1[3] = {c, u, d}, g2[3] = {d, w, c};
        for (int r = 0; r < 3; ++r) {
            s.tri[3 * f1 + r] = g1[r];
            s.tri[3 * f2 + r] = g2[r];
        }
        s.err[f1] = err;
        s.err[f2] = err;
        return;
    }
    const i32 keep = ops.survivor[e], gone = keep == u ? w : u;
    if (!s.locked(keep)) { // a locked survivor is pinned: p is its own position
        float* p = s.xyz + 3 * static_cast<std::size_t>(keep);
        p[0] = ops.px[e];
        p[1] = ops.py[e];
        p[2] = ops.pz[e];
    }
    out.vertex_alive[gone] = 0;
    for (const i32 v : {keep, gone}) {
        const i32 o = fans.off[v], k = fans.k(v);
        for (i32 j = o; j < o + k; ++j) {
            const i32 t = fans.face[j];
            for (int r = 0; r < 3; ++r) mark(s.tri[3 * t + r]);
            if (t == f1 || t == f2) {
                out.triangle_alive[t] = 0;
                continue;
            }
            s.err[t] = err;
            if (v == gone)
                for (int r = 0; r < 3; ++r)
                    if (s.tri[3 * t + r] == gone) s.tri[3 * t + r] = keep;
        }
    }
}

template <class Exec>
struct Compaction {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<u8> vertex_alive, triangle_alive;
    Array<i32> vertex_rank, triangle_rank;
    Surface<Exec> spare; // compact()'s second set of arrays
    Array<u8> spare_marks;
    Array<u32> spare_masks;
    Array<i32> spare_tags;
};

// Drops removed vertices and triangles, keeping the order of the rest. The
// ranks are integer scans; the copies are gathers into the spare arrays,
// which then change places with the live ones. vertex_marks, vertex_masks:
// per-vertex arrays that follow the vertices (changed, refused_slots);
// triangle_refs: n triangle indices to renumber (the samples' owners);
// vertex_tags, where given: a per-vertex array that follows the vertices too
// (a batch's piece of each vertex).
template <class Exec>
void compact(Exec& exec, Surface<Exec>& s, Compaction<Exec>& c, typename Exec::template Array<u8>& vertex_marks,
             typename Exec::template Array<u32>& vertex_masks, i32* triangle_refs, i32 refs,
             typename Exec::template Array<i32>* vertex_tags = nullptr) {
    const i32 nv = s.nv, nt = s.nt;
    const u8* vertex_alive = c.vertex_alive.data();
    const i32 next = exec.rank(nv, [=] TETISO_HD(i64 v) { return vertex_alive[v] != 0; }, c.vertex_rank);
    Surface<Exec>& to = c.spare;
    to.xyz.resize(3 * static_cast<std::size_t>(next));
    to.key.resize(static_cast<std::size_t>(next));
    to.flags.resize(static_cast<std::size_t>(next));
    c.spare_marks.resize(static_cast<std::size_t>(next));
    c.spare_masks.resize(static_cast<std::size_t>(next));
    c.spare_tags.resize(vertex_tags ? static_cast<std::size_t>(next) : 0);
    {
        const i32* remap = c.vertex_rank.data();
        const float* xyz = s.xyz.data();
        const EdgeKey* key = s.key.data();
        const u8* flags = s.flags.data();
        const u8* marks = vertex_marks.data();
        const u32* masks = vertex_masks.data();
        float* to_xyz = to.xyz.data();
        EdgeKey* to_key = to.key.data();
        u8* to_flags = to.flags.data();
        u8* to_marks = c.spare_marks.data();
        u32* to_masks = c.spare_masks.data();
        const i32* tags = vertex_tags ? vertex_tags->data() : nullptr;
        i32* to_tags = c.spare_tags.data();
        exec.for_each(nv, [=] TETISO_HD(i64 v) {
            const i32 r = remap[v];
            if (r < 0) return;
            for (int k = 0; k < 3; ++k) to_xyz[3 * static_cast<std::size_t>(r) + k] = xyz[3 * v + k];
            to_key[r] = key[v];
            to_flags[r] = flags[v];
            to_marks[r] = marks[v];
            to_masks[r] = masks[v];
            if (tags) to_tags[r] = tags[v];
        });
    }
    s.xyz.swap(to.xyz);
    s.key.swap(to.key);
    s.flags.swap(to.flags);
    vertex_marks.swap(c.spare_marks);
    vertex_masks.swap(c.spare_masks);
    if (vertex_tags) vertex_tags->swap(c.spare_tags);
    s.nv = next;
    const u8* triangle_alive = c.triangle_alive.data();
    const i32 tn = exec.rank(nt, [=] TETISO_HD(i64 t) { return triangle_alive[t] != 0; }, c.triangle_rank);
    to.tri.resize(3 * static_cast<std::size_t>(tn));
    to.err.resize(static_cast<std::size_t>(tn));
    {
        const i32* remap = c.vertex_rank.data();
        const i32* tpos = c.triangle_rank.data();
        const i32* tri = s.tri.data();
        const float* err = s.err.data();
        i32* to_tri = to.tri.data();
        float* to_err = to.err.data();
        exec.for_each(nt, [=] TETISO_HD(i64 t) {
            const i32 at = tpos[t];
            if (at < 0) return;
            for (int r = 0; r < 3; ++r) to_tri[3 * static_cast<std::size_t>(at) + r] = remap[tri[3 * t + r]];
            to_err[at] = err[t];
        });
        exec.for_each(refs, [=] TETISO_HD(i64 i) {
            const i32 t = triangle_refs[i];
            if (t >= 0) triangle_refs[i] = tpos[t];
        });
    }
    s.tri.swap(to.tri);
    s.err.swap(to.err);
    s.nt = tn;
}

} // namespace tetiso::reduction
