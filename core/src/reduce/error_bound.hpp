// The error bound of a reduction (ReduceOptions::max_error): samples of the
// input surface, each owned by one current triangle, re-measured by every
// operation that replaces their triangle, so that the distance from every
// input vertex to the reduced surface is known and never accumulates from
// round to round.
//
// Each sample is owned by the triangle of its region it was last measured
// against; an operation re-measures the samples of every face it replaces
// against the new faces, so the distance of each sample to the reduced
// surface is known (as an upper bound: the face found, not necessarily the
// nearest). On a raw surface (an input without error bounds) a sample is one
// input vertex, and the bound is exact at every one of them. An input that
// was reduced before (Piece::error set: a seam's region) may carry the raw
// vertices of some triangles (Piece::sample_xyz, the triangles marked
// sampled, which stand for exactly those): each is a sample again, with base
// 0, so the bound stays exact there and a seam's reduction spends the whole
// budget anew rather than what its domains left. Every other triangle stands
// for raw vertices within its error of it, wherever they are: it is one
// sample, its three corners with that error as base. Its distance to a face
// is the largest of its corners', which bounds the distance of every point
// of the triangle (distance to one triangle is convex), so base + distance
// bounds the raw vertices it stands for. Vertex samples with the largest
// error of their triangles as base would not: a raw vertex lies near the
// inside of a triangle, which can stand farther from the new faces than its
// corners do (well over the bound across a job's seams on random fields,
// test_random_fields). Bounds add up only across calls whose input lacks the
// raw vertices, e.g. a seam's region beyond the samples a job keeps.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "../hd.hpp"
#include "round_view.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::reduction {

// The samples, in arrays of the execution backend. Points are kept in the
// order of their owners, so the samples of triangle t are one run (its
// FaceGeometry's samples_begin .. samples_end, which sort() writes) and a
// test reads them as one run rather than one cache miss each (the loads of
// scattered samples showed in a profile of the reduction). sort() restores the order at the start of every round; an
// operation changes only owner[], which the points stay in step with.
// far_point is never reordered: triangle samples are few.
template <class Exec>
struct Samples {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<SamplePoint> point;
    Array<i32> owner; // triangle, per sample
    Array<i32> far;   // empty when every sample is a raw vertex
    Array<SamplePoint> far_point;
    i32 count = 0;
    bool on = false;

    SamplesView view() const {
        return {point.data(), far.size() > 0 ? far.data() : nullptr, far_point.data(), on};
    }

    // The round's sort by owner (a stable grouping), writing each face's
    // range into its record.
    void sort(Exec& exec, typename Exec::template Array<FaceGeometry>& faces, i32 nt) {
        const i32* own = owner.data();
        exec.group_by_key(count, nt, [=] TETISO_HD(i64 i) { return own[i]; }, begin_, source_, fill_);
        FaceGeometry* g = faces.data();
        const i32* begin = begin_.data();
        exec.for_each(nt, [=] TETISO_HD(i64 t) {
            g[t].samples_begin = begin[t];
            g[t].samples_end = begin[t + 1];
        });
        const auto n = static_cast<std::size_t>(count);
        sorted_point_.resize(n);
        sorted_owner_.resize(n);
        const bool has_far = far.size() > 0;
        sorted_far_.resize(has_far ? n : 0);
        const i32* source = source_.data();
        const SamplePoint* from_point = point.data();
        const i32* from_far = far.data();
        SamplePoint* to_point = sorted_point_.data();
        i32* to_owner = sorted_owner_.data();
        i32* to_far = sorted_far_.data();
        exec.for_each(count, [=] TETISO_HD(i64 at) {
            const i32 i = source[at];
            to_point[at] = from_point[i];
            to_owner[at] = own[i];
            if (has_far) to_far[at] = from_far[i];
        });
        point.swap(sorted_point_);
        owner.swap(sorted_owner_);
        far.swap(sorted_far_);
    }

private:
    Array<i32> fill_, begin_, source_;
    Array<SamplePoint> sorted_point_;
    Array<i32> sorted_owner_, sorted_far_;
};

