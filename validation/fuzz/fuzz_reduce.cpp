// The reduction's contract under arbitrary surfaces: a PLY file is read as
// `tetiso reduce` reads it and, if reduce() takes it, the result must keep
// what reduce.hpp promises for valid input: an oriented 2-manifold with each
// component's genus and boundary loops, no zero-area triangle that the input
// did not have, locked vertices where they were, keys sorted and unique, and
// every input vertex within max_error of the result. reduce() may refuse an
// input only with tetiso::Error; seeds are the PLY corpus, whose mutations
// keep a surface's connectivity and move its vertices.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"
#include "tetiso/reduce.hpp"

namespace {

// The checker's notion of a surface reduce() promises to keep: one edge
// between two triangles run in opposite directions, or on the border.
bool clean_manifold(const tetiso::TopologyReport& report) {
    return report.manifold && report.oriented && report.collapsed_triangles == 0 && report.duplicate_triangles == 0;
}

// The largest magnitude of a coordinate: the float spacing there bounds how
// far writing a position can move it.
double largest_coordinate(const tetiso::Piece& piece) {
    double largest = 0;
    for (const auto* axis : {&piece.x, &piece.y, &piece.z})
        for (const float value : *axis) largest = std::max(largest, std::fabs(double(value)));
    return largest;
}

double bounding_diagonal(const tetiso::Piece& piece) {
    double low[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, high[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    const std::vector<float>* axes[3] = {&piece.x, &piece.y, &piece.z};
    for (int axis = 0; axis < 3; ++axis)
        for (const float value : *axes[axis]) {
            low[axis] = std::min(low[axis], double(value));
            high[axis] = std::max(high[axis], double(value));
        }
    double sum = 0;
    for (int axis = 0; axis < 3; ++axis) sum += (high[axis] - low[axis]) * (high[axis] - low[axis]);
    return std::sqrt(sum);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = tetiso::fuzz::write_file("input.ply", tetiso::fuzz::bytes_of(data, size));
    tetiso::Piece in;
    try {
        in = tetiso::read_piece(path);
    } catch (const tetiso::Error&) {
        return 0;
    }
    // Large inputs only slow the search down: the contract does not depend
    // on size, and the corpus's surfaces are small.
    if (in.triangle_count() == 0 || in.triangle_count() > 20000) return 0;
    tetiso::TopologyReport before;
    try {
        before = tetiso::check_topology(in);
    } catch (const tetiso::Error&) {
        return 0;
    }
    // reduce() promises nothing for input that is not a clean oriented
    // manifold (it may refuse it or not notice), so such input tests only
    // that it neither crashes nor throws anything but tetiso::Error.
    const bool promised = clean_manifold(before);

    tetiso::ReduceOptions options;
    options.max_error = 0.05 * bounding_diagonal(in);
    tetiso::Piece out;
    try {
        out = tetiso::reduce(in, options);
    } catch (const tetiso::Error&) {
        return 0;
    }
    if (!promised) return 0;

    const tetiso::TopologyReport after = tetiso::check_topology(out);
    if (!clean_manifold(after)) __builtin_trap();
    if (!tetiso::same_signatures(before, after)) __builtin_trap();
    if (after.zero_area_triangles > before.zero_area_triangles) __builtin_trap();
    if (!std::is_sorted(out.key.begin(), out.key.end()) ||
        std::adjacent_find(out.key.begin(), out.key.end()) != out.key.end())
        __builtin_trap();
    // A locked vertex keeps its key and its position bit for bit.
    for (std::size_t v = 0; v < in.vertex_count(); ++v) {
        if (!(in.flags[v] & tetiso::kLocked)) continue;
        const auto found = std::lower_bound(out.key.begin(), out.key.end(), in.key[v]);
        if (found == out.key.end() || *found != in.key[v]) __builtin_trap();
        const auto w = static_cast<std::size_t>(found - out.key.begin());
        if (out.x[w] != in.x[v] || out.y[w] != in.y[v] || out.z[w] != in.z[v]) __builtin_trap();
    }
    if (out.triangle_count() > 0) {
        tetiso::HausdorffOptions exact;
        exact.vertices_only = true;
        // Positions are written in float: allow a few units of the last
        // place of the largest coordinate for their rounding.
        const double slack = 4 * std::ldexp(largest_coordinate(in), -23);
        if (tetiso::hausdorff(in, out, exact).forward > options.max_error + slack) __builtin_trap();
    }
    return 0;
}
