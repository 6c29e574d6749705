// Isosurface extraction by marching tetrahedra (paper, section "Isosurface
// generation algorithm", steps 1-6), with the consistency rules that make
// pieces from different domains fit together exactly:
//  - a node whose value equals the level counts as above it, whatever domain
//    holds it (instead of the paper's domain-dependent epsilon shift);
//  - a crossing is interpolated from the end with the smaller global id, so
//    every domain computes bit-identical positions for a shared vertex;
//  - triangle orientation follows from the field alone: normals point towards
//    increasing values;
//  - each vertex is keyed by its global edge id and locked when its edge lies
//    on an interface of the domain;
//  - a crossing keeps clear of its edge's ends by a few dozen ulps of the
//    edge's coordinates (extract_rules.hpp, node_clearance), so that the
//    crossings of the edges through a node at or near the level never share
//    a float position.
// Contract (docs/ARCHITECTURE.md, "Contracts"): the piece, and any union of
// pieces merged by key, is clean as written in float32: no zero-area
// triangle, no two vertices at one position, no self-intersection, an
// oriented manifold (`tetiso check --strict`).
#pragma once

#include "tetiso/device.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso {

struct ExtractOptions {
    // Threads to use inside the domain; 0 means OpenMP's default. The output
    // does not depend on it.
    int threads = 1;
    // Where it runs; the output does not depend on it either.
    Device device{};
};

// Throws tetiso::Error if a field value is not finite or a tetrahedron refers
// to a node that does not exist (the same messages on every device). Adds
// its seconds to seconds->upload, ->extract and ->download where set.
Piece extract(const Domain& domain, float level, const ExtractOptions& options = {}, StageSeconds* seconds = nullptr);

} // namespace tetiso