// The samples of a raw surface: each vertex used by a triangle, owned by the
// first triangle that uses it (a vertex of no triangle is no sample: no
// operation can move it).
template <class Exec>
void build_raw_samples(Exec& exec, const SurfaceView& s, Samples<Exec>& samples,
                       typename Exec::template Array<i32>& scratch, typename Exec::template Array<i32>& rank) {
    exec.assign(scratch, s.nv, std::numeric_limits<i32>::max());
    i32* first = scratch.data();
    exec.for_each(3 * static_cast<i64>(s.nt), [=] TETISO_HD(i64 c) {
        hd::atomic_min(first + s.tri[c], static_cast<i32>(c / 3));
    });
    samples.count = exec.rank(s.nv, [=] TETISO_HD(i64 v) { return first[v] != std::numeric_limits<i32>::max(); }, rank);
    samples.point.resize(static_cast<std::size_t>(samples.count));
    samples.owner.resize(static_cast<std::size_t>(samples.count));
    samples.far.resize(0);
    samples.far_point.resize(0);
    SamplePoint* point = samples.point.data();
    i32* owner = samples.owner.data();
    const i32* at = rank.data();
    exec.for_each(s.nv, [=] TETISO_HD(i64 v) {
        if (at[v] < 0) return;
        const Vec p = s.pos(static_cast<i32>(v));
        point[at[v]] = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), 0.0f};
        owner[at[v]] = first[v];
    });
    samples.on = true;
}

// The samples of an input reduced before (Piece::error set), built on the
// host: its kept raw vertices (base 0), then one triangle sample for every
// triangle not marked sampled (its corners, its error as base).
struct HostSamples {
    std::vector<SamplePoint> point;
    std::vector<i32> owner, far;
    std::vector<SamplePoint> far_point;
};

inline HostSamples samples_of_reduced_input(const Piece& in) {
    HostSamples h;
    const std::size_t nt = in.triangle_count();
    h.point.reserve(nt + in.sample_count());
    for (std::size_t i = 0; i < in.sample_count(); ++i) {
        h.point.push_back({in.sample_xyz[3 * i], in.sample_xyz[3 * i + 1], in.sample_xyz[3 * i + 2], 0.0f});
        h.owner.push_back(in.sample_triangle[i]);
        h.far.push_back(-1);
    }
    for (std::size_t t = 0; t < nt; ++t) {
        if (in.triangle_sampled(t)) continue;
        for (std::size_t r = 0; r < 3; ++r) {
            const auto v = static_cast<std::size_t>(in.triangles[3 * t + r]);
            (r == 0 ? h.point : h.far_point).push_back({in.x[v], in.y[v], in.z[v], in.error[t]});
        }
        h.owner.push_back(static_cast<i32>(t));
        h.far.push_back(static_cast<i32>(h.far_point.size() / 2 - 1));
    }
    return h;
}

// What a reduction hands on of its samples (ReduceOptions::keep_samples):
// the raw vertices among them, grouped by triangle, those of every triangle
// that holds no triangle sample, which is then marked sampled (it stands for
// exactly its samples).
template <class Exec>
struct HandedOn {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<float> xyz;
    Array<i32> triangle;
    Array<u8> sampled;
    i32 count = 0;
};

