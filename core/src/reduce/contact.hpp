// Contact with faces that share no corner (contact_filter.hpp): the round's
// triangles, and the faces its chosen operations make, bucketed by the cells
// of a uniform grid, so that an operation's new faces are tested against
// every face near them, not only against the faces around their corners.
// Where the surface folds back close to itself (two sheets of one component
// a few faces apart, a border running past a sheet) a collapse whose faces
// each turn by little can still carry its fan through a face it shares
// nothing with; the soundness soak's reduced surfaces that crossed
// themselves (results/soundness) were all of this kind.
//
// The grid is built each round from the positions alone, with integer
// counts and the Exec primitives only (exclusive_sum, group_by_key), so it is
// the same on every backend and thread count; the tests that read it are
// per-element functions on float positions in double precision.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "../hd.hpp"
#include "adjacency.hpp"
#include "geometry.hpp"

namespace tetiso::reduction {

// A triangle whose cells span more than two per axis goes into the bucket
// of every cell it covers, or, past this many, into one bucket of its own
// that every query reads (few do: a cell is at least as large as about nine
// in ten of the round's triangles).
constexpr int kMaxCellsPerTriangle = 27;
// A query spanning more cells than this reads every triangle instead: the
// answer must not depend on the cell size, which a batch of pieces
// (batch.hpp) chooses from all of them.
constexpr i64 kMaxCellsPerQuery = 512;
// Cell indices are clamped to 21 bits a side: cells beyond merge, which only
// makes a bucket hold more.
constexpr i64 kCellLimit = i64{1} << 20;
// Distances below this many units in the last place of the coordinates count
// as contact: the positions tested are those that will be written, so the
// margin need only cover the rounding of the test's own arithmetic. A wider
// one judges the cluster of crossings the node clearance leaves around a
// node on the level (extract_rules.hpp, a few dozen ulps across) to be in
// contact with itself, and the cluster stays, needles and all.
constexpr double kContactUlps = 2.0;

struct Box {
    Vec lo, hi;
    TETISO_HD void add(Vec p) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    TETISO_HD double extent() const { return std::max(hi.x - lo.x, std::max(hi.y - lo.y, hi.z - lo.z)); }
    TETISO_HD bool apart(const Box& o, double margin) const {
        return lo.x > o.hi.x + margin || o.lo.x > hi.x + margin || lo.y > o.hi.y + margin ||
               o.lo.y > hi.y + margin || lo.z > o.hi.z + margin || o.lo.z > hi.z + margin;
    }
};

TETISO_HD inline Box box_of(Vec a, Vec b, Vec c) {
    Box box{a, a};
    box.add(b);
    box.add(c);
    return box;
}

// A triangle's box in its own float coordinates (min and max are exact).
struct FloatBox {
    float lo[3], hi[3];
    TETISO_HD Box box() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
};

// A triangle as the queries read it, copied into its bucket's run so that a
// query reads memory in order: its vertices (-2 for an obstacle's corners,
// which are no vertices of the piece; -3 for a collapse's new vertex), its
// corners' positions, and for a face a chosen operation makes, that
// operation's edge (op; -1 for the round's own faces and the obstacles).
struct ContactTriangle {
    i32 id[3];
    float at[9];
    i32 op;
    TETISO_HD Vec corner(int c) const { return {at[3 * c], at[3 * c + 1], at[3 * c + 2]}; }
    TETISO_HD bool obstacle() const { return id[0] == -2; }
    // A vertex of the piece, for a face of the round or a made one (whose
    // new vertex is none).
    TETISO_HD i32 vertex() const { return id[0] >= 0 ? id[0] : id[1]; }
    TETISO_HD bool made() const { return op >= 0; }
    TETISO_HD FloatBox box() const {
        FloatBox b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::min(at[a], std::min(at[3 + a], at[6 + a]));
            b.hi[a] = std::max(at[a], std::max(at[3 + a], at[6 + a]));
        }
        return b;
    }
};

// The low 21 bits of x, two zero bits after each (a Morton code's axis).
TETISO_HD inline u64 spread3(u64 x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffULL;
    x = (x | x << 16) & 0x1f0000ff0000ffULL;
    x = (x | x << 8) & 0x100f00f00f00f00fULL;
    x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
    x = (x | x << 2) & 0x1249249249249249ULL;
    return x;
}

