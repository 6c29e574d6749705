// tetiso as a library: the isosurface of each domain of a decomposed mesh is
// extracted and reduced on its own, then the pieces are merged by the edge
// keys of their vertices into one surface. Exits non-zero unless that
// surface is what the field's level set is, a closed, oriented torus, and
// smaller than the extracted one.
#include <cstddef>
#include <cstdio>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <tetiso/extract.hpp>
#include <tetiso/lattice.hpp>
#include <tetiso/reduce.hpp>
#include <tetiso/seam.hpp>

// The Euler characteristic V - E + F of a closed, consistently oriented
// surface; none if some edge is not run once in each direction (a hole, a
// fold, or pieces that failed to join).
static std::optional<long> euler_characteristic(const tetiso::Piece& surface) {
    std::map<std::pair<int, int>, int> runs; // directed edge -> triangles running it
    std::vector<bool> used(surface.vertex_count());
    for (std::size_t i = 0; i < surface.triangles.size(); ++i) {
        const int a = surface.triangles[i], b = surface.triangles[i % 3 == 2 ? i - 2 : i + 1];
        ++runs[{a, b}];
        used[static_cast<std::size_t>(a)] = true;
    }
    for (const auto& [edge, count] : runs) {
        const auto back = runs.find({edge.second, edge.first});
        if (count != 1 || back == runs.end() || back->second != 1) return std::nullopt;
    }
    long vertices = 0;
    for (const bool u : used) vertices += u;
    return vertices - static_cast<long>(runs.size() / 2) + static_cast<long>(surface.triangle_count());
}

int main() {
    // The built-in test problem: a 40^3-node lattice on [0,5]^3, split into
    // 8 box domains, with a field whose default level set is a torus.
    const tetiso::LatticePartition problem(40, 8, tetiso::make_field("torus"));
    const auto level = static_cast<float>(problem.field().default_level());

    tetiso::ReduceOptions options;
    // Every vertex of the extracted surface stays within a quarter of the
    // lattice spacing of the reduced one.
    options.max_error = 0.25 * problem.spacing();

    std::vector<tetiso::Piece> pieces;
    std::size_t extracted = 0;
    for (int d = 0; d < problem.domain_count(); ++d) {
        // One domain at a time, as a worker that holds only it would. The
        // vertices on its interfaces come out locked: reduction leaves them
        // exactly where the neighbouring domains' pieces have them too.
        const tetiso::Piece piece = tetiso::extract(problem.make_domain(d), level);
        extracted += piece.triangle_count();
        pieces.push_back(tetiso::reduce(piece, options));
    }
    // A vertex two pieces share carries the same key (its mesh edge's) in
    // both, so joining them compares keys, never coordinates. A job seams
    // instead (tetiso::seam), which also reduces along the interfaces.
    const tetiso::Piece surface = tetiso::merge_all(std::move(pieces));

    const std::optional<long> chi = euler_characteristic(surface);
    std::printf("%zu triangles extracted, %zu after reduction; ", extracted, surface.triangle_count());
    if (chi) std::printf("closed, Euler characteristic %ld\n", *chi);
    else std::printf("not closed\n");
    // A torus has characteristic 0, and reduction must have removed triangles.
    return chi && *chi == 0 && surface.triangle_count() < extracted ? 0 : 1;
}
