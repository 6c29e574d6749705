// A batch of pieces reduced side by side (reduce_batch in reduce.hpp): the
// pieces laid one after the other in the same arrays, every round serving
// all of them, so that the fixed cost of a round (on a GPU, its launches and
// its waits for sizes) is paid once for the batch.
//
// Each piece comes out byte for byte as reduce() gives it alone, because
// nothing of a round compares or sums elements of two pieces:
// - concatenation keeps the relative order of a piece's vertices, triangles
//   and samples, and shifts their indices by a constant, so every tie-break
//   by index (a fan's first triangle, an edge's smaller end, the priority
//   order's vertex ties, a sample's first triangle) decides as alone;
// - pieces share no vertex, so no operation of one conflicts with one of
//   another, and the sequential choice (selection.hpp) restricted to a
//   piece is the piece's own; legality, Φ and the samples read a piece's
//   own elements only (the contact test's grid, contact_filter.hpp, holds
//   every piece's triangles in cells sized for the batch, but judges a face
//   against its own piece's faces only, and its answer does not depend on
//   the cell size);
// - compaction keeps the order of what survives, so pieces stay contiguous;
//   the samples' grouping by owner is stable, so it restores each piece's;
// - the stopping rule is kept per piece (rounds.hpp): a finished piece is
//   frozen, its edges quiet, nothing applied to it and nothing compacted
//   away, while the others go on. A frozen piece's samples are still
//   regrouped by owner each round, which changes nothing of what is handed
//   on (a stable grouping of a stable grouping is the same grouping).
// Border vertices of neighbouring domains share keys: keys are only ever
// compared within a piece (a piece's keys are sorted; the batch's need not
// be).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "rounds.hpp"

namespace tetiso::reduction {

// The samples of a raw piece as build_raw_samples makes them on the device:
// each vertex used by a triangle, in vertex order, owned by the first
// triangle that uses it.
inline HostSamples raw_samples_of(const Piece& in) {
    HostSamples h;
    std::vector<i32> first(in.vertex_count(), std::numeric_limits<i32>::max());
    for (std::size_t c = 0; c < in.triangles.size(); ++c) {
        i32& f = first[static_cast<std::size_t>(in.triangles[c])];
        f = std::min(f, static_cast<i32>(c / 3));
    }
    for (std::size_t v = 0; v < first.size(); ++v) {
        if (first[v] == std::numeric_limits<i32>::max()) continue;
        h.point.push_back({in.x[v], in.y[v], in.z[v], 0.0f});
        h.owner.push_back(first[v]);
        h.far.push_back(-1);
    }
    return h;
}

// Loads pieces (each checked by the caller) side by side into the state.
template <class Exec>
void load_pieces(Exec& exec, const std::vector<Piece>& pieces, bool bounded, ReductionState<Exec>& st) {
    std::size_t nv = 0, nt = 0;
    bool raw = true; // every piece is raw: the device builds the samples of all
    for (const Piece& p : pieces) {
        nv += p.vertex_count();
        nt += p.triangle_count();
        raw = raw && p.error.empty();
    }
    std::vector<float> xyz, err;
    std::vector<EdgeKey> key;
    std::vector<u8> flags;
    std::vector<i32> tri, vertex_piece;
    xyz.reserve(3 * nv);
    key.reserve(nv);
    flags.reserve(nv);
    vertex_piece.reserve(nv);
    tri.reserve(3 * nt);
    err.reserve(nt);
    HostSamples samples;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const Piece& p = pieces[i];
        const auto vertex_base = static_cast<i32>(key.size()), triangle_base = static_cast<i32>(err.size());
        for (std::size_t v = 0; v < p.vertex_count(); ++v) xyz.insert(xyz.end(), {p.x[v], p.y[v], p.z[v]});
        key.insert(key.end(), p.key.begin(), p.key.end());
        if (p.flags.empty()) flags.resize(flags.size() + p.vertex_count(), u8{0});
        else flags.insert(flags.end(), p.flags.begin(), p.flags.end());
        vertex_piece.resize(vertex_piece.size() + p.vertex_count(), static_cast<i32>(i));
        for (const i32 v : p.triangles) tri.push_back(v + vertex_base);
        if (p.error.empty()) err.resize(err.size() + p.triangle_count(), 0.0f);
        else err.insert(err.end(), p.error.begin(), p.error.end());
        if (!bounded || raw) continue;
        const HostSamples h = p.error.empty() ? raw_samples_of(p) : samples_of_reduced_input(p);
        const auto far_base = static_cast<i32>(samples.far_point.size() / 2);
        samples.point.insert(samples.point.end(), h.point.begin(), h.point.end());
        for (const i32 t : h.owner) samples.owner.push_back(t + triangle_base);
        for (const i32 f : h.far) samples.far.push_back(f < 0 ? f : f + far_base);
        samples.far_point.insert(samples.far_point.end(), h.far_point.begin(), h.far_point.end());
    }
    Surface<Exec>& s = st.s;
    exec.upload(xyz, s.xyz);
    exec.upload(key, s.key);
    exec.upload(flags, s.flags);
    exec.upload(tri, s.tri);
    exec.upload(err, s.err);
    s.nv = static_cast<i32>(nv);
    s.nt = static_cast<i32>(nt);
    st.pieces = static_cast<i32>(pieces.size());
    exec.upload(vertex_piece, st.vertex_piece);
    st.fans.faulty = -1;
    st.samples.on = false;
    if (!bounded) return;
    if (raw) {
        build_raw_samples(exec, s.view(), st.samples, st.scratch, st.rank);
        return;
    }
    upload_samples(exec, samples, st);
}