template <class Exec>
void hand_on(Exec& exec, Samples<Exec>& samples, i32 nt, HandedOn<Exec>& out,
             typename Exec::template Array<i32>& list, typename Exec::template Array<i32>& first,
             typename Exec::template Array<i32>& order, typename Exec::template Array<i32>& scratch) {
    exec.assign(out.sampled, nt, u8{1});
    u8* sampled = out.sampled.data();
    const i32* owner = samples.owner.data();
    if (samples.far.size() > 0) {
        const i32* far = samples.far.data();
        exec.for_each(samples.count, [=] TETISO_HD(i64 i) {
            if (far[i] >= 0) hd::atomic_store(sampled + owner[i], u8{0});
        });
    }
    out.count = exec.filter(samples.count, [=] TETISO_HD(i64 i) { return sampled[owner[i]] != 0; }, list);
    const i32* kept = list.data();
    exec.group_by_key(out.count, nt, [=] TETISO_HD(i64 k) { return owner[kept[k]]; }, first, order, scratch);
    out.xyz.resize(3 * static_cast<std::size_t>(out.count));
    out.triangle.resize(static_cast<std::size_t>(out.count));
    float* xyz = out.xyz.data();
    i32* triangle = out.triangle.data();
    const i32* by_triangle = order.data();
    const SamplePoint* point = samples.point.data();
    exec.for_each(out.count, [=] TETISO_HD(i64 j) {
        const i32 i = kept[by_triangle[j]];
        xyz[3 * j] = point[i].x;
        xyz[3 * j + 1] = point[i].y;
        xyz[3 * j + 2] = point[i].z;
        triangle[j] = owner[i];
    });
}

// A sample's distance to triangle (a, b, c): its point's, or the largest of
// its corners' (see above).
TETISO_HD TETISO_INLINE double sample_distance(const SamplesView& samples, i32 sample, Vec a, Vec b, Vec c) {
    const SamplePoint* p = samples.point + sample;
    double d = point_triangle_distance({p->x, p->y, p->z}, a, b, c);
    if (const SamplePoint* q = samples.far_corners(sample))
        for (int k = 0; k < 2; ++k) d = std::max(d, point_triangle_distance({q[k].x, q[k].y, q[k].z}, a, b, c));
    return d;
}

// Places every sample of the old faces of both leaves of a collapse on a new
// face: on the face that replaces its own when that is within its room (the
// common case: a face that moves a little keeps its samples), else on the
// nearest. Calls visit(sample, triangle) for each and raises worst to each
// sample's bound; false when some sample has no new face within max_error.
template <class Visit>
TETISO_HD bool place_samples(const RoundView& m, const EdgeSlots& r, const NewFan& fan, double& worst,
                             const Visit& visit) {
    int replacement = 0;
    bool placed = true;
    for_each_leaf_face(r, [&](i32 slot, bool removed) {
        const i32 t = m.face(slot);
        const int own = removed ? -1 : replacement++;
        const FaceGeometry& g = m.geo[t];
        for (i32 sample = g.samples_begin; sample < g.samples_end && placed; ++sample) {
            const double base = m.samples.point[sample].base;
            int at = -1;
            double d = 0.0;
            if (own >= 0) {
                d = sample_distance(m.samples, sample, fan.p, fan.a(own), fan.b(own));
                if (base + d <= m.p.max_error) at = own;
            }
            if (at < 0) {
                d = std::numeric_limits<double>::infinity();
                for (int f = 0; f < fan.count; ++f) {
                    const double df = sample_distance(m.samples, sample, fan.p, fan.a(f), fan.b(f));
                    if (df < d) {
                        d = df;
                        at = f;
                    }
                }
                if (!(base + d <= m.p.max_error)) {
                    placed = false;
                    return;
                }
            }
            worst = std::max(worst, base + d);
            visit(sample, fan.tri[at]);
        }
    });
    return placed;
}

// Calls visit(sample, own_slot) for every sample of the faces of both leaves
// of a collapse, in place_samples' order: own_slot is the slot of the face
// it lies on, -1 where the collapse removes that face.
template <class Visit>
TETISO_HD void for_each_leaf_sample(const RoundView& m, const EdgeSlots& r, const Visit& visit) {
    for_each_leaf_face(r, [&](i32 slot, bool removed) {
        const FaceGeometry& g = m.geo[m.face(slot)];
        for (i32 sample = g.samples_begin; sample < g.samples_end; ++sample) visit(sample, removed ? -1 : slot);
    });
}

