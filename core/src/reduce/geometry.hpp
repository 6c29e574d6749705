// The reduction's small geometry, in double precision from float
// coordinates: triangle quality, contact between faces that share a corner
// or an edge, point-to-segment and point-to-triangle distances, and the
// hash that breaks ties in priority. Each function is one element's work,
// compiled for the host and the device alike (hd.hpp), so that both make the
// same decisions bit for bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "../hd.hpp"

namespace tetiso::reduction {

using i32 = std::int32_t;
using i64 = std::int64_t;
using u8 = std::uint8_t;
using u16 = std::uint16_t;
using u32 = std::uint32_t;
using u64 = std::uint64_t;

struct Vec {
    double x, y, z;
};
TETISO_HD inline Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
TETISO_HD inline Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
TETISO_HD inline Vec operator*(double s, Vec a) { return {s * a.x, s * a.y, s * a.z}; }
TETISO_HD inline double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
TETISO_HD inline Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
TETISO_HD inline double norm2(Vec a) { return dot(a, a); }
TETISO_HD inline double norm(Vec a) { return std::sqrt(dot(a, a)); }

// Sine of the smallest angle of triangle (a, b, c): twice the area over the
// product of the two longer sides. 0 for a degenerate triangle. height_out:
// the height over the longest side.
TETISO_HD inline double quality(Vec a, Vec b, Vec c, Vec* normal_out = nullptr, double* height_out = nullptr) {
    const Vec ab = b - a, bc = c - b, ca = a - c;
    const Vec n = cross(ab, c - a);
    const double area2 = norm(n);
    if (normal_out) *normal_out = area2 > 0 ? (1.0 / area2) * n : Vec{0, 0, 0};
    double l0 = norm2(ab), l1 = norm2(bc), l2 = norm2(ca);
    if (height_out) {
        const double longest = std::max(l0, std::max(l1, l2));
        *height_out = longest > 0 ? area2 / std::sqrt(longest) : 0.0;
    }
    // Drop the shortest side.
    const double shortest = std::min(l0, std::min(l1, l2));
    double product;
    if (shortest == l0) product = l1 * l2;
    else if (shortest == l1) product = l0 * l2;
    else product = l0 * l1;
    return product > 0 ? area2 / std::sqrt(product) : 0.0;
}

// Whether the normal of triangle (a, b, c), of quality q, is the surface's
// rather than an artefact of where its corners were put. Corners are
// floats: a face whose height over its longest side is within a few units
// in the last place of its coordinates has a normal that rounding chose,
// whatever its quality (a needle one ulp wide and a hundred long has
// q = 0.01). Marching tetrahedra make such faces where the surface passes
// within float resolution of a mesh node, and extraction then holds each
// crossing kNodeClearanceUlps (32) ulps off the node (extract_rules.hpp,
// node_clearance): the crossings around the node form a cluster a few
// clearances across whose positions the clearance chose, not the field, and
// the needles between it and the rest of the surface have normals that
// turn by up to a half turn when one corner of the cluster moves within it.
// Judging collapses inside such a cluster by those normals refused every way
// out of it: before the clearance, the cluster stayed as zero-area
// triangles; with it, as needles. kArtefactUlps covers the
// cluster's size (a crossing lies up to √3 clearances from its node, two of
// them up to twice that apart) with a margin; a face that thin still keeps
// an area float resolves and, once a collapse gives it a normal of its own,
// must face its leaves' way (legality.hpp). Below kValidQuality the normal
// is rounding's at any size.
constexpr double kValidQuality = 1e-5;
constexpr double kArtefactUlps = 128.0;
// Under this height a face's area itself is rounding's: a float cross
// product of its sides may come out 0.
constexpr double kRoundingUlps = 4.0;

// q and height: quality()'s, for the same corners.
TETISO_HD inline bool resolved(Vec a, Vec b, Vec c, double q, double height) {
    if (!(q > kValidQuality)) return false;
    const double extent = std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z), std::fabs(b.x), std::fabs(b.y),
                                    std::fabs(b.z), std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    return height > kArtefactUlps * std::numeric_limits<float>::epsilon() * extent;
}

// Whether triangle (a, b, c) is an artefact whose area float still
// resolves: no normal of its own (resolved() false), but a height over its
// longest side above kRoundingUlps.
TETISO_HD inline bool resolvable_artefact(Vec a, Vec b, Vec c) {
    double height;
    const double q = quality(a, b, c, nullptr, &height);
    const double extent = std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z), std::fabs(b.x), std::fabs(b.y),
                                    std::fabs(b.z), std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    return q > 0 && !resolved(a, b, c, q, height) &&
           height > kRoundingUlps * std::numeric_limits<float>::epsilon() * extent;
}

// Whether segment (a, b) is no longer than the artefact scale: a move that
// short stays inside the cluster of crossings around one node.
TETISO_HD inline bool within_artefact_scale(Vec a, Vec b) {
    const double extent = std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z), std::fabs(b.x), std::fabs(b.y),
                                    std::fabs(b.z)});
    return norm(b - a) <= kArtefactUlps * std::numeric_limits<float>::epsilon() * extent;
}

// The same, measuring the triangle first (for the few faces that need it).
TETISO_HD inline bool resolved(Vec a, Vec b, Vec c) {
    double height;
    const double q = quality(a, b, c, nullptr, &height);
    return resolved(a, b, c, q, height);
}