struct ContactGridView {
    const i32* first;                  // per bucket, its first triangle (groups + 2 entries)
    const FloatBox* boxes;             // grouped by bucket: what a query reads first
    const ContactTriangle* triangles;  // grouped by bucket
    const i32* vertex_piece;           // a batch's piece of each vertex (batch.hpp); null for one piece
    i32 groups;                        // buckets of cells (a power of two); bucket `groups` holds the large triangles
    double inv_cell;                   // 1 / cell size (a power of two)
    bool on;

    TETISO_HD i64 cell(double x) const {
        const double c = std::floor(x * inv_cell);
        return c < -static_cast<double>(kCellLimit) ? -kCellLimit
               : c > static_cast<double>(kCellLimit - 1) ? kCellLimit - 1
                                                         : static_cast<i64>(c);
    }
    // The cells tile the buckets periodically, in Morton order: the cells a
    // query reads, and the queries of neighbouring operations, lie in few
    // runs of memory, and two cells share a bucket only when they are a
    // whole period apart.
    TETISO_HD i32 bucket(i64 ix, i64 iy, i64 iz) const {
        const u64 code = spread3(static_cast<u64>(ix + kCellLimit)) << 2 |
                         spread3(static_cast<u64>(iy + kCellLimit)) << 1 | spread3(static_cast<u64>(iz + kCellLimit));
        return static_cast<i32>(code & static_cast<u64>(groups - 1));
    }
};

// The cells a box covers, per axis (inclusive ranges), and their number.
struct CellRange {
    i64 lo[3], hi[3];
    // Saturates (a box across the clamped range would overflow a product of
    // three 21-bit spans).
    TETISO_HD i64 count() const {
        constexpr i64 kMost = i64{1} << 40;
        i64 n = 1;
        for (int a = 0; a < 3; ++a) n = std::min(n * (hi[a] - lo[a] + 1), kMost);
        return n;
    }
    // Whether the box spans at most two cells per axis: such a triangle
    // goes into the bucket of its lowest cell only.
    TETISO_HD bool small() const { return hi[0] - lo[0] <= 1 && hi[1] - lo[1] <= 1 && hi[2] - lo[2] <= 1; }
};
TETISO_HD inline CellRange cells_of(const ContactGridView& g, const Box& box) {
    return {{g.cell(box.lo.x), g.cell(box.lo.y), g.cell(box.lo.z)},
            {g.cell(box.hi.x), g.cell(box.hi.y), g.cell(box.hi.z)}};
}

// Triangle t of the grid: the surface's, then from nt on the obstacles (9
// floats each), then the faces the round's chosen operations make.
struct GridSource {
    SurfaceView s;
    const float* obstacle;
    i32 obstacles;
    const ContactTriangle* made;
    TETISO_HD ContactTriangle operator()(i32 t) const {
        ContactTriangle c;
        c.op = -1;
        if (t < s.nt) {
            for (int k = 0; k < 3; ++k) {
                const i32 v = s.tri[3 * t + k];
                const Vec q = s.pos(v);
                c.id[k] = v;
                c.at[3 * k] = static_cast<float>(q.x);
                c.at[3 * k + 1] = static_cast<float>(q.y);
                c.at[3 * k + 2] = static_cast<float>(q.z);
            }
            return c;
        }
        if (t >= s.nt + obstacles) return made[t - s.nt - obstacles];
        const float* q = obstacle + 9 * static_cast<std::size_t>(t - s.nt);
        for (int k = 0; k < 3; ++k) c.id[k] = -2;
        for (int k = 0; k < 9; ++k) c.at[k] = q[k];
        return c;
    }
};

// A triangle's histogram bin: the float exponent of its box's extent.
TETISO_HD inline i32 extent_bin(const FloatBox& box) {
    const float e = static_cast<float>(box.box().extent());
    u32 b;
    std::memcpy(&b, &e, sizeof b);
    return static_cast<i32>((b >> 23) & 0xff);
}

// How many buckets a triangle goes into: one for a small one (its lowest
// cell) or a large one (the bucket of its own), else one per cell.
TETISO_HD inline u32 entries_of(const ContactGridView& g, const FloatBox& box) {
    const CellRange r = cells_of(g, box.box());
    if (r.small()) return 1u;
    const i64 n = r.count();
    return n > kMaxCellsPerTriangle ? 1u : static_cast<u32>(n);
}

template <class Exec>
struct ContactGrid {
    template <class T>
    using Array = typename Exec::template Array<T>;
    Array<i32> histogram, entry_tri, entry_bucket, first, order, scratch;
    Array<u32> offsets;
    Array<FloatBox> box, entry_box;
    Array<ContactTriangle> triangles, made;
    Array<float> obstacle;
    i32 obstacles = 0;
    ContactGridView grid{nullptr, nullptr, nullptr, nullptr, 0, 0.0, false};

