// `tetiso check`'s report, put together from the checker's parts
// (tetiso/check.hpp) in one place, so that the CLI and tetiso.check give the
// same keys and values.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "tetiso/mesh.hpp"

namespace tetiso {

struct CheckReportOptions {
    bool self_intersections = true; // count them, where this build can
    bool vertices_only = false;     // against a reference: measure at the vertices only
    bool strict = false;            // add "violations", contract_violations' lines
    // How the caller turns the count off, named in the violation that says a
    // build without CGAL could not check it.
    std::string skip_self_intersections = "--no-self-intersections";
};

// "topology"; "self_intersections" where counted; given a reference,
// "against" (same_signatures, reference_topology, hausdorff); with strict,
// "violations". No file names: a caller that read files adds them.
nlohmann::json check_report(const Piece& surface, const Piece* reference, const CheckReportOptions& options);

} // namespace tetiso
