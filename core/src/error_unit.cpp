#include "tetiso/error_unit.hpp"

#include <cmath>

namespace tetiso {

double mean_edge_length(const Piece& piece) {
    double sum = 0;
    for (std::size_t t = 0; t < piece.triangle_count(); ++t)
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>((k + 1) % 3)]);
            sum += std::hypot(piece.x[a] - piece.x[b], piece.y[a] - piece.y[b], piece.z[a] - piece.z[b]);
        }
    return piece.triangle_count() ? sum / static_cast<double>(3 * piece.triangle_count()) : 0.0;
}

} // namespace tetiso
