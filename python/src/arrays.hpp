// NumPy arrays in and out of the module. In: an argument is checked (its kind
// of dtype, its shape, its values where the library needs a range) and copied
// once into the std::vector the library's types hold, whatever its strides
// and byte order; a refusal is a tetiso.Error naming the argument. Out: a
// read-only array over a vector that a Python object owns (a Surface's), with
// that object as its base, so no copy is made and the memory lives as long as
// any view of it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace tetiso::python {

namespace py = pybind11;

// Where the values go: which argument of which call, for messages
// ("extract: points: ...").
struct ArgumentName {
    const char* call;
    const char* argument;
    std::string operator()(const std::string& what) const;
};

// Floating-point values (any float dtype), `columns` per row (0: a 1-D
// array), as doubles in row order. Throws tetiso::Error for another dtype or
// shape, or a row count other than `rows` where rows >= 0.
std::vector<double> float_values(const py::handle& array, std::size_t columns, std::ptrdiff_t rows,
                                 const ArgumentName& name);

// Integer values (any signed or unsigned dtype), as int64, in row order; the
// same checks. uint64 values above INT64_MAX are refused.
std::vector<std::int64_t> integer_values(const py::handle& array, std::size_t columns, std::ptrdiff_t rows,
                                         const ArgumentName& name);

// Unsigned 64-bit values (uint64, or any integer dtype whose values are not
// negative), 1-D, `rows` of them where rows >= 0.
std::vector<std::uint64_t> key_values(const py::handle& array, std::ptrdiff_t rows, const ArgumentName& name);

// Integer values in [low, high], narrowed to T; the first value outside is
// named by its position.
template <class T>
std::vector<T> integers_in_range(const py::handle& array, std::size_t columns, std::ptrdiff_t rows,
                                 std::int64_t low, std::int64_t high, const ArgumentName& name);

// Rows of a 2-D array (or length of a 1-D one) without converting it.
std::size_t row_count(const py::handle& array, const ArgumentName& name);

// A read-only view of `data` (count elements, laid out as `shape`), owned by
// `owner`.
template <class T>
py::array view(const std::vector<T>& data, std::vector<py::ssize_t> shape, const py::handle& owner);

} // namespace tetiso::python
