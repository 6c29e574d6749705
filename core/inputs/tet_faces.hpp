// Internal: the faces of a tetrahedral mesh, each found once with the
// tetrahedra that have it. One pass gives a piece's boundary (faces of one
// tetrahedron only) and the check that no two tetrahedra overlap across a
// face.
//
// Extraction winds every triangle by its own tetrahedron's orientation
// (marching_tets.hpp), so the surface is consistently oriented across a
// face exactly when the two tetrahedra on it lie on opposite sides of it.
// Over positively oriented tetrahedra that is combinatorial: each induces
// an orientation on its faces, and two on opposite sides induce opposite
// ones. A face whose two tetrahedra induce the same orientation is a fold
// (one of them inverted, as where a node was moved across a face) or a
// tetrahedron listed twice; a face of three or more tetrahedra is an
// overlap whatever their positions. What this cannot see is an overlap with
// no such face: a mesh whose boundary passes through itself (two sheets of
// cells over one place, a tetrahedron inverted through the mesh's outer
// boundary with every neighbour still across its faces) needs a search in
// space, which is not done.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tetiso/error.hpp"

namespace tetiso::detail {

// The worst place where tetrahedra of a mesh overlap, as face_pass finds it.
struct FaceClash {
    enum class Kind { none, repeated, folded, crowded };
    Kind kind = Kind::none;
    // The tetrahedra in the file's order; third is second but where crowded.
    std::size_t first = 0, second = 0, third = 0;
    std::size_t faces = 0; // faces that clash, in all
};

// Every face of `tets` (4 corners each, each tetrahedron positively
// oriented, corners below `nodes`): calls boundary(u, v, w, t) for each face
// that only tetrahedron t has (u < v < w), and returns the clash that comes
// first in the file (the smallest later tetrahedron of a clashing pair),
// with the count of all. Faces are bucketed by their smallest corner and
// matched within each bucket, a few dozen faces, which is several times
// faster than sorting them all.
template <class Boundary>
FaceClash face_pass(const std::vector<std::int32_t>& tets, std::size_t nodes, Boundary boundary) {
    const std::size_t count = tets.size() / 4;
    // A tetrahedron's corners sorted, and the parity of that permutation.
    const auto sorted = [&tets](std::size_t t, std::int32_t (&c)[4]) {
        for (int k = 0; k < 4; ++k) c[k] = tets[4 * t + static_cast<std::size_t>(k)];
        std::uint32_t odd = 0;
        const auto order = [&](int i, int j) {
            if (c[i] > c[j]) std::swap(c[i], c[j]), odd ^= 1u;
        };
        order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
        return odd;
    };
    // Each face goes to the bucket of its smallest corner: three faces of a
    // tetrahedron to that of its smallest corner c[0], the fourth (without
    // c[0]) to that of c[1]. The tetrahedra are grouped (counting sorts) by
    // both, and a bucket's faces made from them when it comes: two indices
    // per tetrahedron in memory, not four faces.
    std::vector<std::uint32_t> first_by[2], tets_by[2];
    for (int rank = 0; rank < 2; ++rank) first_by[rank].assign(nodes + 1, 0), tets_by[rank].resize(count);
    for (std::size_t t = 0; t < count; ++t) {
        std::int32_t c[4];
        sorted(t, c);
        ++first_by[0][static_cast<std::size_t>(c[0]) + 1];
        ++first_by[1][static_cast<std::size_t>(c[1]) + 1];
    }
    for (int rank = 0; rank < 2; ++rank)
        for (std::size_t v = 0; v < nodes; ++v) first_by[rank][v + 1] += first_by[rank][v];
    {
        std::vector<std::uint32_t> fill0(first_by[0].begin(), first_by[0].end() - 1);
        std::vector<std::uint32_t> fill1(first_by[1].begin(), first_by[1].end() - 1);
        for (std::size_t t = 0; t < count; ++t) {
            std::int32_t c[4];
            sorted(t, c);
            tets_by[0][fill0[static_cast<std::size_t>(c[0])]++] = static_cast<std::uint32_t>(t);
            tets_by[1][fill1[static_cast<std::size_t>(c[1])]++] = static_cast<std::uint32_t>(t);
        }
    }
    // A face in its smallest corner's bucket: its other two corners as one
    // key, and its tetrahedron's index (below 2^31, as every reader's count
    // is) with in the top bit the parity of the permutation from the
    // tetrahedron's corners to (the face sorted, the corner it lacks): two
    // tetrahedra on opposite sides of a face give it opposite parities.
    struct Face {
        std::uint64_t key;
        std::uint32_t tet_and_side;
    };
    constexpr std::uint32_t kSide = 0x80000000u;
    std::vector<Face> bucket;
    // The faces of t without its sorted corners c[j], j in [from, to):
    // moving c[j] last passes 3 - j others.
    const auto add_faces = [&](std::uint32_t t, int from, int to) {
        std::int32_t c[4];
        const std::uint32_t odd = sorted(t, c);
        for (int j = from; j < to; ++j) {
            std::int32_t f[3];
            for (int k = 0, m = 0; k < 4; ++k)
                if (k != j) f[m++] = c[k];
            const std::uint32_t side = (odd ^ static_cast<std::uint32_t>(3 - j)) & 1u;
            bucket.push_back({static_cast<std::uint64_t>(f[1]) << 32 | static_cast<std::uint32_t>(f[2]), t | (side ? kSide : 0u)});
        }
    };
    const auto tet_of = [](const Face& face) { return static_cast<std::size_t>(face.tet_and_side & ~kSide); };
    FaceClash worst;
    const auto note = [&worst](FaceClash::Kind kind, std::size_t a, std::size_t b, std::size_t c) {
        ++worst.faces;
        if (worst.kind == FaceClash::Kind::none || std::make_pair(c, a) < std::make_pair(worst.third, worst.first))
            worst.kind = kind, worst.first = a, worst.second = b, worst.third = c;
    };
    // A bucket's faces are matched in a small open-addressing table of the
    // keys seen (a few dozen faces a bucket; a sort costs more), each slot
    // holding the first two faces of its key and how many have it; a slot
    // is in use for the bucket whose number it carries, so that the table
    // is never cleared.
    struct Slot {
        std::uint64_t key;
        std::uint32_t first, second, faces, bucket;
    };
    std::vector<Slot> table;
    std::vector<std::uint32_t> slot_of;
    for (std::size_t v = 0; v < nodes; ++v) {
        bucket.clear();
        for (std::uint32_t i = first_by[0][v]; i < first_by[0][v + 1]; ++i) add_faces(tets_by[0][i], 1, 4);
        for (std::uint32_t i = first_by[1][v]; i < first_by[1][v + 1]; ++i) add_faces(tets_by[1][i], 0, 1);
        const auto stamp = static_cast<std::uint32_t>(v + 1);
        if (table.size() < 2 * bucket.size()) {
            std::size_t size = std::max<std::size_t>(64, table.size());
            while (size < 2 * bucket.size()) size *= 2;
            table.assign(size, Slot{0, 0, 0, 0, 0});
        }
        const std::size_t mask = table.size() - 1;
        slot_of.resize(bucket.size());
        for (std::uint32_t i = 0; i < bucket.size(); ++i) {
            const std::uint64_t key = bucket[i].key;
            std::size_t at = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 40) & mask;
            while (table[at].bucket == stamp && table[at].key != key) at = (at + 1) & mask;
            Slot& slot = table[at];
            if (slot.bucket != stamp) slot = Slot{key, i, 0, 0, stamp};
            if (slot.faces == 1) slot.second = i;
            ++slot.faces;
            slot_of[i] = static_cast<std::uint32_t>(at);
        }
        for (std::uint32_t i = 0; i < bucket.size(); ++i) {
            const Slot& slot = table[slot_of[i]];
            if (slot.first != i) continue; // its key was met before
            const Face& face = bucket[i];
            const auto middle = static_cast<std::int32_t>(face.key >> 32), largest = static_cast<std::int32_t>(face.key & 0xffffffffu);
            if (slot.faces == 1) {
                boundary(static_cast<std::int32_t>(v), middle, largest, tet_of(face));
                continue;
            }
            // The corner of tetrahedron t that the face lacks.
            const auto apex = [&](std::size_t t) {
                std::int64_t sum = 0;
                for (int c = 0; c < 4; ++c) sum += tets[4 * t + static_cast<std::size_t>(c)];
                return sum - static_cast<std::int64_t>(v) - middle - largest;
            };
            if (slot.faces > 2) {
                std::vector<std::size_t> on_face;
                for (std::uint32_t k = i; k < bucket.size(); ++k)
                    if (bucket[k].key == face.key) on_face.push_back(tet_of(bucket[k]));
                std::sort(on_face.begin(), on_face.end());
                // A tetrahedron listed twice is named as such, not as a crowd.
                std::size_t a = 0, b = 0;
                for (std::size_t x = 0; x < on_face.size() && a == b; ++x)
                    for (std::size_t y = x + 1; y < on_face.size(); ++y)
                        if (apex(on_face[x]) == apex(on_face[y])) {
                            a = on_face[x], b = on_face[y];
                            break;
                        }
                if (a != b) note(FaceClash::Kind::repeated, a, b, b);
                else note(FaceClash::Kind::crowded, on_face[0], on_face[1], on_face[2]);
            } else if (((face.tet_and_side ^ bucket[slot.second].tet_and_side) & kSide) == 0) { // both on one side
                const std::size_t a = tet_of(face), b = tet_of(bucket[slot.second]);
                const bool repeated = apex(a) == apex(b);
                note(repeated ? FaceClash::Kind::repeated : FaceClash::Kind::folded, std::min(a, b), std::max(a, b), std::max(a, b));
            }
        }
    }
    return worst;
}

