// The stages over arrays: extract (a domain given as arrays, or the lattice
// test problem), reduce, the lattice's domain tasks, seam and merge. Each
// call takes its arguments under the GIL (checked, copied into the library's
// types), releases it for the work, and returns a Surface that owns the
// result. Defaults and option checks are the CLI's, so that a call gives the
// bytes of the command it mirrors.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "module.hpp"
#include "options.hpp"
#include "tetiso/domain_task.hpp"
#include "tetiso/error_unit.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/mesh_file.hpp"
#include "tetiso/reduce.hpp"
#include "tetiso/seam.hpp"

namespace tetiso::python {
namespace {

// The part of a call's options that every reduction shares.
struct Reduction {
    double phi;
    double max_error;
    int threads;
    ReduceOptions options(const Device& device, double spacing = 1.0) const {
        ReduceOptions out;
        out.phi = phi;
        out.threads = threads;
        out.max_error = max_error * spacing;
        out.device = device;
        return out;
    }
};

Piece extract_arrays(const py::handle& points, const py::handle& tets, const py::handle& field,
                     std::optional<double> level, const py::handle& node_ids, const py::handle& interface,
                     const py::handle& shared_edges, int domain_id, int threads, const std::string& device, int gpu,
                     bool reduce_it, double phi, double max_error) {
    level = checked_level(level);
    checked_threads(threads);
    const Reduction reduction{checked_phi(phi), checked_error_bound(max_error), threads};
    if (domain_id < 0) throw Error("domain: must be at least 0, not " + std::to_string(domain_id));

    MeshArrays arrays;
    const std::vector<double> xyz = float_values(points, 3, -1, {"extract", "points"});
    const std::size_t n = xyz.size() / 3;
    if (n > static_cast<std::size_t>(INT32_MAX)) throw Error("extract: points: more nodes than 32-bit indices reach");
    arrays.x.resize(n), arrays.y.resize(n), arrays.z.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        arrays.x[v] = xyz[3 * v], arrays.y[v] = xyz[3 * v + 1], arrays.z[v] = xyz[3 * v + 2];
        if (!std::isfinite(static_cast<float>(arrays.x[v])) || !std::isfinite(static_cast<float>(arrays.y[v])) ||
            !std::isfinite(static_cast<float>(arrays.z[v])))
            throw Error("extract: points: node " + std::to_string(v) + " has a coordinate that is not finite (as a float)");
    }
    // Indices are checked before the tetrahedra are oriented, which reads
    // their corners; the message is extraction's own.
    const std::vector<std::int64_t> corners = integer_values(tets, 4, -1, {"extract", "tets"});
    arrays.tets.resize(corners.size());
    for (std::size_t c = 0; c < corners.size(); ++c) {
        if (corners[c] < 0 || corners[c] >= static_cast<std::int64_t>(n))
            throw Error("domain " + std::to_string(domain_id) + ": tetrahedron " + std::to_string(c / 4) +
                        " refers to a node that does not exist");
        arrays.tets[c] = static_cast<std::int32_t>(corners[c]);
    }
    std::unique_ptr<Field> named_field;
    if (py::isinstance<py::str>(field)) {
        named_field = make_field(field.cast<std::string>());
    } else {
        arrays.f = float_values(field, 0, static_cast<std::ptrdiff_t>(n), {"extract", "field"});
    }
    // A field of the mesh's own has no level of its own; an analytic one has.
    const double chosen_level = level.value_or(named_field ? named_field->default_level() : 0.0);
    std::vector<GlobalId> ids;
    if (!node_ids.is_none())
        ids = integers_in_range<GlobalId>(node_ids, 0, static_cast<std::ptrdiff_t>(n), 0, kMaxGlobalId,
                                          {"extract", "node_ids"});
    std::vector<std::uint8_t> masks;
    if (!interface.is_none())
        masks = integers_in_range<std::uint8_t>(interface, 0, static_cast<std::ptrdiff_t>(n), 0, 255,
                                                {"extract", "interface"});
    std::vector<EdgeKey> shared;
    if (!shared_edges.is_none()) shared = key_values(shared_edges, -1, {"extract", "shared_edges"});