    ContactGridView view() const { return grid; }
};

constexpr int kExtentBins = 256;
// The cell size is read from this many triangles' extents or more: it sets
// how fast the grid is, never what a query finds.
constexpr i64 kExtentSamples = i64{1} << 14;

// Builds the grid of the round's faces, the obstacles and the first `made`
// faces of cg.made: the cell is the power of two at or above the extent of
// nine in ten triangles of a sample (a histogram of their float exponents:
// integer counts); a triangle spanning at most two cells per axis goes into
// the bucket of its lowest cell, so that a query reads one cell more below
// its box; a larger one into the bucket of every cell it covers. Then the
// triangles are copied into their buckets' runs.
template <class Exec>
void build_contact_grid(Exec& exec, const SurfaceView& s, const i32* vertex_piece, i32 made, ContactGrid<Exec>& cg) {
    cg.grid.on = false;
    const i64 total = static_cast<i64>(s.nt) + cg.obstacles + made;
    if (s.nt == 0) return;
    const GridSource source{s, cg.obstacles > 0 ? cg.obstacle.data() : nullptr, cg.obstacles,
                            made > 0 ? cg.made.data() : nullptr};
    ContactGridView g{nullptr, nullptr, nullptr, vertex_piece, 1, 1.0, true};
    exec.assign(cg.histogram, kExtentBins, i32{0});
    i32* histogram = cg.histogram.data();
    cg.box.resize(static_cast<std::size_t>(total));
    FloatBox* box = cg.box.data();
    // The histogram counts every stride-th triangle: on the device, every
    // triangle's increment of one of a few bins queued at that bin's
    // address.
    const i64 stride = std::max<i64>(1, total / kExtentSamples), sampled = (total + stride - 1) / stride;
    exec.for_each(total, [=] TETISO_HD(i64 t) {
        box[t] = source(static_cast<i32>(t)).box();
        if (t % stride == 0) hd::atomic_add(histogram + extent_bin(box[t]), 1);
    });
    std::vector<i32> counts;
    exec.download(cg.histogram, kExtentBins, counts);
    i64 seen = 0;
    int bin = 0;
    for (; bin < kExtentBins - 1; ++bin) {
        seen += counts[static_cast<std::size_t>(bin)];
        if (10 * seen >= 9 * sampled) break;
    }
    // Bin b holds extents below 2^(b - 126); a cell at least that large, and
    // no smaller than 2^-100 (a surface of zero-extent triangles).
    const int exponent = std::max(bin - 126, -100);
    g.inv_cell = std::ldexp(1.0, -exponent);
    const u64 entries = exec.exclusive_sum(
        total, [=] TETISO_HD(i64 t) { return entries_of(g, box[t]); }, cg.offsets);
    i32 groups = 1;
    while (static_cast<u64>(groups) < entries && groups < (1 << 30)) groups *= 2;
    g.groups = groups;
    cg.entry_tri.resize(static_cast<std::size_t>(entries));
    cg.entry_bucket.resize(static_cast<std::size_t>(entries));
    i32* entry_tri = cg.entry_tri.data();
    i32* entry_bucket = cg.entry_bucket.data();
    const u32* offsets = cg.offsets.data();
    exec.for_each(total, [=] TETISO_HD(i64 ti) {
        const i32 t = static_cast<i32>(ti);
        u32 at = offsets[t];
        const CellRange r = cells_of(g, box[t].box());
        if (r.small()) {
            entry_tri[at] = t;
            entry_bucket[at] = g.bucket(r.lo[0], r.lo[1], r.lo[2]);
            return;
        }
        if (r.count() > kMaxCellsPerTriangle) {
            entry_tri[at] = t;
            entry_bucket[at] = g.groups;
            return;
        }
        for (i64 x = r.lo[0]; x <= r.hi[0]; ++x)
            for (i64 y = r.lo[1]; y <= r.hi[1]; ++y)
                for (i64 z = r.lo[2]; z <= r.hi[2]; ++z) {
                    entry_tri[at] = t;
                    entry_bucket[at++] = g.bucket(x, y, z);
                }
    });
    const i32* bucket_of = entry_bucket;
    exec.group_by_key(static_cast<i64>(entries), static_cast<i64>(groups) + 1,
                      [=] TETISO_HD(i64 i) { return bucket_of[i]; }, cg.first, cg.order, cg.scratch);
    cg.triangles.resize(static_cast<std::size_t>(entries));
    cg.entry_box.resize(static_cast<std::size_t>(entries));
    ContactTriangle* triangles = cg.triangles.data();
    FloatBox* entry_box = cg.entry_box.data();
    const i32* order = cg.order.data();
    exec.for_each(static_cast<i64>(entries), [=] TETISO_HD(i64 k) {
        const i32 t = entry_tri[order[k]];
        triangles[k] = source(t);
        entry_box[k] = box[t];
    });
    g.first = cg.first.data();
    g.boxes = entry_box;
    g.triangles = triangles;
    cg.grid = g;
}

