// Scalar fields given analytically on the lattice test problem: the paper's
// field, a few with known topology for validation, and any expression in
// x, y, z (parsed by muparser). Values are computed in double precision from
// the node's lattice coordinates and rounded to float once, so a node's value
// never depends on the domain that asks for it.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

namespace tetiso {

// The built-in fields: their values are the same bits on the CPU and the GPU.
enum class BuiltinField { paper, sphere, torus, gyroid };

class Field {
public:
    virtual ~Field() = default;
    // Evaluates the field at n points whose coordinates are given in double
    // precision; writes n floats. Must be callable concurrently.
    virtual void evaluate(const double* x, const double* y, const double* z, std::size_t n,
                          float* out) const = 0;
    // The name (for built-ins) or the expression, as the user gave it.
    virtual const std::string& description() const = 0;
    // The isosurface level to use when the user gives none.
    virtual double default_level() const = 0;
    // Which built-in field this is, if it is one (the GPU evaluates those
    // itself); an expression is none.
    virtual std::optional<BuiltinField> builtin() const { return std::nullopt; }
};

// Builds a field from a built-in name (paper, sphere, torus, gyroid) or, if
// the text is not a built-in name, from an expression in x, y and z.
// Throws tetiso::Error naming the text if it does not parse or uses unknown
// variables.
std::unique_ptr<Field> make_field(const std::string& name_or_expression);

// Names of the built-in fields, for help texts.
const char* builtin_field_names();

} // namespace tetiso
