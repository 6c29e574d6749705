// tetiso.InSituSession: the in-situ call (tetiso/insitu.hpp) on an mpi4py
// communicator. The solver's arrays are read in place where their layout is
// the library's (C order, native byte order, a dtype it takes: float32 or
// float64 positions and values, int32 or int64 ids, int32 tetrahedra, uint8
// or bool ghost marks); any other integer or float dtype or layout is copied
// once into one it takes. Built where the in-situ library is (MPI found) and
// mpi4py's headers are.
#include <mpi.h>
#include <mpi4py/mpi4py.h>

#include <limits>
#include <memory>
#include <optional>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.hpp"
#include "module.hpp"
#include "options.hpp"
#include "tetiso/insitu.hpp"

namespace tetiso::python {
namespace {

// mpi4py's C API, imported on first use: importing mpi4py initialises MPI,
// which `import tetiso` alone must not do.
MPI_Comm communicator_of(const py::handle& comm) {
    static bool imported = false;
    if (!imported) {
        if (import_mpi4py() < 0) throw py::error_already_set();
        imported = true;
    }
    if (!PyObject_TypeCheck(comm.ptr(), &PyMPIComm_Type))
        throw Error("InSituSession: comm: expected an mpi4py.MPI.Comm, not " +
                    std::string(py::str(py::type::handle_of(comm).attr("__name__"))));
    MPI_Comm* handle = PyMPIComm_Get(comm.ptr());
    if (!handle) throw py::error_already_set();
    return *handle;
}

InSituDevice device_named(const std::string& device) {
    if (device == "cpu") return InSituDevice::cpu;
    if (device == "gpu") return InSituDevice::gpu;
    if (device == "auto") return InSituDevice::automatic;
    throw Error("InSituSession: device: '" + device + "' is none of 'cpu', 'gpu', 'auto'");
}

// The array as the library reads it: the caller's own memory where its dtype
// is one of `taken` and it lies in C order in native byte order, else a
// contiguous copy as `fallback` (the first of `taken`). `kind` is the dtype
// kind accepted at all ('f' floats, 'i' integers of either sign).
struct Held {
    py::array array; // keeps the memory alive for the call
    ArrayView view;
};

bool native_contiguous(const py::array& array) {
    const char order = array.dtype().attr("byteorder").cast<std::string>()[0];
    return (array.flags() & py::array::c_style) && (order == '=' || order == '|');
}

template <class T>
Held hold_as(const py::array& array) {
    auto converted = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!converted) throw py::error_already_set();
    return {converted, ArrayView(converted.data(), static_cast<std::size_t>(converted.size()))};
}

Held hold_floats(const py::handle& object, std::size_t columns, const char* name) {
    const ArgumentName argument{"isosurface", name};
    py::array array = py::array::ensure(object);
    if (!array || array.dtype().kind() != 'f' || array.ndim() != (columns ? 2 : 1) ||
        (columns && array.shape(1) != static_cast<py::ssize_t>(columns))) {
        PyErr_Clear();
        float_values(object, columns, -1, argument); // throws the message extract gives
        throw Error(argument("expected floating-point values (float32 or float64)"));
    }
    if (native_contiguous(array) && array.dtype().itemsize() == 4) return hold_as<float>(array);
    return hold_as<double>(array);
}

Held hold_integers(const py::handle& object, std::size_t columns, const char* name, bool int32_only) {
    const ArgumentName argument{"isosurface", name};
    py::array array = py::array::ensure(object);
    const bool integral = array && (array.dtype().kind() == 'i' || array.dtype().kind() == 'u');
    if (!integral || array.ndim() != (columns ? 2 : 1) || (columns && array.shape(1) != static_cast<py::ssize_t>(columns))) {
        PyErr_Clear();
        integer_values(object, columns, -1, argument); // throws the message extract gives
        throw Error(argument("expected integers"));
    }
    const bool is_int32 = array.dtype().kind() == 'i' && array.dtype().itemsize() == 4;
    const bool is_int64 = array.dtype().kind() == 'i' && array.dtype().itemsize() == 8;
    if (native_contiguous(array) && (is_int32 || (is_int64 && !int32_only)))
        return is_int32 ? hold_as<std::int32_t>(array) : hold_as<std::int64_t>(array);
    if (!int32_only) {
        const std::vector<std::int64_t> values = integer_values(array, columns, -1, argument);
        py::array_t<std::int64_t> copy(static_cast<py::ssize_t>(values.size()), values.data());
        return {copy, ArrayView(copy.data(), values.size())};
    }
    const std::vector<std::int32_t> values =
        integers_in_range<std::int32_t>(array, columns, -1, std::numeric_limits<std::int32_t>::min(),
                                        std::numeric_limits<std::int32_t>::max(), argument);
    py::array_t<std::int32_t> copy(static_cast<py::ssize_t>(values.size()), values.data());
    return {copy, ArrayView(copy.data(), values.size())};
}

Held hold_marks(const py::handle& object) {
    if (object.is_none()) return {};
    py::array array = py::array::ensure(object);
    if (array && array.dtype().kind() == 'b' && array.ndim() == 1 && (array.flags() & py::array::c_style)) {
        // NumPy's bool is one byte, 0 or 1: read as uint8 in place.
        return {array, ArrayView(static_cast<const std::uint8_t*>(array.data()), static_cast<std::size_t>(array.size()))};
    }
    if (array && array.dtype().kind() == 'b') array = array.attr("astype")("uint8");
    const ArgumentName argument{"isosurface", "ghost_cells"};
    if (array && array.dtype().kind() == 'u' && array.dtype().itemsize() == 1 && array.ndim() == 1 &&
        (array.flags() & py::array::c_style))
        return hold_as<std::uint8_t>(array);
    const std::vector<std::uint8_t> values = integers_in_range<std::uint8_t>(object, 0, -1, 0, 255, argument);
    py::array_t<std::uint8_t> copy(static_cast<py::ssize_t>(values.size()), values.data());
    return {copy, ArrayView(copy.data(), values.size())};
}

py::dict cost_dict(const InSituResult& result) {
    const InSituCost& cost = result.cost;
    py::dict seconds;
    seconds["check"] = cost.seconds.check, seconds["scan"] = cost.seconds.scan, seconds["pool"] = cost.seconds.pool;
    seconds["domain"] = cost.seconds.domain, seconds["seams"] = cost.seconds.seams;
    seconds["write"] = cost.seconds.write, seconds["total"] = cost.seconds.total;
    py::dict out;
    out["seconds"] = seconds;
    out["nodes"] = cost.nodes, out["tetrahedra"] = cost.tetrahedra;
    out["triangles_extracted"] = cost.triangles_extracted, out["triangles_reduced"] = cost.triangles_reduced;
    out["seams"] = cost.seams, out["bytes_sent"] = cost.bytes_sent, out["bytes_received"] = cost.bytes_received;
    out["mesh_nodes"] = result.mesh_nodes, out["mesh_tetrahedra"] = result.mesh_tetrahedra;
    out["spacing"] = result.spacing, out["max_error"] = result.max_error, out["domain"] = result.domain;
    return out;
}

struct Session {
    std::unique_ptr<InSituSession> session;
    py::object last_cost = py::none();

