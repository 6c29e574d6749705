// Isosurface reduction (paper, section "Isosurface reduction and seaming"):
// rounds of parallel edge collapse and edge flip driven by the Φ criterion.
//
// Each round computes Φ for every edge from the two leaves (the fans of faces
// around its ends), turns the edges whose Φ exceeds Φ* — and the paper's
// special branches: very short edges, valence-3 vertices, border edges, flips
// of long edges between narrow triangles — into candidate operations, drops
// those that would change the topology or spoil the geometry, picks an
// independent set of them (no two at path length below 2) in parallel and
// deterministically, and applies it. Rounds repeat until no candidate is left,
// two rounds in a row collapse nothing, or max_rounds is reached.
//
// Guarantees (for valid input): every component keeps its genus and its
// boundary loops, the surface stays a consistently oriented 2-manifold, no
// triangle of zero area is created (those of the input are removed where the
// topology allows), vertices flagged kLocked keep their position bit for bit
// and are never removed, border vertices stay on the border, vertex keys stay
// sorted and unique. The output does not depend on the thread count.
// Contract (docs/ARCHITECTURE.md, "Contracts"): given a surface clean as
// written in float32 (extract.hpp), the result is clean as written too: no
// zero-area triangle, no two vertices at one position, no self-intersection;
// legality is judged on the float positions that will be written. Each new
// triangle is tested against every triangle near it, not only those sharing
// a corner: the round's, the new ones of the operations chosen with it, and
// `obstacles`. Not tested: triangles that are neither in the piece nor in
// `obstacles`.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "tetiso/device.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

struct ReduceOptions {
    // Φ*: an edge is collapsed when Φ > phi. Φ is a cosine-like measure of how
    // flat (or evenly bent along the edge) the two leaves are: 1 for a flat
    // fan, cos(α) when a face of a leaf turns by α from its side's reference
    // face. Valid range (0, 1]. The default 0.9 lets a leaf bend by about 25°.
    // With max_error set, the bound usually stops a reduction before phi does.
    double phi = 0.9;
    // Threads, in [0, kMaxThreads]; 0 means OpenMP's default. The output does
    // not depend on it. A round uses at most 16 of them, offered more or not,
    // since its steps are short and their joins would cost more than they
    // share.
    int threads = 1;
    // Where set, asked before every round for the threads that round may use
    // (0 or less: keep the current count); lets a job hand a running
    // reduction the cores of workers that ran out of work.
    std::function<int()> more_threads;
    // Where the rounds run; the output does not depend on it. threads and
    // more_threads apply to the host.
    Device device{};
    // Upper bound on the number of rounds (>= 0).
    int max_rounds = 200;
    // Smallest angle of the new triangles: a collapse or flip may not make
    // the smallest angle of the region it changes smaller than
    // min(min_angle_degrees, that region's smallest angle before), so
    // collapses that clean up degenerate triangles stay possible but no
    // operation creates a triangle worse than the bound out of good ones
    // (a needle a few dozen ulps wide, an artefact of where extraction put
    // its corners near a mesh node, is held to an area float resolves
    // instead).
    // 1 degree is the checker's "near degenerate" line; larger bounds keep
    // more triangles and remove few more bad ones. Valid range [0, 30].
    double min_angle_degrees = 1.0;
    // Absolute bound on the distance from every vertex of the input to the
    // reduced surface: every input vertex is tracked, so the bound is exact
    // at them. An input reduced before (Piece::error set) stands for raw
    // vertices it no longer has: then every point of each input triangle is
    // tracked, its distance plus the triangle's error kept under the bound,
    // so the bound holds at the raw vertices over any number of reductions.
    // Between raw vertices the two surfaces can part further, so the
    // symmetric Hausdorff distance may exceed max_error; the command line's
    // default, 0.25 h (h the lattice spacing), keeps it within 0.5 h on
    // marching-tets surfaces. Units: those of the coordinates. <= 0 means no
    // bound (Φ alone decides); NaN throws tetiso::Error.
    double max_error = 0.0;
    // With max_error > 0: hand the samples on in the output
    // (Piece::sample_xyz), those of every triangle that stands only for raw
    // vertices, so that a later reduction of the same region (a seam's)
    // measures the raw vertices again rather than adding its bound to this
    // one's.
    bool keep_samples = false;
    // No surviving triangle of a collapse may turn its normal by more than this.
    double max_normal_turn_degrees = 45.0;
    // An edge shorter than short_edge_ratio times the mean length of the other
    // edges of its two faces (or of length 0) is collapsed whatever Φ is.
    double short_edge_ratio = 0.1;
    // Edge flips: an interior edge between two faces that are coplanar within
    // flip_max_dihedral_degrees is flipped when that raises the smaller
    // minimum angle of the two faces by more than 20 %.
    bool flips = true;
    double flip_max_dihedral_degrees = 10.0;
    // The test of each new face against the faces near it that share no
    // corner with it (the contract's "no self-intersection" where a surface
    // folds back close to itself). Off, a reduction costs about half as
    // much, and its result may cross itself where two sheets come within a
    // fan's size of each other.
    bool contact_test = true;
    // Triangles beside the piece, not part of it (nine coordinates each, x,
    // y, z of three corners): no new triangle may meet one, other than at a
    // corner it shares with it by position. A seam reducing a region of a
    // surface passes the rest of the surface around the region, so that the
    // region cannot be pushed through it.
    std::vector<float> obstacles;
};

