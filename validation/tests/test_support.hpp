// Small helpers shared by the test programs: building lattice surfaces and
// comparing pieces exactly.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"
#include "tetiso/field.hpp"
#include "tetiso/lattice.hpp"
#include "tetiso/seam.hpp"

namespace tetiso::test {

// What f throws as a tetiso::Error, or "(no error)".
inline std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

// The whole file as bytes (empty if it cannot be read).
inline std::string read_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A directory of its own for the running test (process id and test name, so
// that CTest's parallel runs never share one), removed with everything in it
// when the object goes.
class ScratchDirectory {
public:
    explicit ScratchDirectory(const std::string& prefix)
        : path_(std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()) + "_" + test_name())) {
        std::filesystem::create_directories(path_);
    }
    ~ScratchDirectory() { std::filesystem::remove_all(path_); }
    ScratchDirectory(const ScratchDirectory&) = delete;
    ScratchDirectory& operator=(const ScratchDirectory&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path at(const std::string& name) const { return path_ / name; }

private:
    // One path component: a parameterised test's name holds a '/', which
    // would leave the directory above it behind.
    static std::string test_name() {
        std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        std::replace(name.begin(), name.end(), '/', '_');
        return name;
    }

    std::filesystem::path path_;
};

// Renumbers a domain's nodes by `order` (new index -> old index).
inline Domain renumbered(const Domain& d, const std::vector<std::int32_t>& order) {
    Domain out = d;
    std::vector<std::int32_t> rank(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
        const auto old = static_cast<std::size_t>(order[i]);
        rank[old] = static_cast<std::int32_t>(i);
        out.x[i] = d.x[old];
        out.y[i] = d.y[old];
        out.z[i] = d.z[old];
        out.f[i] = d.f[old];
        out.gid[i] = d.gid[old];
        out.interface[i] = d.interface[old];
    }
    for (auto& v : out.tets) v = rank[static_cast<std::size_t>(v)];
    return out;
}

// Extracts every domain of an N-lattice split into D domains and merges the
// pieces by key, as `tetiso extract` does.
inline Piece lattice_surface(std::int64_t n, int domains, const std::string& field_name,
                             std::optional<double> level = std::nullopt, int threads = 1) {
    const Lattice lattice(n);
    const Decomposition decomposition(lattice, domains);
    const auto field = make_field(field_name);
    const auto value = static_cast<float>(level.value_or(field->default_level()));
    std::vector<Piece> pieces;
    for (int d = 0; d < decomposition.domain_count(); ++d)
        pieces.push_back(extract(decomposition.make_domain(d, *field), value, ExtractOptions{threads}));
    Piece surface = merge_all(std::move(pieces));
    unlock_settled(surface, [&](GlobalId a, GlobalId b) { return decomposition.domains_of_edge(a, b); });
    return surface;
}

// Triangles as vertex-key triples rotated to start at the smallest key,
// sorted: equal lists mean the same triangles with the same orientation.
inline std::vector<std::array<EdgeKey, 3>> canonical_triangles(const Piece& piece) {
    std::vector<std::array<EdgeKey, 3>> out(piece.triangle_count());
    for (std::size_t t = 0; t < out.size(); ++t) {
        std::array<EdgeKey, 3> k{piece.key[static_cast<std::size_t>(piece.triangles[3 * t])],
                                 piece.key[static_cast<std::size_t>(piece.triangles[3 * t + 1])],
                                 piece.key[static_cast<std::size_t>(piece.triangles[3 * t + 2])]};
        std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
        out[t] = k;
    }
    std::sort(out.begin(), out.end());
    return out;
}

inline bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](float p, float q) {
               return std::bit_cast<std::uint32_t>(p) == std::bit_cast<std::uint32_t>(q);
           });
}

// Same vertices (keys, bit-identical positions, flags) and same triangles up
// to their order.
inline bool same_surface(const Piece& a, const Piece& b) {
    return a.key == b.key && same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z) &&
           a.flags == b.flags && canonical_triangles(a) == canonical_triangles(b);
}

