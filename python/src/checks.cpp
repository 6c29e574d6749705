// tetiso.check: `tetiso check` on a Surface in memory, the same report as a
// dict (the JSON the CLI prints, less the "file" names it has no file for),
// from the same checker functions put together in the same way
// (core/cli/check_command.cpp).
#include <optional>

#include "module.hpp"
#include "tetiso/check.hpp"
#include "tetiso/error.hpp"

namespace tetiso::python {
namespace {

std::string check_report(const Piece& surface, const Piece* reference, bool self_intersections, bool vertices_only,
                         bool strict) {
    if (vertices_only && !reference) throw Error("check: vertices_only applies with against");
    nlohmann::json out;
    {
        py::gil_scoped_release unlocked;
        const TopologyReport topology = check_topology(surface);
        out = {{"topology", to_json(topology)}};
        std::optional<std::vector<TrianglePair>> crossings;
        if (self_intersections && have_self_intersections()) {
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
                {"hausdorff", to_json(hausdorff(surface, *reference, HausdorffOptions{.vertices_only = vertices_only}))},
            };
        }
        if (strict) {
            std::vector<std::string> violations = contract_violations(
                surface, topology, crossings, reference_topology ? &*reference_topology : nullptr);
            if (self_intersections && !have_self_intersections())
                violations.push_back("self-intersections: not checked, this tetiso was built without CGAL "
                                     "(self_intersections=False gates without them)");
            out["violations"] = violations;
        }
    }
    return out.dump();
}

} // namespace

void register_checks(py::module_& m) {
    m.def("check", [](const Piece& surface, const Piece* against, bool self_intersections, bool vertices_only,
                      bool strict) {
        const std::string report = check_report(surface, against, self_intersections, vertices_only, strict);
        return py::module_::import("json").attr("loads")(report);
    }, py::arg("surface"), py::kw_only(), py::arg("against") = py::none(), py::arg("self_intersections") = true,
          py::arg("vertices_only") = false, py::arg("strict") = false,
          "`tetiso check` as a dict: topology, quality, self-intersections (CGAL builds); against a reference "
          "the Hausdorff distance and whether the component signatures match; strict=True adds 'violations', "
          "the lines `tetiso check --strict` prints (empty when the surface keeps the contract)");
    m.def("have_self_intersections", &have_self_intersections,
          "Whether check can count self-intersections (tetiso built with CGAL)");
}

} // namespace tetiso::python
