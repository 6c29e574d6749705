// Seaming pieces by their vertex keys (paper, section "Isosurface reduction
// and seaming"): two pieces get one numbering by merging their key-sorted
// vertex lists; no coordinates are compared. A vertex keyed by the same edge
// in both pieces becomes one vertex.
// Contract (docs/ARCHITECTURE.md, "Contracts"): pieces that are clean as
// written (extract.hpp, reduce.hpp) seam and reduce into a surface that is
// clean as written too, with each component's signature that of the
// unreduced surface.
#pragma once

#include <functional>
#include <vector>

#include "tetiso/mesh.hpp"
#include "tetiso/partition.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

// Merges two pieces covering disjoint sets of domains. Throws tetiso::Error if
// they share a domain, or if a key appears in both with different positions
// (the pieces were not extracted consistently). `threads` (0: all cores)
// never changes the result.
Piece merge_by_key(const Piece& a, const Piece& b, int threads = 1);

// Merges any number of pieces, pairwise in a balanced tree, and puts the
// triangles in canonical order (order_triangles): the result does not depend
// on the order of `pieces`, nor on how a surface was cut into them (the
// lattice's surface is the same bytes for any number of domains).
Piece merge_all(std::vector<Piece> pieces);

// Each triangle rotated to start at its smallest vertex index (its
// orientation kept), the triangles sorted by their three indices, and the
// per-triangle arrays (error, sampled, sample_triangle) carried along. As the
// vertices are in key order, two pieces with the same vertices and oriented
// triangles become the same arrays, however they were put together.
void order_triangles(Piece& piece);

// Clears kLocked on every vertex whose edge lies in no domain outside
// `piece.domains`: its neighbourhood is complete, so reduction may touch it.
// Returns the number of vertices unlocked. With threads > 1 (0: all cores)
// domains_of_edge is called from that many threads at once.
std::size_t unlock_settled(Piece& piece, const EdgeDomains& domains_of_edge, int threads = 1);

// What reduces a region: tetiso::reduce when empty, or another function with
// the same result (a Gpu's reduce).
using Reducer = std::function<Piece(const Piece&, const ReduceOptions&, ReduceReport*)>;

struct SeamOptions {
    bool reduce = true;
    ReduceOptions reduce_options;
    Reducer reducer; // empty: tetiso::reduce
    // How far from the seam the reduction reaches, in edges. The rest of
    // the piece was reduced before and is left exactly as it is. Because
    // the seam re-measures the raw vertices it carries (sample_rings), one
    // ring reduces about as far as more would, for less work.
    int rings = 1;
    // The raw-vertex samples (Piece::sample_xyz) a seam's result keeps: those
    // of the triangles within sample_rings edges of a vertex still locked,
    // where a later seam's region reaches. Farther ones are dropped (their
    // triangles' errors still bound them): a later seam's region that
    // reaches such a triangle measures the whole triangle instead, spending
    // only what its error left of the budget. More rings keep more samples
    // (larger pieces to send) for a few fewer triangles; < 0 drops them all.
    int sample_rings = 1;
};

// Drops the samples of every triangle with no vertex within `rings` edges of
// a locked vertex (all of them when no vertex is locked, or rings < 0).
// `threads` (0: all cores) never changes the result.
void keep_samples_near_locked(Piece& piece, int rings, int threads = 1);

struct SeamReport {
    std::size_t vertices_unlocked = 0;
    std::size_t region_triangles = 0; // triangles handed to the reduction
    ReduceReport reduce;
    // Wall-clock seconds of each step: merging by key and unlocking what the
    // merge settled; finding the region near the seam and copying it out;
    // reducing it; splicing it back into the piece. The steps other than the
    // reduction pass over the whole piece: they are what a seam costs beyond
    // its neighbourhood.
    struct Seconds {
        double merge = 0, region = 0, reduce = 0, splice = 0;
    } seconds;
};

// The seaming task of the paper: merge two pieces by key, unlock what the
// merge settled, and reduce again near the seam only. The reduction sees the
// triangles within `rings` edges of the unlocked vertices, with the region's
// rim locked and the triangles around the rim for its tests to read (locked,
// unchanged), and its result is spliced back by key; its cost is that of the
// seam's neighbourhood (plus a few linear passes to find it), not the piece's.
// The result depends only on the two pieces, never on who seams them or when.
// The linear passes run on options.reduce_options.threads, and so may the
// calls of domains_of_edge (unlock_settled).
Piece seam(const Piece& a, const Piece& b, const EdgeDomains& domains_of_edge, const SeamOptions& options = {},
           SeamReport* report = nullptr);

// Reduces a domain's piece, keeping its raw vertices as samples: the whole
// of it where it is a 2-manifold, which a box domain's piece always is. A
// domain of an unstructured partition may touch itself along an edge, and
// its piece then has two fans at the vertex on that edge (locked, since the
// edge is shared); all but the triangles around such vertices is reduced
// then, by reduce_near's rules, and they wait for the seam that completes
// them.
Piece reduce_piece(const Piece& piece, const ReduceOptions& options, ReduceReport* report = nullptr,
                   const Reducer& reducer = {});

// Reduces `piece` near the vertices marked in `seed` (see seam); exposed for
// tests and for callers that unlock vertices by other means.
Piece reduce_near(const Piece& piece, const std::vector<std::uint8_t>& seed, const SeamOptions& options,
                  SeamReport* report = nullptr);

} // namespace tetiso