// Distance between segments (p0, p1) and (q0, q1) (Ericson, Real-Time
// Collision Detection, 5.1.9).
TETISO_HD inline double segment_distance(Vec p0, Vec p1, Vec q0, Vec q1) {
    const Vec d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = norm2(d1), e = norm2(d2), f = dot(d2, r);
    double s = 0.0, t = 0.0;
    if (a <= 0 && e <= 0) return norm(r);
    if (a <= 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return norm((p0 + s * d1) - (q0 + t * d2));
}

// Whether segment (q0, q1) comes within eps of triangle (a, b, c) of unit
// normal n: where it crosses the plane, or where it lies in it.
TETISO_HD inline bool segment_meets(Vec a, Vec b, Vec c, Vec n, Vec q0, Vec q1, double eps) {
    const double d0 = dot(q0 - a, n), d1 = dot(q1 - a, n);
    if ((d0 > eps && d1 > eps) || (d0 < -eps && d1 < -eps)) return false;
    if (std::abs(d0) <= eps && std::abs(d1) <= eps) // in the plane: the segment against the triangle's sides
        return point_triangle_distance(q0, a, b, c) <= eps || point_triangle_distance(q1, a, b, c) <= eps ||
               segment_distance(q0, q1, a, b) <= eps || segment_distance(q0, q1, b, c) <= eps ||
               segment_distance(q0, q1, c, a) <= eps;
    const double t = d0 == d1 ? 0.0 : std::clamp(d0 / (d0 - d1), 0.0, 1.0);
    return point_triangle_distance(q0 + t * (q1 - q0), a, b, c) <= eps;
}

// Whether triangles p and q, which share no corner, meet or come within a
// few units in the last place of their coordinates (contact that rounding
// would decide). A degenerate one (zero area: a segment or a point) meets
// the other where one of its sides does. np: p's unit normal as quality()
// gives it (zero when p is degenerate), which the caller often has.
TETISO_HD inline bool triangles_meet(Vec p0, Vec p1, Vec p2, Vec np, Vec q0, Vec q1, Vec q2) {
    double extent = 0.0;
    for (const Vec v : {p0, p1, p2, q0, q1, q2})
        extent = std::max(extent, std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))));
    const double eps = kContactUlps * std::numeric_limits<float>::epsilon() * extent;
    const bool p_flat = !(norm2(np) > 0);
    if (!p_flat) {
        // q wholly on one side of p's plane, farther than eps: none of q's
        // sides comes near p (segment_meets below, which would measure the
        // same distances), nor does any point of that plane come near q.
        const double d0 = dot(q0 - p0, np), d1 = dot(q1 - p0, np), d2 = dot(q2 - p0, np);
        if ((d0 > eps && d1 > eps && d2 > eps) || (d0 < -eps && d1 < -eps && d2 < -eps)) return false;
    }
    Vec nq;
    const bool q_flat = !(quality(q0, q1, q2, &nq) > 0);
    if (!q_flat) { // and the same the other way
        const double d0 = dot(p0 - q0, nq), d1 = dot(p1 - q0, nq), d2 = dot(p2 - q0, nq);
        if ((d0 > eps && d1 > eps && d2 > eps) || (d0 < -eps && d1 < -eps && d2 < -eps)) return false;
    }
    if (p_flat && q_flat) {
        const Vec p[3] = {p0, p1, p2}, q[3] = {q0, q1, q2};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (segment_distance(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3]) <= eps) return true;
        return false;
    }
    return (!q_flat && (segment_meets(q0, q1, q2, nq, p0, p1, eps) || segment_meets(q0, q1, q2, nq, p1, p2, eps) ||
                        segment_meets(q0, q1, q2, nq, p2, p0, eps))) ||
           (!p_flat && (segment_meets(p0, p1, p2, np, q0, q1, eps) || segment_meets(p0, p1, p2, np, q1, q2, eps) ||
                        segment_meets(p0, p1, p2, np, q2, q0, eps)));
}