    py::gil_scoped_release unlocked;
    Domain domain = domain_from_arrays(std::move(arrays), named_field.get(), "extract: tets");
    domain.id = domain_id;
    if (!ids.empty()) domain.gid = std::move(ids);
    if (!masks.empty()) domain.interface = std::move(masks);
    std::sort(shared.begin(), shared.end());
    shared.erase(std::unique(shared.begin(), shared.end()), shared.end());
    domain.shared_edges = std::move(shared);
    const DeviceUse use(device, gpu);
    Piece surface = extract(domain, static_cast<float>(chosen_level), ExtractOptions{threads, use.device()});
    if (reduce_it) surface = reduce(surface, reduction.options(use.device(), tetiso::mean_edge_length(domain)));
    return surface;
}

Piece extract_lattice(std::int64_t n, int domains, const std::string& field, std::optional<double> level,
                      int threads, const std::string& device, int gpu, bool reduce_it, double phi, double max_error) {
    level = checked_level(level);
    checked_threads(threads);
    checked_count(domains, "domains");
    const Reduction reduction{checked_phi(phi), checked_error_bound(max_error), threads};
    py::gil_scoped_release unlocked;
    const LatticePartition partition(n, domains, make_field(field));
    const Decomposition& decomposition = partition.decomposition();
    const DeviceUse use(device, gpu);
    DomainTaskOptions task;
    task.level = static_cast<float>(level.value_or(partition.field().default_level()));
    task.device = use.device();
    task.threads = threads;
    std::vector<Piece> pieces;
    for (int d = 0; d < decomposition.domain_count(); ++d) pieces.push_back(run_domain_task(partition, d, task).piece);
    Piece surface = merge_all(std::move(pieces));
    unlock_settled(surface, [&](GlobalId a, GlobalId b) { return decomposition.domains_of_edge(a, b); });
    if (reduce_it) surface = reduce(surface, reduction.options(use.device(), partition.lattice().spacing()));
    return surface;
}

Piece reduce_surface(const Piece& input, double phi, std::optional<double> max_error, int threads,
                     const std::string& device, int gpu, int max_rounds, double min_angle_degrees, bool keep_samples) {
    checked_threads(threads);
    const Reduction reduction{checked_phi(phi), max_error ? checked_error_bound(*max_error) : 0.0, threads};
    py::gil_scoped_release unlocked;
    const DeviceUse use(device, gpu);
    ReduceOptions options = reduction.options(use.device());
    if (!max_error) options.max_error = kAutoErrorPerEdgeLength * mean_edge_length(input);
    options.max_rounds = max_rounds;
    options.min_angle_degrees = min_angle_degrees;
    options.keep_samples = keep_samples;
    return reduce(input, options);
}

// A domain's task as `tetiso run` runs it (core/job/job.cpp): extracted,
// reduced keeping its raw vertices as samples, those far from any open
// interface dropped.
Piece lattice_piece(const LatticePartition& partition, int domain, std::optional<double> level, bool reduce_it,
                    double phi, double max_error, int sample_rings, int threads, const std::string& device, int gpu) {
    level = checked_level(level);
    checked_threads(threads);
    const Reduction reduction{checked_phi(phi), checked_error_bound(max_error), threads};
    if (domain < 0 || domain >= partition.domain_count())
        throw Error("domain: " + std::to_string(domain) + " is outside 0 to " + std::to_string(partition.domain_count() - 1));
    py::gil_scoped_release unlocked;
    const DeviceUse use(device, gpu);
    DomainTaskOptions task;
    task.level = static_cast<float>(level.value_or(partition.field().default_level()));
    task.device = use.device();
    task.threads = threads;
    if (reduce_it) {
        task.reduce = reduction.options(use.device(), partition.spacing());
        task.reduce->keep_samples = true;
    }
    Piece piece = run_domain_task(partition, domain, task).piece;
    if (reduce_it) keep_samples_near_locked(piece, sample_rings);
    return piece;
}

Piece seam_pieces(const Piece& a, const Piece& b, const py::object& lattice_object,
                  const std::optional<std::function<std::vector<int>(GlobalId, GlobalId)>>& holders, bool reduce_it,
                  double phi, double max_error, int rings, int sample_rings, int threads) {
    checked_threads(threads);
    checked_rings(rings, "rings");
    const Reduction reduction{checked_phi(phi), checked_error_bound(max_error), threads};
    std::shared_ptr<LatticePartition> lattice;
    if (!lattice_object.is_none()) {
        if (!py::isinstance<LatticePartition>(lattice_object))
            throw Error("seam: lattice: expected a tetiso.Lattice, not " +
                        std::string(py::str(py::type::handle_of(lattice_object).attr("__name__"))));
        lattice = lattice_object.cast<std::shared_ptr<LatticePartition>>();
    }
    if (lattice && holders) throw Error("seam: give lattice or domains_of_edge, not both");
    std::vector<int> both = a.domains;
    both.insert(both.end(), b.domains.begin(), b.domains.end());
    std::sort(both.begin(), both.end());
    EdgeDomains domains_of_edge = [both](GlobalId, GlobalId) { return both; }; // the last seam: all settled
    if (lattice) domains_of_edge = [lattice](GlobalId x, GlobalId y) { return lattice->domains_of_edge(x, y); };
    if (holders) {
        // A Python function: called with the GIL, once per locked vertex.
        domains_of_edge = [function = *holders](GlobalId x, GlobalId y) {
            py::gil_scoped_acquire locked;
            return function(x, y);
        };
    }
    SeamOptions options;
    options.reduce = reduce_it;
    options.reduce_options = reduction.options(Device::host());
    options.rings = rings;
    options.sample_rings = sample_rings;
    py::gil_scoped_release unlocked;
    return seam(a, b, domains_of_edge, options);
}

} // namespace

