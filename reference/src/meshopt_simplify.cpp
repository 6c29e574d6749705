// The meshoptimizer baseline for reduction: a thin adapter from a Piece's
// structure of arrays to meshopt_simplify's interleaved positions and 32-bit
// index buffer, and back. meshopt_simplify only collapses vertices onto other
// existing vertices, so the result is a subset of the input's vertices; keeping
// them in input order keeps their keys sorted and unique.
#include <meshoptimizer.h>

#include <vector>

#include "reference_piece.hpp"
#include "tetiso/reference.hpp"

namespace tetiso::reference {

Piece meshopt_simplify(const Piece& piece, std::size_t target_triangles, float target_error, bool lock_border,
                       float* result_error) {
    check_piece_arrays("meshopt_simplify", piece);
    const std::size_t n = piece.vertex_count();
    std::vector<float> positions(3 * n);
    for (std::size_t v = 0; v < n; ++v) {
        positions[3 * v] = piece.x[v];
        positions[3 * v + 1] = piece.y[v];
        positions[3 * v + 2] = piece.z[v];
    }
    const std::vector<unsigned int> indices(piece.triangles.begin(), piece.triangles.end());

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
    Piece out = survivors(piece, renumber, [&](std::size_t v, float& x, float& y, float& z) {
        x = piece.x[v];
        y = piece.y[v];
        z = piece.z[v];
    });
    out.triangles.resize(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) out.triangles[i] = renumber[kept[i]];
    return out;
}

} // namespace tetiso::reference
