#include "arrays.hpp"

#include <cstring>
#include <limits>

#include "tetiso/error.hpp"

namespace tetiso::python {

std::string ArgumentName::operator()(const std::string& what) const {
    return std::string(call) + ": " + argument + ": " + what;
}

namespace {

py::array as_array(const py::handle& object, const ArgumentName& name) {
    py::array array = py::array::ensure(object);
    if (!array) {
        PyErr_Clear();
        throw Error(name("expected an array, not " + std::string(py::str(py::type::handle_of(object).attr("__name__")))));
    }
    return array;
}

std::string describe(const py::array& array) {
    std::string shape = "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d)
        shape += (d ? ", " : "") + std::to_string(array.shape(d)) + (array.ndim() == 1 ? "," : "");
    return std::string(py::str(array.dtype())) + " of shape " + shape + ")";
}

// Checks the shape: 1-D of `rows` (columns 0), or 2-D of rows x columns.
void check_shape(const py::array& array, std::size_t columns, std::ptrdiff_t rows, const char* expected,
                 const ArgumentName& name) {
    const bool shape_ok = columns == 0 ? array.ndim() == 1
                                       : array.ndim() == 2 && array.shape(1) == static_cast<py::ssize_t>(columns);
    const std::string wanted = columns == 0 ? "(n,)" : "(n, " + std::to_string(columns) + ")";
    if (!shape_ok) throw Error(name(std::string("expected ") + expected + " of shape " + wanted + ", not " + describe(array)));
    if (rows >= 0 && array.shape(0) != rows)
        throw Error(name("expected " + std::to_string(rows) + " rows (one per " +
                         (columns == 0 || columns == 3 ? "point" : "element") + "), not " + std::to_string(array.shape(0))));
}

template <class T>
std::vector<T> contiguous_copy(const py::array& array) {
    const auto converted = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!converted) throw py::error_already_set();
    std::vector<T> out(static_cast<std::size_t>(converted.size()));
    if (!out.empty()) std::memcpy(out.data(), converted.data(), out.size() * sizeof(T));
    return out;
}

} // namespace

std::vector<double> float_values(const py::handle& object, std::size_t columns, std::ptrdiff_t rows,
                                 const ArgumentName& name) {
    const py::array array = as_array(object, name);
    const char* expected = "floating-point values (float32 or float64)";
    if (array.dtype().kind() != 'f') throw Error(name(std::string("expected ") + expected + ", not " + describe(array)));
    check_shape(array, columns, rows, expected, name);
    return contiguous_copy<double>(array);
}

std::vector<std::int64_t> integer_values(const py::handle& object, std::size_t columns, std::ptrdiff_t rows,
                                         const ArgumentName& name) {
    const py::array array = as_array(object, name);
    const char* expected = "integers";
    const char kind = array.dtype().kind();
    if (kind != 'i' && kind != 'u') throw Error(name(std::string("expected ") + expected + ", not " + describe(array)));
    check_shape(array, columns, rows, expected, name);
    if (kind == 'u' && array.dtype().itemsize() == 8) {
        const std::vector<std::uint64_t> wide = contiguous_copy<std::uint64_t>(array);
        std::vector<std::int64_t> out(wide.size());
        for (std::size_t i = 0; i < wide.size(); ++i) {
            if (wide[i] > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
                throw Error(name("value " + std::to_string(wide[i]) + " at position " + std::to_string(i) + " is too large"));
            out[i] = static_cast<std::int64_t>(wide[i]);
        }
        return out;
    }
    return contiguous_copy<std::int64_t>(array);
}

std::vector<std::uint64_t> key_values(const py::handle& object, std::ptrdiff_t rows, const ArgumentName& name) {
    const py::array array = as_array(object, name);
    const char kind = array.dtype().kind();
    if (kind == 'u') {
        check_shape(array, 0, rows, "unsigned integers", name);
        return contiguous_copy<std::uint64_t>(array);
    }
    const std::vector<std::int64_t> values = integer_values(object, 0, rows, name);
    std::vector<std::uint64_t> out(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] < 0)
            throw Error(name("value " + std::to_string(values[i]) + " at position " + std::to_string(i) + " is negative"));
        out[i] = static_cast<std::uint64_t>(values[i]);
    }
    return out;
}

template <class T>
std::vector<T> integers_in_range(const py::handle& array, std::size_t columns, std::ptrdiff_t rows,
                                 std::int64_t low, std::int64_t high, const ArgumentName& name) {
    const std::vector<std::int64_t> values = integer_values(array, columns, rows, name);
    std::vector<T> out(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (values[i] < low || values[i] > high) {
            const std::string where = columns == 0 ? "position " + std::to_string(i)
                                                   : "row " + std::to_string(i / columns) + ", column " +
                                                         std::to_string(i % columns);
            throw Error(name("value " + std::to_string(values[i]) + " at " + where + " is outside [" +
                             std::to_string(low) + ", " + std::to_string(high) + "]"));
        }
        out[i] = static_cast<T>(values[i]);
    }
    return out;
}

template std::vector<std::int32_t> integers_in_range(const py::handle&, std::size_t, std::ptrdiff_t, std::int64_t,
                                                     std::int64_t, const ArgumentName&);
template std::vector<std::int64_t> integers_in_range(const py::handle&, std::size_t, std::ptrdiff_t, std::int64_t,
                                                     std::int64_t, const ArgumentName&);
template std::vector<std::uint8_t> integers_in_range(const py::handle&, std::size_t, std::ptrdiff_t, std::int64_t,
                                                     std::int64_t, const ArgumentName&);

std::size_t row_count(const py::handle& object, const ArgumentName& name) {
    const py::array array = as_array(object, name);
    if (array.ndim() < 1) throw Error(name("expected an array of rows, not " + describe(array)));
    return static_cast<std::size_t>(array.shape(0));
}

template <class T>
py::array view(const std::vector<T>& data, std::vector<py::ssize_t> shape, const py::handle& owner) {
    // An empty vector may have no storage; NumPy then makes an empty array of its own.
    py::array out(py::dtype::of<T>(), std::move(shape), {}, data.empty() ? nullptr : data.data(),
                  data.empty() ? py::handle() : owner);
    py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return out;
}

template py::array view(const std::vector<float>&, std::vector<py::ssize_t>, const py::handle&);
template py::array view(const std::vector<std::int32_t>&, std::vector<py::ssize_t>, const py::handle&);
template py::array view(const std::vector<std::uint64_t>&, std::vector<py::ssize_t>, const py::handle&);
template py::array view(const std::vector<std::uint8_t>&, std::vector<py::ssize_t>, const py::handle&);

} // namespace tetiso::python
