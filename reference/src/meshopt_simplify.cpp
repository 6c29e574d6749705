// The meshoptimizer baseline for reduction: a thin adapter from a Piece's
// structure of arrays to meshopt_simplify's interleaved positions and 32-bit
// index buffer, and back. meshopt_simplify only collapses vertices onto other
// existing vertices, so the result is a subset of the input's vertices; keeping
// them in input order keeps their keys sorted and unique.
#include <meshoptimizer.h>

#include <string>
#include <vector>

#include "tetiso/error.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {

Piece meshopt_simplify(const Piece& piece, std::size_t target_triangles, float target_error, bool lock_border,
                       float* result_error) {
    const std::size_t n = piece.vertex_count();
    if (piece.x.size() != n || piece.y.size() != n || piece.z.size() != n || piece.flags.size() != n)
        throw Error("meshopt_simplify: vertex arrays of the piece differ in length");
    if (piece.triangles.size() % 3 != 0)
        throw Error("meshopt_simplify: triangle array is not a multiple of 3");

    std::vector<float> positions(3 * n);
    for (std::size_t v = 0; v < n; ++v) {
        positions[3 * v] = piece.x[v];
        positions[3 * v + 1] = piece.y[v];
        positions[3 * v + 2] = piece.z[v];
    }
    std::vector<unsigned int> indices(piece.triangles.size());
    for (std::size_t i = 0; i < indices.size(); ++i) {
        const std::int32_t corner = piece.triangles[i];
        if (corner < 0 || static_cast<std::size_t>(corner) >= n)
            throw Error("meshopt_simplify: triangle " + std::to_string(i / 3) + " refers to vertex " +
                        std::to_string(corner) + ", the piece has " + std::to_string(n));
        indices[i] = static_cast<unsigned int>(corner);
    }

    // meshoptimizer's worst case is no reduction at all, so the destination
    // must hold every input index.
    std::vector<unsigned int> kept(indices.size());
    float error = 0.0f;
    const std::size_t kept_count = ::meshopt_simplify(
        kept.data(), indices.data(), indices.size(), positions.data(), n, 3 * sizeof(float), 3 * target_triangles,
        target_error, lock_border ? static_cast<unsigned int>(meshopt_SimplifyLockBorder) : 0u, &error);
    kept.resize(kept_count);
    if (result_error != nullptr) *result_error = error;

    // Compact to the vertices still referenced, in input order.
    std::vector<std::int32_t> renumber(n, -1);
    for (const unsigned int v : kept) renumber[v] = 0;
    Piece out;
    out.domains = piece.domains;
    for (std::size_t v = 0; v < n; ++v) {
        if (renumber[v] < 0) continue;
        renumber[v] = static_cast<std::int32_t>(out.key.size());
        out.x.push_back(piece.x[v]);
        out.y.push_back(piece.y[v]);
        out.z.push_back(piece.z[v]);
        out.key.push_back(piece.key[v]);
        out.flags.push_back(piece.flags[v]);
    }
    out.triangles.resize(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) out.triangles[i] = renumber[kept[i]];
    return out;
}

} // namespace tetiso::reference
