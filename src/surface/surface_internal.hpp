// dsreg surface — machinery shared by the extraction (digital_surface.cpp) and the per-label
// views of a label complex (label_surface.cpp). Not part of the public API.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "../common/disjoint_sets.hpp"
#include "dsreg/digital_surface.hpp"

namespace dsreg::surface_detail {

using Pointel = std::array<std::int64_t, 3>;

/// Corners, faces and components number in the tens of millions: 32-bit sets.
using UnionFind = detail::DisjointSets<std::uint32_t>;

/// Corner offsets (along the two tangent axes b = axis+1, c = axis+2) listed counter-clockwise
/// seen from outside: e_b × e_c = e_axis, so (0,0),(1,0),(1,1),(0,1) turns positively around
/// +e_axis and must be reversed for a face whose normal is −e_axis.
constexpr int kCornerOffsets[2][4][2] = {
    {{0, 0}, {0, 1}, {1, 1}, {1, 0}},  // sign −1
    {{0, 0}, {1, 0}, {1, 1}, {0, 1}},  // sign +1
};

/// The 4 corner pointels of a surfel, counter-clockwise seen from outside its voxel (inline: the
/// complex's edges ask for them about nine times per face).
inline std::array<Pointel, 4> corner_pointels(const Surfel& s) {
    const int a = s.axis, b = (a + 1) % 3, c = (a + 2) % 3;
    const int side = s.sign > 0 ? 1 : 0;
    std::array<Pointel, 4> corners{};
    for (int k = 0; k < 4; ++k) {
        Pointel p{s.voxel[0], s.voxel[1], s.voxel[2]};
        p[a] += side;
        p[b] += kCornerOffsets[side][k][0];
        p[c] += kCornerOffsets[side][k][1];
        corners[k] = p;
    }
    return corners;
}

/// The edge m of a quad with corners `corners` whose end points are p and q, in either order,
/// or −1. Sets `same_direction` when corner m is p (the edge runs p → q).
inline int edge_between(const std::array<Pointel, 4>& corners, const Pointel& p, const Pointel& q, bool& same_direction) {
    for (int m = 0; m < 4; ++m) {
        const Pointel& a = corners[m];
        const Pointel& b = corners[(m + 1) % 4];
        if ((a == p && b == q) || (a == q && b == p)) {
            same_direction = a == p;
            return m;
        }
    }
    return -1;
}

/// Corner k of face f on side `side` (0: in the surface of its inner label, 1: of its outer
/// label), among the corners of a surface with `sides` sides per face (1 when every outer
/// label is the background, else 2): ids of "label corners", 4·sides per face.
inline std::uint32_t label_corner(std::int64_t f, int side, int k, int sides) {
    return static_cast<std::uint32_t>((f * sides + side) * 4 + k);
}

/// 2 if some face has a non-background outer label, else 1.
int label_sides(const DigitalSurface& surface);

/// Unites the label corners that a label's umbrella joins: across every edge e of face f that
/// the surface of the label on `side` glues to face g (adjacent_face, adjacent_face_outer), the
/// two corners of f on that edge with the corners of g at the same pointels. The classes are
/// the vertices of the labels' own surfaces (one per umbrella).
void unite_label_corners(const DigitalSurface& surface, int sides, UnionFind& corners);

}  // namespace dsreg::surface_detail
