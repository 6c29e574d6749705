// tetiso.Surface: a tetiso::Piece held by Python. Its arrays are read-only
// views of the piece's own vectors (no copy), since a piece's vertices stay
// sorted by key, which a seam relies on; tetiso.read and Surface.write are
// the library's readers and writers, the CLI's bytes.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.hpp"
#include "module.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

namespace tetiso::python {

Piece surface_from_arrays(const py::handle& points, const py::handle& triangles, const py::handle& keys,
                          const py::handle& flags, const py::handle& error, const std::vector<int>& domains) {
    const std::vector<double> xyz = float_values(points, 3, -1, {"Surface", "points"});
    const std::size_t n = xyz.size() / 3;
    Piece piece;
    piece.x.resize(n), piece.y.resize(n), piece.z.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
        piece.x[v] = static_cast<float>(xyz[3 * v]);
        piece.y[v] = static_cast<float>(xyz[3 * v + 1]);
        piece.z[v] = static_cast<float>(xyz[3 * v + 2]);
        if (!std::isfinite(piece.x[v]) || !std::isfinite(piece.y[v]) || !std::isfinite(piece.z[v]))
            throw Error("Surface: points: vertex " + std::to_string(v) + " has a coordinate that is not finite (as a float)");
    }
    const auto last_vertex = static_cast<std::int64_t>(n) - 1;
    piece.triangles = integers_in_range<std::int32_t>(triangles, 3, -1, 0, last_vertex, {"Surface", "triangles"});
    const auto m = static_cast<std::ptrdiff_t>(piece.triangle_count());
    if (keys.is_none()) {
        piece.key.resize(n);
        for (std::size_t v = 0; v < n; ++v) piece.key[v] = v;
    } else {
        piece.key = key_values(keys, static_cast<std::ptrdiff_t>(n), {"Surface", "keys"});
    }
    piece.flags = flags.is_none() ? std::vector<std::uint8_t>(n, 0)
                                  : integers_in_range<std::uint8_t>(flags, 0, static_cast<std::ptrdiff_t>(n), 0, 255,
                                                                    {"Surface", "flags"});
    if (!error.is_none()) {
        const std::vector<double> bounds = float_values(error, 0, m, {"Surface", "error"});
        piece.error.assign(bounds.begin(), bounds.end());
        for (std::size_t t = 0; t < piece.error.size(); ++t)
            if (!(piece.error[t] >= 0) || !std::isfinite(piece.error[t]))
                throw Error("Surface: error: triangle " + std::to_string(t) + "'s bound is not a finite number >= 0");
    }
    piece.domains = domains;
    std::sort(piece.domains.begin(), piece.domains.end());
    piece.domains.erase(std::unique(piece.domains.begin(), piece.domains.end()), piece.domains.end());
    if (!order_by_key(piece)) throw Error("Surface: keys: two vertices have the same key");
    return piece;
}

namespace {

const Piece& piece_of(const py::handle& self) { return self.cast<const Piece&>(); }

} // namespace

void register_surface(py::module_& m) {
    py::class_<Piece>(m, "Surface",
                      "A triangulated surface: vertices sorted by their global edge key (unique), triangles "
                      "counter-clockwise seen from increasing field. Its arrays are read-only views of its "
                      "own memory, not copies; `points` alone is a copy.")
        .def(py::init(&surface_from_arrays), py::arg("points"), py::arg("triangles"), py::kw_only(),
             py::arg("keys") = py::none(), py::arg("flags") = py::none(), py::arg("error") = py::none(),
             py::arg("domains") = std::vector<int>{},
             "A surface from arrays: points (n, 3) floats, triangles (m, 3) integers; keys (n,) unsigned "
             "(default 0..n-1; vertices are reordered by key), flags (n,) uint8 (bit 0: locked), error (m,) "
             "per-triangle bound. Copied once.")
        .def_property_readonly("x", [](py::object self) { return view(piece_of(self).x, {py::ssize_t(piece_of(self).x.size())}, self); })
        .def_property_readonly("y", [](py::object self) { return view(piece_of(self).y, {py::ssize_t(piece_of(self).y.size())}, self); })
        .def_property_readonly("z", [](py::object self) { return view(piece_of(self).z, {py::ssize_t(piece_of(self).z.size())}, self); })
        .def_property_readonly("keys", [](py::object self) { return view(piece_of(self).key, {py::ssize_t(piece_of(self).key.size())}, self); })
        .def_property_readonly("flags", [](py::object self) { return view(piece_of(self).flags, {py::ssize_t(piece_of(self).flags.size())}, self); })
        .def_property_readonly("triangles", [](py::object self) {
            const Piece& piece = piece_of(self);
            return view(piece.triangles, {py::ssize_t(piece.triangle_count()), 3}, self);
        })
        .def_property_readonly("error", [](py::object self) { return view(piece_of(self).error, {py::ssize_t(piece_of(self).error.size())}, self); },
                               "Per-triangle bound on the distance to the raw surface (empty where none)")
        .def_property_readonly("points", [](const Piece& piece) {
            py::array_t<float> out({py::ssize_t(piece.vertex_count()), py::ssize_t(3)});
            auto xyz = out.mutable_unchecked<2>();
            for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
                xyz(py::ssize_t(v), 0) = piece.x[v];
                xyz(py::ssize_t(v), 1) = piece.y[v];
                xyz(py::ssize_t(v), 2) = piece.z[v];
            }
            return out;
        }, "The positions as one (n, 3) array: a copy, since the surface keeps x, y and z apart")
        .def_property_readonly("domains", [](const Piece& piece) { return piece.domains; })
        .def_property_readonly("vertex_count", &Piece::vertex_count)
        .def_property_readonly("triangle_count", &Piece::triangle_count)
        .def_property_readonly("sample_count", &Piece::sample_count,
                               "Raw vertices kept for a later seam's reduction (Lattice.piece, seam)")
        .def("write", [](const Piece& piece, const std::filesystem::path& path) {
            py::gil_scoped_release unlocked;
            write_piece(piece, path);
        }, py::arg("path"), "Writes .ply or .vtp by the extension, atomically: what the CLI writes")
        .def("__repr__", [](const Piece& piece) {
            return "<tetiso.Surface: " + std::to_string(piece.vertex_count()) + " vertices, " +
                   std::to_string(piece.triangle_count()) + " triangles>";
        });

    m.def("read", [](const std::filesystem::path& path) {
        py::gil_scoped_release unlocked;
        return read_piece(path);
    }, py::arg("path"), "Reads a .ply or .vtp surface (tetiso's or another tool's PLY)");
}

} // namespace tetiso::python
