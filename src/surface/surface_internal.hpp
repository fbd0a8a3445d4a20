// dsreg surface — machinery shared by the extraction (digital_surface.cpp) and the per-label
// views of a label complex (label_surface.cpp). Not part of the public API.
#pragma once

#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

#include "dsreg/digital_surface.hpp"

namespace dsreg::surface_detail {

using Pointel = std::array<std::int64_t, 3>;

/// Disjoint sets with path halving; the smallest index of a set is its root, whatever the order
/// of the unions (so results never depend on it).
class UnionFind {
public:
    explicit UnionFind(std::size_t size) : parent_(size) { std::iota(parent_.begin(), parent_.end(), 0u); }
    std::uint32_t find(std::uint32_t x) {
        while (parent_[x] != x) {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b) std::swap(a, b);
        parent_[a] = b;  // the smaller index stays root
    }
    std::size_t size() const { return parent_.size(); }

private:
    std::vector<std::uint32_t> parent_;
};

/// The 4 corner pointels of a surfel, counter-clockwise seen from outside its voxel.
std::array<Pointel, 4> corner_pointels(const Surfel& s);

/// The edge m of a quad with corners `corners` whose end points are p and q, in either order,
/// or −1. Sets `same_direction` when corner m is p (the edge runs p → q).
int edge_between(const std::array<Pointel, 4>& corners, const Pointel& p, const Pointel& q, bool& same_direction);

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
