// Analytic fields of the lattice test problem (paper, section "Testing
// software implementation") and user expressions through muparser.
#include "tetiso/field.hpp"

#include <cmath>
#include <vector>

#include "field_formulas.hpp"
#include "tetiso/error.hpp"

#ifdef TETISO_HAVE_MUPARSER
#include <muParser.h>
#endif

namespace tetiso {
namespace {

// A built-in field: field_formulas.hpp's formula, which the GPU evaluates too.
class BuiltinFieldImpl final : public Field {
public:
    BuiltinFieldImpl(std::string name, double level, BuiltinField kind)
        : name_(std::move(name)), level_(level), kind_(kind) {}
    void evaluate(const double* x, const double* y, const double* z, std::size_t n, float* out) const override {
        for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(field_formulas::value(kind_, x[i], y[i], z[i]));
    }
    const std::string& description() const override { return name_; }
    double default_level() const override { return level_; }
    std::optional<BuiltinField> builtin() const override { return kind_; }

private:
    std::string name_;
    double level_;
    BuiltinField kind_;
};

#ifdef TETISO_HAVE_MUPARSER
// muparser's bulk mode evaluates one parsed expression over arrays of
// variables; a parser is not safe to share between threads, so each call
// builds its own (parsing costs microseconds, a domain has ~10^6 nodes).
class ExpressionField final : public Field {
public:
    explicit ExpressionField(std::string expression) : expression_(std::move(expression)) {
        double x = 1.0, y = 2.0, z = 3.0;
        try {
            mu::Parser parser;
            parser.DefineVar("x", &x);
            parser.DefineVar("y", &y);
            parser.DefineVar("z", &z);
            parser.SetExpr(expression_);
            parser.Eval(); // parses now, so errors surface before any work starts
        } catch (const mu::Parser::exception_type& e) {
            throw Error("field '" + expression_ + "' is neither a built-in (" + builtin_field_names() +
                            ") nor an expression in x, y, z that parses: " + e.GetMsg());
        }
    }
    void evaluate(const double* x, const double* y, const double* z, std::size_t n,
                  float* out) const override {
        std::vector<double> xs(x, x + n), ys(y, y + n), zs(z, z + n), values(n);
        mu::Parser parser;
        parser.DefineVar("x", xs.data());
        parser.DefineVar("y", ys.data());
        parser.DefineVar("z", zs.data());
        parser.SetExpr(expression_);
        parser.Eval(values.data(), static_cast<int>(n));
        for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(values[i]);
    }
    const std::string& description() const override { return expression_; }
    double default_level() const override { return 0.0; }

private:
    std::string expression_;
};
#endif

} // namespace

const char* builtin_field_names() { return "paper, sphere, torus, gyroid"; }

std::unique_ptr<Field> make_field(const std::string& text) {
    // Each built-in's isosurface level: paper 0.5 (the paper's), a sphere of
    // radius 2, a torus of tube radius 0.6, the gyroid's zero set.
    if (text == "paper") return std::make_unique<BuiltinFieldImpl>("paper", 0.5, BuiltinField::paper);
    if (text == "sphere") return std::make_unique<BuiltinFieldImpl>("sphere", 2.0, BuiltinField::sphere);
    if (text == "torus") return std::make_unique<BuiltinFieldImpl>("torus", 0.6, BuiltinField::torus);
    if (text == "gyroid") return std::make_unique<BuiltinFieldImpl>("gyroid", 0.0, BuiltinField::gyroid);
#ifdef TETISO_HAVE_MUPARSER
    return std::make_unique<ExpressionField>(text);
#else
    throw Error("unknown field '" + text + "' (built-in fields: " + builtin_field_names() +
                "; expressions need a build with muparser)");
#endif
}

} // namespace tetiso