TETISO_HD inline bool triangles_meet(Vec p0, Vec p1, Vec p2, Vec q0, Vec q1, Vec q2) {
    Vec np;
    quality(p0, p1, p2, &np);
    return triangles_meet(p0, p1, p2, np, q0, q1, q2);
}

// What a query reads: its box widened by twice the margin, in float
// (rounding it, by half a float ulp, cannot leave out a triangle within the
// margin of the box), and the cells around that, one more below (a small
// triangle sits in its lowest cell only); or, where those would be more
// than kMaxCellsPerQuery, every entry. Its items, read one by one and each
// on its own: 0, the bucket of the large triangles; then one per cell in
// x, y, z order (or one for every entry).
struct ContactQuery {
    float lo[3], hi[3];
    CellRange cells;
    bool every;

    TETISO_HD bool near(const FloatBox& t) const {
        return !(t.lo[0] > hi[0] || t.hi[0] < lo[0] || t.lo[1] > hi[1] || t.hi[1] < lo[1] || t.lo[2] > hi[2] ||
                 t.hi[2] < lo[2]);
    }
    TETISO_HD i64 items() const { return 1 + (every ? 1 : cells.count()); }
};

TETISO_HD inline ContactQuery contact_query(const ContactGridView& g, const Box& box, double margin) {
    const double reach = 2.0 * margin;
    const Box wide{{box.lo.x - reach, box.lo.y - reach, box.lo.z - reach},
                   {box.hi.x + reach, box.hi.y + reach, box.hi.z + reach}};
    ContactQuery q{{static_cast<float>(wide.lo.x), static_cast<float>(wide.lo.y), static_cast<float>(wide.lo.z)},
                   {static_cast<float>(wide.hi.x), static_cast<float>(wide.hi.y), static_cast<float>(wide.hi.z)},
                   cells_of(g, wide),
                   false};
    for (int a = 0; a < 3; ++a) q.cells.lo[a] = std::max(q.cells.lo[a] - 1, -kCellLimit);
    q.every = q.cells.count() > kMaxCellsPerQuery;
    return q;
}

// The entries item `item` of query q reads: [begin, end) of the grid's
// (g.triangles, g.boxes), and for a cell the cell itself.
struct ItemSpan {
    i32 begin, end;
    bool cell;
    i64 x, y, z;
};
TETISO_HD inline ItemSpan item_span(const ContactGridView& g, const ContactQuery& q, i64 item) {
    if (item == 0) return {g.first[g.groups], g.first[g.groups + 1], false, 0, 0, 0};
    if (q.every) return {0, g.first[g.groups], false, 0, 0, 0};
    const CellRange& r = q.cells;
    const i64 sy = r.hi[1] - r.lo[1] + 1, sz = r.hi[2] - r.lo[2] + 1, c = item - 1;
    const i64 x = r.lo[0] + c / (sy * sz), y = r.lo[1] + (c / sz) % sy, z = r.lo[2] + c % sz;
    const i32 bucket = g.bucket(x, y, z);
    return {g.first[bucket], g.first[bucket + 1], true, x, y, z};
}

// Whether entry k of span `span` is one for_each_entry_of_item calls f for:
// its triangle's box comes within the query's box, and a triangle of a cell
// is read once, at the first of its cells that the query reads (its lowest
// cell, or the query's, per axis). Without the latter, a bucket that many of
// the query's cells share (a small surface has few) is read once for each
// of them.
TETISO_HD inline bool entry_read(const ContactGridView& g, const ContactQuery& q, const ItemSpan& span, i32 k) {
    const FloatBox& b = g.boxes[k];
    if (!q.near(b)) return false;
    if (!span.cell) return true;
    const CellRange own = cells_of(g, b.box());
    const CellRange& r = q.cells;
    return std::max(own.lo[0], r.lo[0]) == span.x && std::max(own.lo[1], r.lo[1]) == span.y &&
           std::max(own.lo[2], r.lo[2]) == span.z;
}

// Calls f(k) for every entry k (g.triangles[k], g.boxes[k]) of item `item`
// of query q whose triangle's box comes within the query's margin of its box
// (and for some others beside it: f must not depend on being called only
// for those), until f returns false; whether none did. Over all the items,
// f sees every such triangle of the grid.
template <class F>
TETISO_HD bool for_each_entry_of_item(const ContactGridView& g, const ContactQuery& q, i64 item, const F& f) {
    const ItemSpan span = item_span(g, q, item);
    for (i32 k = span.begin; k < span.end; ++k)
        if (entry_read(g, q, span, k) && !f(k)) return false;
    return true;
}

} // namespace tetiso::reduction
