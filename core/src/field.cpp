// Analytic fields of the lattice test problem (paper, section "Testing
// software implementation") and user expressions through muparser.
#include "tetiso/field.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "tetiso/error.hpp"

#ifdef TETISO_HAVE_MUPARSER
#include <muParser.h>
#endif

namespace tetiso {
namespace {

constexpr double kCentre = 2.5; // the centre of the [0,5]^3 cube

template <class Formula>
class BuiltinField final : public Field {
public:
    BuiltinField(std::string name, double level, Formula formula)
        : name_(std::move(name)), level_(level), formula_(formula) {}
    void evaluate(const double* x, const double* y, const double* z, std::size_t n,
                  float* out) const override {
        for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(formula_(x[i], y[i], z[i]));
    }
    const std::string& description() const override { return name_; }
    double default_level() const override { return level_; }

private:
    std::string name_;
    double level_;
    Formula formula_;
};

template <class Formula>
std::unique_ptr<Field> builtin(std::string name, double level, Formula formula) {
    return std::make_unique<BuiltinField<Formula>>(std::move(name), level, formula);
}

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
    if (text == "paper") {
        return builtin("paper", 0.5, [](double x, double y, double z) {
            return 2.0 * std::cos(10.0 * x) + 2.0 * std::sin(10.0 * y) + std::cos(10.0 * z);
        });
    }
    if (text == "sphere") {
        // Distance to the cube centre; level 2 is a closed sphere of radius 2.
        return builtin("sphere", 2.0, [](double x, double y, double z) {
            return std::sqrt((x - kCentre) * (x - kCentre) + (y - kCentre) * (y - kCentre) +
                             (z - kCentre) * (z - kCentre));
        });
    }
    if (text == "torus") {
        // Distance to a circle of radius 1.5 around the z axis through the
        // centre; level 0.6 is a closed torus (genus 1) inside the cube.
        return builtin("torus", 0.6, [](double x, double y, double z) {
            const double ring = std::hypot(x - kCentre, y - kCentre) - 1.5;
            return std::hypot(ring, z - kCentre);
        });
    }
    if (text == "gyroid") {
        // Two periods along each axis: many handles, open at the cube faces.
        return builtin("gyroid", 0.0, [](double x, double y, double z) {
            constexpr double k = 2.0 * std::numbers::pi / 2.5;
            return std::sin(k * x) * std::cos(k * y) + std::sin(k * y) * std::cos(k * z) +
                   std::sin(k * z) * std::cos(k * x);
        });
    }
#ifdef TETISO_HAVE_MUPARSER
    return std::make_unique<ExpressionField>(text);
#else
    throw Error("unknown field '" + text + "' (built-in fields: " + builtin_field_names() +
                "; expressions need a build with muparser)");
#endif
}

} // namespace tetiso