// Entries [stride * begin, stride * end) of a piece's array.
template <class T>
std::vector<T> range(const std::vector<T>& from, std::size_t begin, std::size_t end, std::size_t stride = 1) {
    return std::vector<T>(from.begin() + static_cast<std::ptrdiff_t>(stride * begin),
                          from.begin() + static_cast<std::ptrdiff_t>(stride * end));
}

// The reduced batch split back into its pieces (st.pieces of them), each
// as unload_piece gives it alone.
template <class Exec>
std::vector<Piece> unload_pieces(Exec& exec, ReductionState<Exec>& st, bool keep_samples) {
    const auto count = static_cast<std::size_t>(st.pieces);
    if (count == 1) return {unload_piece(exec, st, keep_samples)};
    const Piece all = unload_piece(exec, st, keep_samples);
    std::vector<i32> vertex_piece;
    exec.download(st.vertex_piece, st.s.nv, vertex_piece);
    // Pieces stay contiguous and in order: where each begins.
    std::vector<std::size_t> vertex_begin(count + 1, 0), triangle_begin(count + 1, 0), sample_begin(count + 1, 0);
    for (const i32 p : vertex_piece) ++vertex_begin[static_cast<std::size_t>(p) + 1];
    for (std::size_t t = 0; t < all.triangle_count(); ++t)
        ++triangle_begin[static_cast<std::size_t>(vertex_piece[static_cast<std::size_t>(all.triangles[3 * t])]) + 1];
    for (const i32 t : all.sample_triangle)
        ++sample_begin[static_cast<std::size_t>(vertex_piece[static_cast<std::size_t>(all.triangles[3 * static_cast<std::size_t>(t)])]) + 1];
    for (std::size_t p = 0; p < count; ++p) {
        vertex_begin[p + 1] += vertex_begin[p];
        triangle_begin[p + 1] += triangle_begin[p];
        sample_begin[p + 1] += sample_begin[p];
    }
    std::vector<Piece> out(count);
    for (std::size_t p = 0; p < count; ++p) {
        Piece& o = out[p];
        const std::size_t v0 = vertex_begin[p], v1 = vertex_begin[p + 1];
        const std::size_t t0 = triangle_begin[p], t1 = triangle_begin[p + 1];
        const std::size_t s0 = sample_begin[p], s1 = sample_begin[p + 1];
        o.x = range(all.x, v0, v1);
        o.y = range(all.y, v0, v1);
        o.z = range(all.z, v0, v1);
        o.key = range(all.key, v0, v1);
        o.flags = range(all.flags, v0, v1);
        o.triangles = range(all.triangles, t0, t1, 3);
        for (i32& v : o.triangles) v -= static_cast<i32>(v0);
        o.error = range(all.error, t0, t1);
        if (all.sampled.empty()) continue;
        o.sample_xyz = range(all.sample_xyz, s0, s1, 3);
        o.sample_triangle = range(all.sample_triangle, s0, s1);
        for (i32& t : o.sample_triangle) t -= static_cast<i32>(t0);
        o.sampled = range(all.sampled, t0, t1);
    }
    return out;
}

} // namespace tetiso::reduction
