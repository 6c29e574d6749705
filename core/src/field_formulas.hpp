// The built-in fields' formulas, for the host and the device alike (the GPU
// evaluates a lattice domain's field itself): double precision from the
// node's coordinates, sine and cosine from hd.hpp, so both round to the same
// float.
#pragma once

#include "hd.hpp"
#include "tetiso/field.hpp"

namespace tetiso::field_formulas {

constexpr double kCentre = 2.5; // the centre of the [0,5]^3 cube

TETISO_HD inline double hypot(double a, double b) { return sqrt(a * a + b * b); }

TETISO_HD inline double value(BuiltinField kind, double x, double y, double z) {
    switch (kind) {
    case BuiltinField::paper: return 2.0 * hd::cos(10.0 * x) + 2.0 * hd::sin(10.0 * y) + hd::cos(10.0 * z);
    case BuiltinField::sphere:
        // Distance to the cube centre; level 2 is a closed sphere of radius 2.
        return sqrt((x - kCentre) * (x - kCentre) + (y - kCentre) * (y - kCentre) + (z - kCentre) * (z - kCentre));
    case BuiltinField::torus: {
        // Distance to a circle of radius 1.5 around the z axis through the
        // centre; level 0.6 is a closed torus (genus 1) inside the cube.
        const double ring = hypot(x - kCentre, y - kCentre) - 1.5;
        return hypot(ring, z - kCentre);
    }
    case BuiltinField::gyroid:
    default: {
        // Two periods along each axis: many handles, open at the cube faces.
        constexpr double k = 2.0 * hd::kPi / 2.5;
        return hd::sin(k * x) * hd::cos(k * y) + hd::sin(k * y) * hd::cos(k * z) + hd::sin(k * z) * hd::cos(k * x);
    }
    }
}

} // namespace tetiso::field_formulas