void register_stages(py::module_& m) {
    m.def("extract", &extract_arrays, py::arg("points"), py::arg("tets"), py::arg("field"),
          py::arg("level") = py::none(), py::kw_only(), py::arg("node_ids") = py::none(),
          py::arg("interface") = py::none(), py::arg("shared_edges") = py::none(), py::arg("domain") = 0,
          py::arg("threads") = 1, py::arg("device") = "cpu", py::arg("gpu") = 0, py::arg("reduce") = false,
          py::arg("phi") = 0.9, py::arg("max_error") = 0.25,
          "The isosurface of one domain given as arrays (marching tetrahedra): points (n, 3), tets (m, 4) "
          "node indices, field (n,) values or a field's name or expression. level defaults to 0 for values, "
          "the field's own for a name. reduce=True reduces it, max_error in mean tetrahedron edge lengths. "
          "The bytes of `tetiso extract --mesh` on the same mesh.");
    m.def("extract_lattice", &extract_lattice, py::arg("n"), py::kw_only(), py::arg("domains") = 1,
          py::arg("field") = "paper", py::arg("level") = py::none(), py::arg("threads") = 1,
          py::arg("device") = "cpu", py::arg("gpu") = 0, py::arg("reduce") = false, py::arg("phi") = 0.9,
          py::arg("max_error") = 0.25,
          "The paper's test problem, n^3 nodes on [0,5]^3 cut into boxes, extracted domain by domain and "
          "merged by key: the bytes of `tetiso extract --lattice n`. max_error in lattice spacings.");
    m.def("reduce", &reduce_surface, py::arg("surface"), py::kw_only(), py::arg("phi") = 0.9,
          py::arg("max_error") = py::none(), py::arg("threads") = 1, py::arg("device") = "cpu", py::arg("gpu") = 0,
          py::arg("max_rounds") = ReduceOptions{}.max_rounds,
          py::arg("min_angle_degrees") = ReduceOptions{}.min_angle_degrees, py::arg("keep_samples") = false,
          "Rounds of parallel edge collapse and flip, topology and locked vertices kept. max_error is "
          "absolute; None: 0.4 x the mean edge length, as `tetiso reduce`; 0: no bound.");

    py::class_<LatticePartition, std::shared_ptr<LatticePartition>>(
        m, "Lattice", "The paper's test problem split into boxes as `tetiso run --lattice n --domains d` splits it")
        .def(py::init([](std::int64_t n, int domains, const std::string& field) {
                 checked_count(domains, "domains");
                 return std::make_shared<LatticePartition>(n, domains, make_field(field));
             }),
             py::arg("n"), py::arg("domains") = 1, py::arg("field") = "paper")
        .def_property_readonly("n", [](const LatticePartition& p) { return p.lattice().n(); })
        .def_property_readonly("domain_count", &LatticePartition::domain_count)
        .def_property_readonly("spacing", &LatticePartition::spacing)
        .def_property_readonly("default_level", [](const LatticePartition& p) { return p.field().default_level(); })
        .def("domains_of_edge", &LatticePartition::domains_of_edge, py::arg("a"), py::arg("b"),
             "The domains holding the mesh edge between nodes a and b (global ids)")
        .def("piece", &lattice_piece, py::arg("domain"), py::kw_only(), py::arg("level") = py::none(),
             py::arg("reduce") = true, py::arg("phi") = 0.9, py::arg("max_error") = 0.25,
             py::arg("sample_rings") = SeamOptions{}.sample_rings, py::arg("threads") = 1, py::arg("device") = "cpu",
             py::arg("gpu") = 0,
             "One domain's task of `tetiso run`: extracted and reduced (max_error in lattice spacings), its "
             "interface vertices locked, its raw vertices near them kept for the seams");

    m.def("seam", &seam_pieces, py::arg("a"), py::arg("b"), py::kw_only(), py::arg("lattice") = py::none(),
          py::arg("domains_of_edge") = py::none(), py::arg("reduce") = true, py::arg("phi") = 0.9,
          py::arg("max_error") = 0.0, py::arg("rings") = SeamOptions{}.rings,
          py::arg("sample_rings") = SeamOptions{}.sample_rings, py::arg("threads") = 1,
          "Merges two pieces by key, unlocks the vertices whose edge the merge settled (by the lattice's "
          "domains, a function (gid, gid) -> domains, or, with neither, all of them: the last seam) and "
          "reduces within `rings` edges of them. max_error is absolute.");
    m.def("merge", [](const std::vector<Piece>& pieces) {
        std::vector<Piece> copies = pieces;
        py::gil_scoped_release unlocked;
        return merge_all(std::move(copies));
    }, py::arg("pieces"), "Merges pieces by key into one in canonical order, without reducing");
}

} // namespace tetiso::python