// How many samples the faces of both leaves of a collapse hold.
TETISO_HD inline i32 leaf_sample_count(const RoundView& m, const EdgeSlots& r) {
    i32 count = 0;
    for_each_leaf_face(r, [&](i32 slot, bool) {
        const FaceGeometry& g = m.geo[m.face(slot)];
        count += g.samples_end - g.samples_begin;
    });
    return count;
}

// One sample placed as place_samples places it: the triangle it goes to
// (-1 when no new face is within max_error of it) and its bound.
struct LeafSamplePlacement {
    i32 sample, triangle;
    double bound;
};

// A sample of the leaves of collapse e to p (for_each_leaf_sample's sample
// and own_slot), placed by itself: the same distances, compared in the same
// order, as place_samples computes for it, so that placing the samples of
// one collapse on as many threads gives place_samples' placements and, as
// the largest of the bounds, its worst. In two steps: the face that
// replaces its own (which keeps most samples), and only where that is too
// far, the nearest new face.
TETISO_HD inline bool place_on_own_face(const RoundView& m, Vec p, i32 sample, i32 own_slot,
                                        LeafSamplePlacement& placed) {
    if (own_slot < 0) return false;
    const double d = sample_distance(m.samples, sample, p, m.s.pos(m.fans.next[own_slot]),
                                     m.s.pos(m.fans.prev[own_slot]));
    const double bound = m.samples.point[sample].base + d;
    if (!(bound <= m.p.max_error)) return false;
    placed = {sample, m.face(own_slot), bound};
    return true;
}
TETISO_HD inline LeafSamplePlacement place_on_nearest_face(const RoundView& m, i32 e, Vec p, i32 sample) {
    const double base = m.samples.point[sample].base;
    double d = std::numeric_limits<double>::infinity();
    i32 at = -1;
    for_each_leaf_face(slots(m, e), [&](i32 slot, bool removed) {
        if (removed) return;
        const double df = sample_distance(m.samples, sample, p, m.s.pos(m.fans.next[slot]), m.s.pos(m.fans.prev[slot]));
        if (df < d) {
            d = df;
            at = m.face(slot);
        }
    });
    if (!(base + d <= m.p.max_error)) return {sample, -1, 0.0};
    return {sample, at, base + d};
}

// The same for a flip: f1 = (u, w, c), f2 = (w, u, d) become (c, u, d) in
// f1's place and (d, w, c) in f2's; each sample of either goes to the nearer
// of the two.
template <class Visit>
TETISO_HD bool place_flip_samples(const RoundView& m, const EdgeSlots& r, double& worst, const Visit& visit) {
    const Vec pu = m.s.pos(r.u), pw = m.s.pos(r.w), pc = m.s.pos(r.c), pd = m.s.pos(r.d);
    for (const i32 t : {r.f1, r.f2})
        for (i32 sample = m.geo[t].samples_begin; sample < m.geo[t].samples_end; ++sample) {
            const double d1 = sample_distance(m.samples, sample, pc, pu, pd);
            const double d2 = sample_distance(m.samples, sample, pd, pw, pc);
            const double bound = m.samples.point[sample].base + std::min(d1, d2);
            if (!(bound <= m.p.max_error)) return false;
            worst = std::max(worst, bound);
            visit(sample, d1 <= d2 ? r.f1 : r.f2);
        }
    return true;
}

// Re-measures the samples of a chosen flip's two faces against the new ones
// and gives each its new owner (before the flip is applied). A chosen
// collapse needs no such step: its legality test, run when its turn came,
// already moved its samples.
TETISO_HD inline void move_flip_samples(const RoundView& m, i32 e, i32* owner) {
    const EdgeSlots r = slots(m, e, false);
    double worst = 0.0;
    place_flip_samples(m, r, worst, [&](i32 sample, i32 t) { owner[sample] = t; });
}

} // namespace tetiso::reduction
