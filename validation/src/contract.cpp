// The surface contract as a gate (check.hpp, contract_violations): what
// `tetiso check --strict` and the soundness soak fail on. Each clause is one
// line naming the count and where the first instance is, so that a CI log
// says what broke and where to look without the JSON.
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "tetiso/check.hpp"

namespace tetiso {

namespace {

std::string point(const std::array<double, 3>& at) {
    char text[96];
    std::snprintf(text, sizeof text, "(%.9g, %.9g, %.9g)", at[0], at[1], at[2]);
    return text;
}

std::string vertex_list(const std::vector<std::int32_t>& vertices) {
    std::string out;
    for (std::size_t i = 0; i < vertices.size(); ++i) out += (i ? ", " : "") + std::to_string(vertices[i]);
    return out;
}

std::string first_spot(const std::vector<ProblemSpot>& spots, const char* what) {
    if (spots.empty()) return "";
    const ProblemSpot& s = spots.front();
    if (s.triangle >= 0) return "; the first is triangle " + std::to_string(s.triangle) + " at " + point(s.at);
    return std::string("; the first is ") + what + " " + vertex_list(s.vertices) + " at " + point(s.at);
}

std::string plural(std::int64_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

// A multiset of signatures as "2 × (genus 0, 0 boundary loops), …".
std::string describe(const std::vector<TopologySignature>& signatures) {
    if (signatures.empty()) return "no component";
    std::map<TopologySignature, int> count;
    for (const TopologySignature& s : signatures) ++count[s];
    std::string out;
    for (const auto& [s, n] : count) {
        if (!out.empty()) out += ", ";
        out += std::to_string(n) + " × (" + (s.orientable ? "genus " : "non-orientable, cross-caps ") +
               std::to_string(s.genus) + ", " + plural(s.boundary_loops, "boundary loop", "boundary loops") + ")";
    }
    return out;
}

} // namespace

std::array<double, 3> triangle_centroid(const Piece& mesh, std::int64_t triangle) {
    std::array<double, 3> at{};
    for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(3 * triangle + c)]);
        at[0] += mesh.x[v] / 3.0;
        at[1] += mesh.y[v] / 3.0;
        at[2] += mesh.z[v] / 3.0;
    }
    return at;
}

std::vector<std::string> contract_violations(const Piece& mesh, const TopologyReport& r,
                                             const std::optional<std::vector<TrianglePair>>& self_intersections,
                                             const TopologyReport* reference) {
    std::vector<std::string> lines;
    if (r.degenerate_triangles > 0)
        lines.push_back("degenerate triangles: " + std::to_string(r.degenerate_triangles) + " (" +
                        std::to_string(r.collapsed_triangles) + " collapsed, " +
                        std::to_string(r.zero_area_triangles) + " of zero area)" +
                        first_spot(r.where.degenerate_triangles, "triangle"));
    if (r.duplicate_positions > 0)
        lines.push_back("duplicate positions: " +
                        plural(r.duplicate_positions, "vertex repeats", "vertices repeat") +
                        " the position of another" + first_spot(r.where.duplicate_positions, "vertices"));
    if (self_intersections && !self_intersections->empty()) {
        const TrianglePair& p = self_intersections->front();
        lines.push_back("self-intersections: " +
                        plural(static_cast<std::int64_t>(self_intersections->size()), "pair", "pairs") +
                        " of triangles cross; the first is triangles " + std::to_string(p.first) + " and " +
                        std::to_string(p.second) + " at " + point(triangle_centroid(mesh, p.first)));
    }
    if (r.duplicate_triangles > 0)
        lines.push_back("duplicate triangles: " + plural(r.duplicate_triangles, "triangle repeats", "triangles repeat") +
                        " the corners of another");
    if (!r.manifold) {
        std::string where = first_spot(r.where.non_manifold_edges, "edge");
        if (where.empty()) where = first_spot(r.where.non_manifold_vertices, "vertex");
        lines.push_back("non-manifold: " + plural(r.non_manifold_edges, "edge", "edges") + " of 3 or more triangles, " +
                        plural(r.non_manifold_vertices, "vertex", "vertices") + " pinched" + where);
    }
    if (!r.oriented || !r.orientable) {
        std::int64_t non_orientable = 0;
        for (const ComponentReport& c : r.per_component) non_orientable += !c.orientable;
        lines.push_back("orientation: " + plural(r.misoriented_edges, "edge is", "edges are") +
                        " run the same way by both their triangles" +
                        (non_orientable ? ", " + plural(non_orientable, "component is", "components are") +
                                              " not orientable"
                                        : "") +
                        first_spot(r.where.misoriented_edges, "edge"));
    }
    if (reference && !same_signatures(r, *reference))
        lines.push_back("signatures: the components are " + describe(r.signatures) + ", the reference's " +
                        describe(reference->signatures));
    return lines;
}

nlohmann::json to_json(const std::vector<TrianglePair>& pairs, const Piece& mesh) {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t i = 0; i < pairs.size() && i < kMaxProblemSpots; ++i)
        out.push_back({{"triangles", {pairs[i].first, pairs[i].second}},
                       {"at", triangle_centroid(mesh, pairs[i].first)}});
    return out;
}

} // namespace tetiso