// How a reader names tetrahedron t in messages: "tetrahedron t", and the
// file's own number for it where that differs ("(cell 12)" in a .vtu with
// other cells, "(element 57)" in a .msh).
struct TetNames {
    const std::uint64_t* numbers = nullptr; // null: t itself
    std::size_t count = 0;                  // numbers there are
    const char* word = "cell";
    std::string operator()(std::size_t t) const;
};

// Six times the signed volume of tetrahedron (a, b, c, d), in double over
// position(v, axis): positive where d lies on the side of (a, b, c) that
// the right-hand rule points to.
template <class Position>
double volume6(Position position, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        const double origin = position(a, k);
        u[k] = position(b, k) - origin;
        v[k] = position(c, k) - origin;
        w[k] = position(d, k) - origin;
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

// Orients each tetrahedron of `tets` positively, two corners swapped where
// volume6(a, b, c, d), six times its signed volume, is negative; throws
// tetiso::Error naming `name` and the tetrahedron for one of zero volume.
// Returns which were listed in negative order (1) and which not (0).
template <class Volume6>
std::vector<std::uint8_t> orient_each(std::vector<std::int32_t>& tets, Volume6 volume6, const std::string& name,
                                      const TetNames& names) {
    std::vector<std::uint8_t> listed_negative(tets.size() / 4, 0);
    for (std::size_t t = 0; t < listed_negative.size(); ++t) {
        std::int32_t* v = tets.data() + 4 * t;
        const double volume = volume6(v[0], v[1], v[2], v[3]);
        if (volume == 0)
            throw Error(name + ": " + names(t) + " has zero volume (its corners, as stored in float, are coplanar)");
        if (volume < 0) std::swap(v[2], v[3]), listed_negative[t] = 1;
    }
    return listed_negative;
}

// Throws tetiso::Error naming `name` and the tetrahedra where `clash` is
// one: a tetrahedron listed twice, one inverted (against the orientation
// most of the mesh's tetrahedra are listed in, `listed_negative` from
// orient_each) or two that overlap, or several on one face.
void refuse_clash(const FaceClash& clash, const std::vector<std::uint8_t>& listed_negative, const std::string& name,
                  const TetNames& names);

} // namespace tetiso::detail
