// Shared operations on the flat mesh types.
#include "tetiso/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace tetiso {

bool order_by_key(Piece& piece) {
    const std::size_t n = piece.vertex_count();
    if (!std::is_sorted(piece.key.begin(), piece.key.end())) {
        std::vector<std::int32_t> order(n);
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
            return piece.key[static_cast<std::size_t>(a)] < piece.key[static_cast<std::size_t>(b)];
        });
        std::vector<std::int32_t> rank(n);
        for (std::size_t i = 0; i < n; ++i) rank[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
        auto permute = [&](auto& values) {
            auto copy = values;
            for (std::size_t i = 0; i < n; ++i) values[i] = copy[static_cast<std::size_t>(order[i])];
        };
        permute(piece.x);
        permute(piece.y);
        permute(piece.z);
        permute(piece.key);
        permute(piece.flags);
        for (auto& corner : piece.triangles) corner = rank[static_cast<std::size_t>(corner)];
    }
    return std::adjacent_find(piece.key.begin(), piece.key.end()) == piece.key.end();
}

double mean_edge_length(const Domain& domain) {
    double sum = 0;
    for (std::size_t t = 0; t < domain.tet_count(); ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b) {
                const auto i = static_cast<std::size_t>(domain.tets[4 * t + static_cast<std::size_t>(a)]);
                const auto j = static_cast<std::size_t>(domain.tets[4 * t + static_cast<std::size_t>(b)]);
                const double dx = domain.x[i] - domain.x[j], dy = domain.y[i] - domain.y[j],
                             dz = domain.z[i] - domain.z[j];
                sum += std::sqrt(dx * dx + dy * dy + dz * dz);
            }
    return domain.tet_count() ? sum / static_cast<double>(6 * domain.tet_count()) : 0.0;
}

} // namespace tetiso