struct ReduceRound {
    int round = 0;
    // Operations offered to the selection: every possible collapse (its Φ
    // still unknown) and every flip proposed.
    std::size_t candidates = 0;
    // Operations whose answer was computed: the collapses no longer pending
    // at the end of the round (Φ and position computed when the selection
    // reached them, or valence-3 collapses, complete when classified), plus
    // the flips proposed.
    std::size_t evaluated = 0;
    std::size_t collapses = 0;
    std::size_t flips = 0;
    // Steps of the choice by reservations, collapses and flips together (0
    // where the host swept in order): what a round waits for on a GPU.
    std::size_t selection_steps = 0;
    // Times the collapses' steps ran: more than once where a collapse they
    // chose was then found to move a sample too far (on a GPU, which places
    // samples only for the collapses the steps decide, in large rounds).
    std::size_t selection_passes = 0;
    // The surface at the start of the round.
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    // Vertices that outlive the round and whose fan it altered (a face
    // removed, rewritten or moved): what the next round's fans, edges and
    // normals would have to redo if they were updated rather than rebuilt.
    std::size_t changed_vertices = 0;
    double seconds = 0.0; // wall clock, every step of the round
};

// Wall-clock seconds spent in each step of the rounds, summed over rounds:
// the reduce stage of StageSeconds taken apart (for profiling; see
// rounds.hpp for the steps).
struct ReduceStageSeconds {
    double fans = 0, edges = 0, geometry = 0, propose = 0, select = 0, contact = 0, apply = 0, compact = 0;
};

struct ReduceReport {
    std::size_t triangles_in = 0, triangles_out = 0;
    std::size_t vertices_in = 0, vertices_out = 0;
    std::vector<ReduceRound> rounds;
    double seconds = 0.0; // the whole call, input checks included
    ReduceStageSeconds stages;
};

// Reduces a triangulated piece. The input must be an oriented 2-manifold with
// or without border (each edge in one or two triangles, two triangles run an
// edge in opposite directions, the triangles around a vertex form a single
// fan), with finite coordinates and keys sorted ascending and unique.
// Vertices used by no triangle are kept as they are.
// Throws tetiso::Error for options outside their valid range and for input
// that breaks these rules, naming the element (e.g. "edge (key a, key b) has
// 3 triangles"), the same on every device. Adds its seconds to
// seconds->upload, ->reduce and ->download where set.
Piece reduce(const Piece& in, const ReduceOptions& options = {}, ReduceReport* report = nullptr,
             StageSeconds* seconds = nullptr);

// Reduces several pieces side by side: one set of rounds serves all of them
// (on a GPU the fixed cost of a round, its launches and its waits, is then
// paid once for the batch), and each piece stops when it would alone. Each
// result is byte for byte reduce(pieces[i], options), for any thread count
// and device; the report is the batch's (its rounds, every piece's
// triangles). Throws tetiso::Error for bad options as reduce() does, and for
// a piece reduce() would refuse with reduce()'s message naming the piece
// ("tetiso::reduce_batch: piece 3: ..."). A batch must fit where it runs:
// on a GPU, all of its pieces and their rounds' arrays at once.
std::vector<Piece> reduce_batch(const std::vector<Piece>& pieces, const ReduceOptions& options = {},
                                ReduceReport* report = nullptr, StageSeconds* seconds = nullptr);

} // namespace tetiso