// Distance from p to triangle (a, b, c), written here rather than taken from
// the library so that the tests check it with a second implementation: the
// plane's distance when p projects inside, else the nearest edge's.
inline double point_triangle_distance(std::array<double, 3> p, std::array<double, 3> a, std::array<double, 3> b,
                                      std::array<double, 3> c) {
    auto sub = [](std::array<double, 3> u, std::array<double, 3> v) {
        return std::array<double, 3>{u[0] - v[0], u[1] - v[1], u[2] - v[2]};
    };
    auto dot = [](std::array<double, 3> u, std::array<double, 3> v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
    auto cross = [](std::array<double, 3> u, std::array<double, 3> v) {
        return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    };
    auto segment = [&](std::array<double, 3> u, std::array<double, 3> v) {
        const auto uv = sub(v, u), up = sub(p, u);
        const double len2 = dot(uv, uv);
        const double t = len2 > 0 ? std::clamp(dot(up, uv) / len2, 0.0, 1.0) : 0.0;
        const std::array<double, 3> q{u[0] + t * uv[0], u[1] + t * uv[1], u[2] + t * uv[2]};
        const auto d = sub(p, q);
        return std::sqrt(dot(d, d));
    };
    const auto n = cross(sub(b, a), sub(c, a));
    const double n2 = dot(n, n);
    if (n2 > 0) {
        // Inside when p's projection lies on the inner side of all three edges.
        const bool inside = dot(cross(sub(b, a), sub(p, a)), n) >= 0 && dot(cross(sub(c, b), sub(p, b)), n) >= 0 &&
                            dot(cross(sub(a, c), sub(p, c)), n) >= 0;
        if (inside) return std::abs(dot(sub(p, a), n)) / std::sqrt(n2);
    }
    return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

// The positions of a piece's referenced vertices, sorted.
inline std::vector<std::array<float, 3>> referenced_positions(const Piece& piece) {
    std::vector<std::uint8_t> used(piece.vertex_count(), 0);
    for (const std::int32_t v : piece.triangles) used[static_cast<std::size_t>(v)] = 1;
    std::vector<std::array<float, 3>> out;
    for (std::size_t v = 0; v < piece.vertex_count(); ++v)
        if (used[v]) out.push_back({piece.x[v], piece.y[v], piece.z[v]});
    std::sort(out.begin(), out.end());
    return out;
}

// The positions of a piece's raw-vertex samples, sorted.
inline std::vector<std::array<float, 3>> sample_positions(const Piece& piece) {
    std::vector<std::array<float, 3>> out(piece.sample_count());
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = {piece.sample_xyz[3 * i], piece.sample_xyz[3 * i + 1], piece.sample_xyz[3 * i + 2]};
    std::sort(out.begin(), out.end());
    return out;
}

// What Piece promises of its samples: each is one of the raw vertices
// (`raw`, sorted), held by a triangle marked sampled, whose error bounds the
// sample's distance to it.
inline void expect_samples_sound(const Piece& piece, const std::vector<std::array<float, 3>>& raw,
                                 const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_TRUE(piece.sampled.empty() || piece.sampled.size() == piece.triangle_count());
    ASSERT_EQ(piece.sample_xyz.size(), 3 * piece.sample_count());
    std::size_t unsound = 0, foreign = 0;
    for (std::size_t i = 0; i < piece.sample_count(); ++i) {
        const auto t = static_cast<std::size_t>(piece.sample_triangle[i]);
        ASSERT_LT(t, piece.triangle_count());
        ASSERT_TRUE(piece.triangle_sampled(t)) << "sample " << i << " of triangle " << t;
        auto corner = [&](int k) {
            const auto v = static_cast<std::size_t>(piece.triangles[3 * t + static_cast<std::size_t>(k)]);
            return std::array<double, 3>{piece.x[v], piece.y[v], piece.z[v]};
        };
        const std::array<float, 3> q{piece.sample_xyz[3 * i], piece.sample_xyz[3 * i + 1], piece.sample_xyz[3 * i + 2]};
        const double d = point_triangle_distance({q[0], q[1], q[2]}, corner(0), corner(1), corner(2));
        unsound += d > piece.triangle_error(t) * (1 + 1e-5) + 1e-7 ? 1 : 0;
        foreign += std::binary_search(raw.begin(), raw.end(), q) ? 0 : 1;
    }
    EXPECT_EQ(unsound, 0u) << "samples farther from their triangle than its error";
    EXPECT_EQ(foreign, 0u) << "samples that are no raw vertex";
}

inline double area(const Piece& p) {
    double sum = 0;
    for (std::size_t t = 0; t < p.triangle_count(); ++t) {
        const auto a = static_cast<std::size_t>(p.triangles[3 * t]), b = static_cast<std::size_t>(p.triangles[3 * t + 1]),
                   c = static_cast<std::size_t>(p.triangles[3 * t + 2]);
        const double u[3] = {p.x[b] - p.x[a], p.y[b] - p.y[a], p.z[b] - p.z[a]};
        const double v[3] = {p.x[c] - p.x[a], p.y[c] - p.y[a], p.z[c] - p.z[a]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        sum += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return sum;
}

// Signed enclosed volume (divergence theorem): positive when normals point out.
inline double signed_volume(const Piece& p) {
    double sum = 0;
    for (std::size_t t = 0; t < p.triangle_count(); ++t) {
        const auto a = static_cast<std::size_t>(p.triangles[3 * t]), b = static_cast<std::size_t>(p.triangles[3 * t + 1]),
                   c = static_cast<std::size_t>(p.triangles[3 * t + 2]);
        const double ax = p.x[a] - 2.5, ay = p.y[a] - 2.5, az = p.z[a] - 2.5;
        const double bx = p.x[b] - 2.5, by = p.y[b] - 2.5, bz = p.z[b] - 2.5;
        const double cx = p.x[c] - 2.5, cy = p.y[c] - 2.5, cz = p.z[c] - 2.5;
        sum += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6.0;
    }
    return sum;
}

} // namespace tetiso::test
