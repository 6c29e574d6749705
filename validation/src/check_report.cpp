#include "tetiso/check_report.hpp"

#include <optional>
#include <vector>

#include "tetiso/check.hpp"

namespace tetiso {

nlohmann::json check_report(const Piece& surface, const Piece* reference, const CheckReportOptions& options) {
    const TopologyReport topology = check_topology(surface);
    nlohmann::json out = {{"topology", to_json(topology)}};
    std::optional<std::vector<TrianglePair>> crossings;
    if (options.self_intersections && have_self_intersections()) {
        crossings = find_self_intersections(surface);
        out["self_intersections"] = crossings ? nlohmann::json(crossings->size()) : nlohmann::json(nullptr);
        if (crossings) out["topology"]["where"]["self_intersections"] = to_json(*crossings, surface);
    }
    std::optional<TopologyReport> reference_topology;
    if (reference) {
        reference_topology = check_topology(*reference);
        out["against"] = {
            {"same_signatures", same_signatures(topology, *reference_topology)},
            {"reference_topology", to_json(*reference_topology)},
            {"hausdorff", to_json(hausdorff(surface, *reference, HausdorffOptions{.vertices_only = options.vertices_only}))},
        };
    }
    if (options.strict) {
        std::vector<std::string> violations =
            contract_violations(surface, topology, crossings, reference_topology ? &*reference_topology : nullptr);
        if (options.self_intersections && !have_self_intersections())
            violations.push_back("self-intersections: not checked, this tetiso was built without CGAL (" +
                                 options.skip_self_intersections + " gates without them)");
        out["violations"] = violations;
    }
    return out;
}

} // namespace tetiso
