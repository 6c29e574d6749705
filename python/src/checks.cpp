// tetiso.check: `tetiso check` on a Surface in memory, the same report as a
// dict (the JSON the CLI prints, less the "file" names it has no file for):
// both are the checker's check_report.
#include "module.hpp"
#include "tetiso/check.hpp"
#include "tetiso/check_report.hpp"
#include "tetiso/error.hpp"

namespace tetiso::python {
namespace {

std::string report_text(const Piece& surface, const Piece* reference, bool self_intersections, bool vertices_only,
                        bool strict) {
    if (vertices_only && !reference) throw Error("check: vertices_only applies with against");
    nlohmann::json out;
    {
        py::gil_scoped_release unlocked;
        out = check_report(surface, reference,
                           CheckReportOptions{.self_intersections = self_intersections,
                                              .vertices_only = vertices_only,
                                              .strict = strict,
                                              .skip_self_intersections = "self_intersections=False"});
    }
    return out.dump();
}

} // namespace

void register_checks(py::module_& m) {
    m.def("check", [](const Piece& surface, const Piece* against, bool self_intersections, bool vertices_only,
                      bool strict) {
        const std::string report = report_text(surface, against, self_intersections, vertices_only, strict);
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