// Whether triangles (a, b1, c1) and (a, b2, c2), with unit normals n1 and
// n2, share a point other than their common corner a (they share no other
// corner). Each triangle that crosses the other's plane does so along a
// segment starting at a, on the line common to both planes; the triangles
// overlap exactly when these segments leave a the same way. Triangles that
// lie in one plane (within a millionth of their size: rounding leaves a
// flat surface's corners that far apart) overlap when one's side or bisector
// points strictly into the other's angle at a.
TETISO_HD inline bool overlap_at_corner(Vec a, Vec b1, Vec c1, Vec n1, Vec b2, Vec c2, Vec n2) {
    const Vec eb1 = b1 - a, ec1 = c1 - a, eb2 = b2 - a, ec2 = c2 - a;
    const double sb2 = dot(eb2, n1), sc2 = dot(ec2, n1);
    if ((sb2 > 0 && sc2 > 0) || (sb2 < 0 && sc2 < 0)) {
        const double flat = 1e-6 * std::sqrt(std::max(norm2(eb2), norm2(ec2)));
        if (std::abs(sb2) > flat || std::abs(sc2) > flat) return false;
    } else {
        const double sb1 = dot(eb1, n2), sc1 = dot(ec1, n2);
        if ((sb1 > 0 && sc1 > 0) || (sb1 < 0 && sc1 < 0)) return false;
        const double flat = 1e-6 * std::sqrt(std::max({norm2(eb1), norm2(ec1), norm2(eb2), norm2(ec2)}));
        const bool coplanar = std::abs(sb2) <= flat && std::abs(sc2) <= flat;
        if (!coplanar && sb1 != sc1 && sb2 != sc2) {
            const Vec x1 = eb1 + (sb1 / (sb1 - sc1)) * (ec1 - eb1);
            const Vec x2 = eb2 + (sb2 / (sb2 - sc2)) * (ec2 - eb2);
            return dot(x1, x2) > 0;
        }
    }
    // One plane: compare the angles at a, turning about n1.
    auto inside = [&](Vec d, Vec e, Vec f) {
        const double turn = dot(cross(e, f), n1);
        return dot(cross(e, d), n1) * turn > 0 && dot(cross(d, f), n1) * turn > 0;
    };
    auto bisector = [](Vec e, Vec f) { return (1.0 / norm(e)) * e + (1.0 / norm(f)) * f; };
    return inside(eb2, eb1, ec1) || inside(ec2, eb1, ec1) || inside(bisector(eb2, ec2), eb1, ec1) ||
           inside(eb1, eb2, ec2) || inside(ec1, eb2, ec2);
}

// Whether triangles (a, b, c), of unit normal n1, and (b, a, d), which share
// edge (a, b), overlap: only when they lie in one plane with c and d on the
// same side of the edge (the surface folded flat onto itself).
TETISO_HD inline bool overlap_at_edge(Vec a, Vec b, Vec c, Vec n1, Vec d) {
    const Vec ab = b - a, ad = d - a;
    if (std::abs(dot(ad, n1)) > 1e-6 * std::sqrt(std::max(norm2(ab), norm2(ad)))) return false;
    return dot(cross(ab, c - a), cross(ab, ad)) > 0;
}

// Whether x and y lie clearly on one side of the plane through corner a of
// normal n: then a face (a, x, y) meets the face of that plane at a only
// (overlap_at_corner's first test, which settles most pairs).
TETISO_HD inline bool apart(Vec a, Vec n, Vec x, Vec y) {
    const Vec ex = x - a, ey = y - a;
    const double sx = dot(ex, n), sy = dot(ey, n);
    if (!((sx > 0 && sy > 0) || (sx < 0 && sy < 0))) return false;
    const double flat2 = 1e-12 * std::max(norm2(ex), norm2(ey));
    return sx * sx > flat2 || sy * sy > flat2;
}

// Whether the half-open angle [a, b) at a fan's apex, seen along m (the
// sides ea, eb taken from the apex), holds the ray `ray` (perpendicular to
// m); across = m x ray. starts_on_ray: a is the ray's own side, counted as
// on it whatever rounding says. A fan whose faces all turn the same way
// about the apex turns once around it exactly when one of its angles holds
// the ray along the first side of its first face.
TETISO_HD inline bool holds_ray(Vec ea, Vec eb, Vec ray, Vec across, bool starts_on_ray) {
    const double sa = starts_on_ray ? 0.0 : dot(ea, across), sb = dot(eb, across);
    if (!(sa <= 0 && sb > 0)) return false;
    const double t = sa / (sa - sb);
    return dot(ea, ray) + t * (dot(eb, ray) - dot(ea, ray)) > 0;
}

TETISO_HD inline double point_segment_distance(Vec p, Vec a, Vec b) {
    const Vec ab = b - a;
    const double len2 = norm2(ab);
    double t = len2 > 0 ? dot(p - a, ab) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return norm(p - (a + t * ab));
}

// Distance from p to triangle (a, b, c) (Ericson, Real-Time Collision
// Detection, 5.1.5). Forced inline into the sample loops, which call it more
// than anything else in a job's profile.
TETISO_HD TETISO_INLINE double point_triangle_distance(Vec p, Vec a, Vec b, Vec c) {
    const Vec ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return norm(ap);
    const Vec bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return norm(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return norm(p - (a + (d1 / (d1 - d3)) * ab));
    const Vec cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return norm(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return norm(p - (a + (d2 / (d2 - d6)) * ac));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return norm(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
    const double denom = va + vb + vc;
    if (!(denom > 0)) return std::min(norm(ap), std::min(norm(bp), norm(cp)));
    const double v = vb / denom, w = vc / denom;
    return norm(p - (a + v * ab + w * ac));
}

// Deterministic 64-bit mixing (splitmix64 finaliser).
TETISO_HD inline u64 mix64(u64 x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

} // namespace tetiso::reduction
