// A solver's piece checked and viewed (piece_check.hpp): the same rules as
// the .vtu reader's (core/inputs/io_vtu.cpp), so that a piece the in-situ
// call takes is one the file route takes too.
#include "piece_check.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "tetiso/error.hpp"

namespace tetiso::insitu {

namespace {

const char* type_name(ScalarType type) {
    switch (type) {
    case ScalarType::float32: return "float32";
    case ScalarType::float64: return "float64";
    case ScalarType::int32: return "int32";
    case ScalarType::int64: return "int64";
    case ScalarType::uint8: return "uint8";
    }
    return "unknown";
}

void require(const ArrayView& array, const char* name, std::initializer_list<ScalarType> types) {
    bool offered = false;
    std::string names;
    for (const ScalarType type : types) {
        offered |= array.type == type;
        names += std::string(names.empty() ? "" : " or ") + type_name(type);
    }
    if (!offered) throw Error(std::string("the ") + name + " are " + type_name(array.type) + "; give " + names);
    if (array.size > 0 && !array.data) throw Error(std::string("the ") + name + " hold " + std::to_string(array.size) + " values at a null address");
}

template <class T>
const T* values(const ArrayView& array) {
    return static_cast<const T*>(array.data);
}

template <class T>
bool finite_floats(const T* v, std::size_t count, std::size_t& bad) {
    for (std::size_t i = 0; i < count; ++i)
        if (!(std::abs(v[i]) <= std::numeric_limits<float>::max())) {
            bad = i;
            return false;
        }
    return true;
}

} // namespace

CheckedPiece check_piece(const InSituPiece& piece) {
    require(piece.coordinates, "coordinates", {ScalarType::float32, ScalarType::float64});
    require(piece.global_ids, "global ids", {ScalarType::int32, ScalarType::int64});
    require(piece.field, "field values", {ScalarType::float32, ScalarType::float64});
    require(piece.tetrahedra, "tetrahedra", {ScalarType::int32});
    if (!piece.ghost_cells.empty()) require(piece.ghost_cells, "ghost cell marks", {ScalarType::uint8});
    if (piece.coordinates.size % 3 != 0)
        throw Error("the coordinates hold " + std::to_string(piece.coordinates.size) + " values, not 3 per node");
    const std::size_t nodes = piece.coordinates.size / 3;
    if (nodes > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
        throw Error("more nodes than one piece's 32-bit indices can hold");
    if (piece.global_ids.size != nodes)
        throw Error("the global ids hold " + std::to_string(piece.global_ids.size) + " values for " + std::to_string(nodes) + " nodes");
    if (piece.field.size != nodes)
        throw Error("the field values hold " + std::to_string(piece.field.size) + " values for " + std::to_string(nodes) + " nodes");
    if (piece.tetrahedra.size % 4 != 0)
        throw Error("the tetrahedra hold " + std::to_string(piece.tetrahedra.size) + " corners, not 4 per tetrahedron");
    const std::size_t tets = piece.tetrahedra.size / 4;
    if (!piece.ghost_cells.empty() && piece.ghost_cells.size != tets)
        throw Error("the ghost cell marks hold " + std::to_string(piece.ghost_cells.size) + " values for " + std::to_string(tets) +
                    " tetrahedra");

    detail::PieceNodes view;
    view.count = nodes;
    view.stride = 3;
    view.coordinates_double = piece.coordinates.type == ScalarType::float64;
    const std::size_t element = view.coordinates_double ? sizeof(double) : sizeof(float);
    for (int axis = 0; axis < 3; ++axis)
        view.coordinate[axis] = static_cast<const char*>(piece.coordinates.data) + static_cast<std::size_t>(axis) * element;
    view.ids = piece.global_ids.data;
    view.ids_64 = piece.global_ids.type == ScalarType::int64;
    view.values = piece.field.data;
    view.values_double = piece.field.type == ScalarType::float64;

    std::size_t bad = 0;
    if (view.coordinates_double ? !finite_floats(values<double>(piece.coordinates), 3 * nodes, bad)
                                : !finite_floats(values<float>(piece.coordinates), 3 * nodes, bad))
        throw Error("the coordinates of node " + std::to_string(bad / 3) + " are not finite numbers in float range");
    if (view.values_double ? !finite_floats(values<double>(piece.field), nodes, bad)
                           : !finite_floats(values<float>(piece.field), nodes, bad))
        throw Error("the field value at node " + std::to_string(bad) + " is not a finite number in float range");
    for (std::size_t i = 0; i < nodes; ++i)
        if (view.id(i) < 0 || view.id(i) > kMaxGlobalId)
            throw Error("global id " + std::to_string(view.id(i)) + " of node " + std::to_string(i) + " is outside [0, 2^32)");

    const std::int32_t* corners = values<std::int32_t>(piece.tetrahedra);
    const std::uint8_t* ghost = piece.ghost_cells.empty() ? nullptr : values<std::uint8_t>(piece.ghost_cells);
    CheckedPiece checked;
    const auto n = static_cast<std::int64_t>(nodes);
    for (std::size_t t = 0; t < tets; ++t) {
        if (ghost && ghost[t]) continue; // another rank's: its indices are not this piece's concern
        const std::int32_t* v = corners + 4 * t;
        for (int k = 0; k < 4; ++k) {
            if (v[k] < 0 || v[k] >= n)
                throw Error("tetrahedron " + std::to_string(t) + " refers to node " + std::to_string(v[k]) + " of " +
                            std::to_string(nodes));
            for (int j = 0; j < k; ++j)
                if (v[j] == v[k]) throw Error("tetrahedron " + std::to_string(t) + " repeats node " + std::to_string(v[k]));
        }
        if (ghost) {
            checked.kept.insert(checked.kept.end(), v, v + 4);
            checked.numbers.push_back(t);
        }
    }
    const std::int32_t* kept = ghost ? checked.kept.data() : corners;
    const std::size_t kept_count = ghost ? checked.kept.size() / 4 : tets;
    checked.mesh = detail::piece_mesh(view, kept, kept_count, "the piece");
    // Messages name a tetrahedron by its place in the solver's array, ghosts
    // counted, as the .vtu reader names it by its cell index.
    checked.mesh.numbers = ghost ? checked.numbers.data() : nullptr;
    return checked;
}

} // namespace tetiso::insitu