    Session(std::unique_ptr<InSituSession> made) : session(std::move(made)) {}
    Session(Session&&) = default;
    // A session Python frees after MPI was finalized (mpi4py finalizes at
    // exit, before the interpreter frees what is left) can free nothing
    // through MPI any more: it is let go.
    ~Session() {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (finalized) (void)session.release();
    }
    InSituSession& open() {
        if (!session) throw Error("InSituSession: the session was closed");
        return *session;
    }
};

} // namespace

void register_insitu(py::module_& m) {
    py::class_<Session>(m, "InSituSession",
                        "The in-situ call on a solver's communicator (every rank makes it together): "
                        "the communicator duplicated and the device made once, for a call every few steps")
        .def(py::init([](const py::handle& comm, const std::string& device, int threads, int root) {
                 checked_threads(threads);
                 const MPI_Comm communicator = communicator_of(comm);
                 const InSituSessionOptions options{device_named(device), threads, root};
                 py::gil_scoped_release unlocked;
                 return Session(std::make_unique<InSituSession>(communicator, options));
             }),
             py::arg("comm"), py::kw_only(), py::arg("device") = "cpu", py::arg("threads") = 1, py::arg("root") = 0)
        .def_property_readonly("rank", [](Session& s) { return s.open().rank(); })
        .def_property_readonly("size", [](Session& s) { return s.open().size(); })
        .def_property_readonly("last_cost", [](const Session& s) { return s.last_cost; },
                               "This rank's cost of the last call: seconds by stage, sizes, bytes sent and received")
        .def("isosurface", [](Session& s, const py::handle& points, const py::handle& global_ids,
                              const py::handle& field, const py::handle& tets, double level,
                              const py::handle& ghost_cells, bool reduce_it, double phi, double max_error,
                              int seam_rings, int sample_rings, std::optional<std::filesystem::path> output) -> py::object {
                 InSituOptions options;
                 options.level = *checked_level(level);
                 options.reduce = reduce_it;
                 options.reduce_options.phi = checked_phi(phi);
                 options.max_error_spacings = checked_error_bound(max_error);
                 options.seam_rings = checked_rings(seam_rings, "seam_rings");
                 options.sample_rings = sample_rings;
                 if (output) options.output = *output;
                 const Held held[] = {hold_floats(points, 3, "points"), hold_integers(global_ids, 0, "global_ids", false),
                                      hold_floats(field, 0, "field"), hold_integers(tets, 4, "tets", true),
                                      hold_marks(ghost_cells)};
                 const InSituPiece piece{held[0].view, held[1].view, held[2].view, held[3].view, held[4].view};
                 std::optional<InSituResult> result;
                 {
                     py::gil_scoped_release unlocked;
                     result = s.open().isosurface(piece, options);
                 }
                 s.last_cost = cost_dict(*result);
                 if (!result->surface) return py::none();
                 return py::cast(std::move(*result->surface));
             },
             py::arg("points"), py::arg("global_ids"), py::arg("field"), py::arg("tets"), py::arg("level"),
             py::kw_only(), py::arg("ghost_cells") = py::none(), py::arg("reduce") = true, py::arg("phi") = 0.9,
             py::arg("max_error") = 0.25, py::arg("seam_rings") = 1, py::arg("sample_rings") = 1,
             py::arg("output") = py::none(),
             "Collective: this rank's piece (points (n, 3), global_ids (n,), field (n,), tets (m, 4) local "
             "indices, ghost_cells (m,) nonzero = another rank's) to the reduced surface, byte for byte "
             "`tetiso run --mesh` on the same pieces as a .pvtu. Returns the Surface on the root, None "
             "elsewhere; max_error in the whole mesh's mean edge lengths; output: the root writes it too.")
        .def("close", [](Session& s) {
            py::gil_scoped_release unlocked;
            s.session.reset();
        }, "Frees the session's communicator and device (collective); before MPI is finalized")
        .def("__enter__", [](py::object self) { return self; })
        .def("__exit__", [](Session& s, py::args) {
            py::gil_scoped_release unlocked;
            s.session.reset();
        });
}

} // namespace tetiso::python
