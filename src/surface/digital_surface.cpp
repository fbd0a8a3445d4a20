#include "dsreg/digital_surface.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>

#include "dsreg/error.hpp"
#include "surface_internal.hpp"

namespace dsreg {

namespace surface_detail {

int label_sides(const DigitalSurface& surface) {
    for (const FaceLabels& l : surface.face_labels)
        if (l.outer != 0) return 2;
    return 1;
}

void unite_label_corners(const DigitalSurface& surface, int sides, UnionFind& corners) {
    const std::int64_t m = surface.face_count();
    for (std::int64_t f = 0; f < m; ++f) {
        const auto mine = corner_pointels(surface.surfels[std::size_t(f)]);
        for (int side = 0; side < sides; ++side) {
            const FaceMatrix& adjacent = side == 0 ? surface.adjacent_face : surface.adjacent_face_outer;
            const FaceLabels& labels = surface.face_labels[std::size_t(f)];
            const std::uint32_t label = side == 0 ? labels.inner : labels.outer;
            for (int e = 0; e < 4; ++e) {
                const std::int64_t g = adjacent(f, e);
                if (g < 0) continue;
                const int g_side = surface.face_labels[std::size_t(g)].inner == label ? 0 : 1;
                bool same = false;
                const int edge = edge_between(corner_pointels(surface.surfels[std::size_t(g)]), mine[e], mine[(e + 1) % 4], same);
                const int at_first = same ? edge : (edge + 1) % 4;  // corner of g at pointel mine[e]
                const int at_second = same ? (edge + 1) % 4 : edge;
                corners.unite(label_corner(f, side, e, sides), label_corner(g, g_side, at_first, sides));
                corners.unite(label_corner(f, side, (e + 1) % 4, sides), label_corner(g, g_side, at_second, sides));
            }
        }
    }
}

}  // namespace surface_detail

namespace {

using surface_detail::corner_pointels;
using surface_detail::label_corner;
using surface_detail::Pointel;
using surface_detail::UnionFind;

/// The label of a voxel, 0 outside the grid, for the two kinds of volumes: the extraction is
/// written once against these (a binary volume is the label map {0, 1}).
/// row(j, k): the voxels of row (j, k) from x = 0, or nullptr outside the grid; label_of(value)
/// the label of one of them.
struct MaskLabels {
    const BinaryVolume& volume;
    const VoxelGrid& grid() const { return volume.grid; }
    std::uint32_t operator()(const std::int64_t v[3]) const { return volume.inside(v[0], v[1], v[2]) ? 1u : 0u; }
    const std::uint8_t* row(std::int64_t j, std::int64_t k) const {
        return volume.grid.contains(0, j, k) ? volume.mask.data() + volume.grid.linear_index(0, j, k) : nullptr;
    }
    static std::uint32_t label_of(std::uint8_t value) { return value != 0 ? 1u : 0u; }
};

struct IndexLabels {
    const LabelVolume& volume;
    const VoxelGrid& grid() const { return volume.grid; }
    std::uint32_t operator()(const std::int64_t v[3]) const { return volume.label(v[0], v[1], v[2]); }
    const std::uint32_t* row(std::int64_t j, std::int64_t k) const {
        return volume.grid.contains(0, j, k) ? volume.labels.data() + volume.grid.linear_index(0, j, k) : nullptr;
    }
    static std::uint32_t label_of(std::uint32_t value) { return value; }
};

/// The in-plane axis direction that crosses edge e (corner e → corner e+1) of surfel s,
/// pointing away from the face: returns (axis, sign).
std::pair<int, int> edge_crossing_direction(const Surfel& s, int e) {
    const int a = s.axis, b = (a + 1) % 3, c = (a + 2) % 3;
    const int side = s.sign > 0 ? 1 : 0;
    const int* o0 = surface_detail::kCornerOffsets[side][e];
    const int* o1 = surface_detail::kCornerOffsets[side][(e + 1) % 4];
    if (o0[0] == o1[0]) return {b, o0[0] == 1 ? 1 : -1};
    return {c, o0[1] == 1 ? 1 : -1};
}

int direction_code(int axis, int sign) { return 2 * axis + (sign > 0 ? 1 : 0); }

/// Surfels sorted by key = 6·(voxel linear index) + direction code, with an index of the first
/// surfel of every voxel row for fast look-up, and the labels of each.
struct SurfelIndex {
    std::vector<Surfel> surfels;
    std::vector<FaceLabels> labels;
    std::vector<std::int64_t> keys;
    std::vector<std::int64_t> row_first;  ///< size ny·nz + 1
};

/// One pass over the voxels: every face between a voxel and a neighbour of a lower label (the
/// background outside the grid) is a surfel of the voxel.
template <class Labels>
SurfelIndex enumerate_surfels(const Labels& label) {
    const VoxelGrid& g = label.grid();
    const std::int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
    std::vector<std::vector<Surfel>> per_slice(static_cast<std::size_t>(nz));
    std::vector<std::vector<FaceLabels>> per_slice_labels(static_cast<std::size_t>(nz));
#pragma omp parallel for schedule(dynamic)
    for (std::int64_t k = 0; k < nz; ++k) {
        std::vector<Surfel>& out = per_slice[static_cast<std::size_t>(k)];
        std::vector<FaceLabels>& out_labels = per_slice_labels[static_cast<std::size_t>(k)];
        for (std::int64_t j = 0; j < ny; ++j) {
            // The row and its four neighbour rows (nullptr beyond the grid: background).
            const auto* here = label.row(j, k);
            const decltype(here) across[2][2] = {{label.row(j - 1, k), label.row(j + 1, k)},
                                                 {label.row(j, k - 1), label.row(j, k + 1)}};
            const auto at = [&](const decltype(here) row, std::int64_t i) {
                return row && i >= 0 && i < nx ? Labels::label_of(row[i]) : 0u;
            };
            for (std::int64_t i = 0; i < nx; ++i) {
                const std::uint32_t inner = Labels::label_of(here[i]);
                if (inner == 0) continue;
                for (int axis = 0; axis < 3; ++axis)
                    for (int sign : {-1, 1}) {
                        const std::uint32_t outer = axis == 0 ? at(here, i + sign) : at(across[axis - 1][sign > 0], i);
                        if (outer >= inner) continue;
                        out.push_back(Surfel{{std::int32_t(i), std::int32_t(j), std::int32_t(k)},
                                             std::int8_t(axis), std::int8_t(sign)});
                        out_labels.push_back(FaceLabels{inner, outer});
                    }
            }
        }
    }
    SurfelIndex index;
    std::size_t total = 0;
    for (const auto& s : per_slice) total += s.size();
    index.surfels.reserve(total);
    index.labels.reserve(total);
    for (std::size_t k = 0; k < per_slice.size(); ++k) {
        index.surfels.insert(index.surfels.end(), per_slice[k].begin(), per_slice[k].end());
        index.labels.insert(index.labels.end(), per_slice_labels[k].begin(), per_slice_labels[k].end());
        std::vector<Surfel>().swap(per_slice[k]);
        std::vector<FaceLabels>().swap(per_slice_labels[k]);
    }
    index.keys.resize(total);
    index.row_first.assign(static_cast<std::size_t>(ny * nz + 1), 0);
    for (std::size_t f = 0; f < total; ++f) {
        const Surfel& s = index.surfels[f];
        index.keys[f] = 6 * g.linear_index(s.voxel[0], s.voxel[1], s.voxel[2]) + direction_code(s.axis, s.sign);
        ++index.row_first[static_cast<std::size_t>(s.voxel[1] + ny * s.voxel[2] + 1)];
    }
    std::partial_sum(index.row_first.begin(), index.row_first.end(), index.row_first.begin());
    return index;
}

std::int64_t find_surfel(const SurfelIndex& index, const VoxelGrid& g, const std::int64_t v[3], int axis, int sign) {
    const std::int64_t key = 6 * g.linear_index(v[0], v[1], v[2]) + direction_code(axis, sign);
    const std::int64_t row = v[1] + g.dims[1] * v[2];
    const auto first = index.keys.begin() + index.row_first[static_cast<std::size_t>(row)];
    const auto last = index.keys.begin() + index.row_first[static_cast<std::size_t>(row + 1)];
    const auto it = std::lower_bound(first, last, key);
    if (it == last || *it != key) return -1;
    return it - index.keys.begin();
}

/// The face between voxel v and its neighbour along (axis, sign), two voxels of different
/// labels: the surfel of the higher label.
template <class Labels>
std::int64_t find_face_between(const Labels& label, const SurfelIndex& index, const std::int64_t v[3], int axis, int sign) {
    std::int64_t w[3] = {v[0], v[1], v[2]};
    w[axis] += sign;
    if (label(v) > label(w)) return find_surfel(index, label.grid(), v, axis, sign);
    if (!label.grid().contains(w[0], w[1], w[2])) return -1;
    return find_surfel(index, label.grid(), w, axis, -sign);
}

/// The face across edge e of surfel s in the surface of the label on `side` of it (0: inner,
/// the voxel of s; 1: outer, the voxel across). With v that label's voxel, n its outward normal
/// and t the crossing direction, the candidates are the concave turn (voxel v+t+n, normal −t),
/// the flat continuation (voxel v+t, normal n) and the convex turn (voxel v, normal t). Where v
/// and v+t+n touch only along this edge (v+t of another label), 26-connectivity joins them
/// (concave) and 6-connectivity keeps them apart (convex). Both rules are symmetric, so faces
/// pair up consistently within each label's surface. `four_surfels` tells whether the linel has
/// four surfels of that label's surface (v and v+t+n touch only along it).
template <class Labels>
std::int64_t neighbor_across_edge(const Labels& label, const SurfelIndex& index, const Surfel& s, int side, int e,
                                  Connectivity connectivity, bool& four_surfels) {
    const auto [t_axis, t_sign] = edge_crossing_direction(s, e);
    std::int64_t v[3] = {s.voxel[0], s.voxel[1], s.voxel[2]};
    int n_sign = s.sign;
    if (side == 1) {
        v[s.axis] += s.sign;
        n_sign = -s.sign;
    }
    const std::uint32_t own = label(v);
    std::int64_t flat[3] = {v[0], v[1], v[2]};
    flat[t_axis] += t_sign;
    std::int64_t diagonal[3] = {flat[0], flat[1], flat[2]};
    diagonal[s.axis] += n_sign;
    const bool flat_inside = label(flat) == own;
    const bool diagonal_inside = label(diagonal) == own;
    four_surfels = diagonal_inside && !flat_inside;
    const bool concave = diagonal_inside && (flat_inside || connectivity == Connectivity::TwentySix);
    if (concave) return find_face_between(label, index, diagonal, t_axis, -t_sign);
    if (flat_inside) return find_face_between(label, index, flat, s.axis, n_sign);
    return find_face_between(label, index, v, t_axis, t_sign);
}

/// Fills the adjacency of the surface of the label on `side` of every face (−1 for a
/// background side). `four_surfel_edges` gets, per face, bit e set when its edge e lies on a
/// linel of four surfels of that surface.
template <class Labels>
void pair_face_edges(const Labels& label, const SurfelIndex& index, Connectivity connectivity, int side,
                     FaceMatrix& adjacent, std::vector<std::uint8_t>& four_surfel_edges) {
    const std::int64_t m = static_cast<std::int64_t>(index.surfels.size());
    adjacent.resize(m, 4);
    four_surfel_edges.assign(static_cast<std::size_t>(m), 0);
    bool inconsistent = false;
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        const Surfel& s = index.surfels[static_cast<std::size_t>(f)];
        if (side == 1 && index.labels[std::size_t(f)].outer == 0) {
            adjacent.row(f).setConstant(-1);
            continue;
        }
        const auto corners = corner_pointels(s);
        for (int e = 0; e < 4; ++e) {
            bool four_surfels = false;
            const std::int64_t g = neighbor_across_edge(label, index, s, side, e, connectivity, four_surfels);
            bool same = false;
            const int edge = g < 0 ? -1
                                   : surface_detail::edge_between(corner_pointels(index.surfels[static_cast<std::size_t>(g)]),
                                                                  corners[e], corners[(e + 1) % 4], same);
            if (edge < 0 || g == f) {
                inconsistent = true;  // benign race: only ever set to true
                continue;
            }
            adjacent(f, e) = static_cast<std::int32_t>(g);
            if (four_surfels) four_surfel_edges[static_cast<std::size_t>(f)] |= std::uint8_t(1u << e);
        }
    }
    if (inconsistent) throw Error("internal error: digital surface edge pairing is inconsistent");
}

/// Groups face corners into vertices: the corners that some label's umbrella joins (across
/// every glued edge, the corners at the same pointel), and the two sides of each face corner.
void build_vertices(DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    const int sides = surface_detail::label_sides(surface);
    UnionFind corners(static_cast<std::size_t>(4 * sides * m));
    surface_detail::unite_label_corners(surface, sides, corners);
    if (sides == 2)
        for (std::int64_t f = 0; f < m; ++f)
            if (surface.face_labels[std::size_t(f)].outer != 0)
                for (int k = 0; k < 4; ++k) corners.unite(label_corner(f, 0, k, sides), label_corner(f, 1, k, sides));
    std::vector<std::int32_t> vertex_of_root(corners.size(), -1);
    std::vector<std::int64_t> first_corner;
    for (std::int64_t c = 0; c < 4 * m; ++c) {
        const std::uint32_t root = corners.find(label_corner(c / 4, 0, int(c % 4), sides));
        std::int32_t& id = vertex_of_root[root];
        if (id < 0) {
            id = static_cast<std::int32_t>(first_corner.size());
            first_corner.push_back(c);
        }
        surface.quads(c / 4, c % 4) = id;
    }
    const std::int64_t n = static_cast<std::int64_t>(first_corner.size());
    surface.vertices.resize(n, 3);
    surface.vertex_pointels.resize(n, 3);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t c = first_corner[static_cast<std::size_t>(i)];
        const Pointel p = corner_pointels(surface.surfels[static_cast<std::size_t>(c / 4)])[c % 4];
        surface.vertices.row(i) = surface.grid.pointel_position(p[0], p[1], p[2]).transpose();
        for (int d = 0; d < 3; ++d) surface.vertex_pointels(i, d) = static_cast<std::int32_t>(p[d]);
    }
}

/// Edge of face g glued to edge e of face f (the edge of g between the same two pointels).
int matching_edge(const DigitalSurface& surface, std::int64_t f, int e, std::int64_t g) {
    const auto corners = corner_pointels(surface.surfels[static_cast<std::size_t>(f)]);
    bool same = false;
    return surface_detail::edge_between(corner_pointels(surface.surfels[static_cast<std::size_t>(g)]), corners[e],
                                        corners[(e + 1) % 4], same);
}

/// A linel of four surfels of one label's surface, f1, f2, f3, f4 (f1 and f3 run along it in
/// the same direction, f2 and f4 the other way), is glued f1–f2, f3–f4 or f1–f4, f3–f2. If both
/// its end pointels come out with a single vertex of that label's surface, its two glued edges
/// join the same two vertices: the surface is pinched along the linel, and no mesh with straight
/// edges can separate the two sheets there (e.g. two voxels touching by one edge, joined by
/// 26-connectivity). The other gluing splits both end vertices in two (around each end pointel
/// the umbrella through the linel twice becomes two umbrellas), which the regularization can
/// pull apart. Re-glues such linels, at most one per vertex per call (two re-gluings at one
/// pointel could merge its umbrellas again); returns how many. `four_surfel_edges[side]` marks
/// the edges on linels of four surfels in the surface of the label on that side of each face.
/// The vertices must be rebuilt afterwards.
std::int64_t reglue_pinched_linels(DigitalSurface& surface, const std::vector<std::uint8_t> four_surfel_edges[2]) {
    const std::int64_t m = surface.face_count();
    const int sides = surface_detail::label_sides(surface);
    UnionFind corners(static_cast<std::size_t>(4 * sides * m));
    surface_detail::unite_label_corners(surface, sides, corners);  // classes: the labels' own vertices
    struct FaceEdge {
        std::uint32_t from, to;  // the label's own vertices, in the label's orientation
        std::int64_t face;
        int side, edge;
        bool operator<(const FaceEdge& o) const {
            return std::tie(from, to, face, side) < std::tie(o.from, o.to, o.face, o.side);
        }
    };
    std::vector<FaceEdge> edges;
    for (int side = 0; side < sides; ++side)
        for (std::int64_t f = 0; f < m; ++f)
            for (int e = 0; e < 4; ++e)
                if (four_surfel_edges[side][static_cast<std::size_t>(f)] & (1u << e)) {
                    const std::uint32_t first = corners.find(label_corner(f, side, e, sides));
                    const std::uint32_t second = corners.find(label_corner(f, side, (e + 1) % 4, sides));
                    // the outer side sees the face from behind: its edges run the other way
                    edges.push_back(side == 0 ? FaceEdge{first, second, f, side, e} : FaceEdge{second, first, f, side, e});
                }
    std::sort(edges.begin(), edges.end());
    const auto adjacency = [&](int side) -> FaceMatrix& {
        return side == 0 ? surface.adjacent_face : surface.adjacent_face_outer;
    };
    const auto side_of = [&](std::int64_t face, std::uint32_t label) {
        return surface.face_labels[static_cast<std::size_t>(face)].inner == label ? 0 : 1;
    };
    std::vector<std::uint32_t> touched;
    std::int64_t reglued = 0;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
        const FaceEdge &one = edges[i], &three = edges[i + 1];
        if (one.from != three.from || one.to != three.to) continue;
        if (std::find(touched.begin(), touched.end(), one.from) != touched.end() ||
            std::find(touched.begin(), touched.end(), one.to) != touched.end())
            continue;
        touched.push_back(one.from);
        touched.push_back(one.to);
        const FaceLabels& labels = surface.face_labels[static_cast<std::size_t>(one.face)];
        const std::uint32_t label = one.side == 0 ? labels.inner : labels.outer;
        const std::int64_t two = adjacency(one.side)(one.face, one.edge);
        const std::int64_t four = adjacency(three.side)(three.face, three.edge);
        const int two_edge = matching_edge(surface, one.face, one.edge, two);
        const int four_edge = matching_edge(surface, three.face, three.edge, four);
        adjacency(one.side)(one.face, one.edge) = static_cast<std::int32_t>(four);
        adjacency(side_of(four, label))(four, four_edge) = static_cast<std::int32_t>(one.face);
        adjacency(three.side)(three.face, three.edge) = static_cast<std::int32_t>(two);
        adjacency(side_of(two, label))(two, two_edge) = static_cast<std::int32_t>(three.face);
        ++reglued;
        ++i;
    }
    return reglued;
}

}  // namespace

std::array<std::int64_t, 3> surfel_corner_pointel(const Surfel& s, int corner) {
    return corner_pointels(s)[std::size_t(corner)];
}

/// Connected components of the complex: faces glued in any label's surface.
void label_components(DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    UnionFind faces(static_cast<std::size_t>(m));
    for (std::int64_t f = 0; f < m; ++f)
        for (int e = 0; e < 4; ++e) {
            faces.unite(std::uint32_t(f), std::uint32_t(surface.adjacent_face(f, e)));
            if (surface.adjacent_face_outer.rows() == m && surface.adjacent_face_outer(f, e) >= 0)
                faces.unite(std::uint32_t(f), std::uint32_t(surface.adjacent_face_outer(f, e)));
        }
    surface.face_component.assign(static_cast<std::size_t>(m), -1);
    std::vector<std::int32_t> label_of_root(static_cast<std::size_t>(m), -1);
    std::int32_t count = 0;
    for (std::int64_t f = 0; f < m; ++f) {
        std::int32_t& label = label_of_root[faces.find(std::uint32_t(f))];
        if (label < 0) label = count++;
        surface.face_component[static_cast<std::size_t>(f)] = label;
    }
    surface.component_count = count;
}

std::int64_t count_split_pointels(const DigitalSurface& surface) {
    const VoxelGrid& g = surface.grid;
    std::vector<std::int64_t> keys(static_cast<std::size_t>(surface.vertex_count()));
    for (std::int64_t i = 0; i < surface.vertex_count(); ++i)
        keys[static_cast<std::size_t>(i)] =
            surface.vertex_pointels(i, 0) +
            (g.dims[0] + 1) * (surface.vertex_pointels(i, 1) + (g.dims[1] + 1) * std::int64_t(surface.vertex_pointels(i, 2)));
    std::sort(keys.begin(), keys.end());
    std::int64_t split = 0;
    for (std::size_t i = 1; i < keys.size(); ++i)
        if (keys[i] == keys[i - 1] && (i == 1 || keys[i - 1] != keys[i - 2])) ++split;
    return split;
}

namespace {

void check_grid(const VoxelGrid& g, std::size_t voxel_values) {
    if (g.dims[0] <= 0 || g.dims[1] <= 0 || g.dims[2] <= 0 || static_cast<std::int64_t>(voxel_values) != g.voxel_count())
        throw Error("invalid volume: dimensions do not match the voxel data");
    if (g.dims[0] >= INT32_MAX || g.dims[1] >= INT32_MAX || g.dims[2] >= INT32_MAX)
        throw Error("invalid volume: a dimension exceeds 2^31 - 2 voxels");
}

template <class Labels>
DigitalSurface extract(const Labels& label, Connectivity connectivity, std::vector<std::int64_t> label_values) {
    SurfelIndex index = enumerate_surfels(label);
    if (index.surfels.empty()) throw Error("the object is empty: no voxel has a value in the selected range");
    bool two_sided = false;
    for (const FaceLabels& l : index.labels) two_sided = two_sided || l.outer != 0;
    const std::size_t limit = std::size_t(1) << (two_sided ? 29 : 30);  // 4 (8) corner ids per face in 32 bits
    if (index.surfels.size() >= limit)
        throw Error("the surface has " + std::to_string(index.surfels.size()) + " surfels; at most 2^" +
                    (two_sided ? "29 are supported between labels" : "30 are supported"));

    DigitalSurface surface;
    surface.grid = label.grid();
    surface.label_values = std::move(label_values);
    std::vector<std::uint8_t> four_surfel_edges[2];
    pair_face_edges(label, index, connectivity, 0, surface.adjacent_face, four_surfel_edges[0]);
    pair_face_edges(label, index, connectivity, 1, surface.adjacent_face_outer, four_surfel_edges[1]);
    surface.surfels = std::move(index.surfels);
    surface.face_labels = std::move(index.labels);
    index = SurfelIndex();
    surface.quads.resize(std::int64_t(surface.surfels.size()), 4);
    build_vertices(surface);
    // Each re-gluing splits two vertices of a label's own surface, so the rounds are few (one
    // per pinched linel sharing a vertex with another); the bound only guards against a bug.
    for (int round = 0; reglue_pinched_linels(surface, four_surfel_edges) > 0; ++round) {
        if (round == 1000) throw Error("internal error: pinched linels keep coming back");
        build_vertices(surface);
    }
    label_components(surface);
    surface.split_pointel_count = count_split_pointels(surface);
    return surface;
}

}  // namespace

DigitalSurface extract_digital_surface(const BinaryVolume& volume, Connectivity connectivity) {
    check_grid(volume.grid, volume.mask.size());
    return extract(MaskLabels{volume}, connectivity, {0, 1});
}

DigitalSurface extract_digital_surface(const LabelVolume& volume, Connectivity connectivity) {
    check_grid(volume.grid, volume.labels.size());
    if (volume.values.empty()) throw Error("invalid label map: no label table");
    for (const std::uint32_t l : volume.labels)
        if (l >= volume.values.size()) throw Error("invalid label map: a voxel has a label index beyond the label table");
    return extract(IndexLabels{volume}, connectivity, volume.values);
}

PointMatrix surfel_centers(const DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    PointMatrix centers(m, 3);
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        const Surfel& s = surface.surfels[static_cast<std::size_t>(f)];
        Eigen::Vector3d c = surface.grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        c[s.axis] += 0.5 * s.sign * surface.grid.spacing[s.axis];
        centers.row(f) = c.transpose();
    }
    return centers;
}

std::vector<std::int64_t> component_euler_characteristics(const DigitalSurface& surface) {
    std::vector<std::int64_t> faces(static_cast<std::size_t>(surface.component_count), 0);
    std::vector<std::int64_t> vertices(faces.size(), 0);
    std::vector<char> seen(static_cast<std::size_t>(surface.vertex_count()), 0);
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const std::size_t c = static_cast<std::size_t>(surface.face_component[static_cast<std::size_t>(f)]);
        ++faces[c];
        for (int k = 0; k < 4; ++k) {
            char& s = seen[static_cast<std::size_t>(surface.quads(f, k))];
            if (!s) ++vertices[c];
            s = 1;
        }
    }
    std::vector<std::int64_t> chi(faces.size());
    for (std::size_t c = 0; c < faces.size(); ++c) chi[c] = vertices[c] - 2 * faces[c] + faces[c];  // E = 4F/2
    return chi;
}

namespace {

/// Compressed rows over the vertices of `faces`: row i lists value(f, e) for each corner e of a
/// face f at vertex i, in increasing f (a counting sort of the corners by vertex).
template <class Value>
void rows_of_corners(const FaceMatrix& faces, std::int64_t vertex_count, std::vector<std::int64_t>& offsets,
                     std::vector<std::int32_t>& values, Value value) {
    const std::int64_t k = faces.cols();
    offsets.assign(static_cast<std::size_t>(vertex_count + 1), 0);
    for (std::int64_t f = 0; f < faces.rows(); ++f)
        for (std::int64_t e = 0; e < k; ++e) ++offsets[static_cast<std::size_t>(faces(f, e) + 1)];
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    values.resize(static_cast<std::size_t>(offsets.back()));
    std::vector<std::int64_t> cursor(offsets.begin(), offsets.end() - 1);
    for (std::int64_t f = 0; f < faces.rows(); ++f)
        for (std::int64_t e = 0; e < k; ++e) values[static_cast<std::size_t>(cursor[static_cast<std::size_t>(faces(f, e))]++)] = value(f, e);
}

}  // namespace

VertexLinks vertex_links(const FaceMatrix& faces, std::int64_t vertex_count) {
    VertexLinks links;
    const std::int64_t k = faces.cols();
    rows_of_corners(faces, vertex_count, links.offsets, links.neighbors,
                    [&](std::int64_t f, std::int64_t e) { return faces(f, (e + 1) % k); });
    return links;
}

VertexCorners vertex_corners(const FaceMatrix& faces, std::int64_t vertex_count) {
    const std::int64_t k = faces.cols();
    if (faces.rows() * k > std::int64_t(std::numeric_limits<std::int32_t>::max()))
        throw Error("too many faces for 32-bit corner codes (" + std::to_string(faces.rows()) + ")");
    VertexCorners corners;
    corners.face_size = std::int32_t(k);
    rows_of_corners(faces, vertex_count, corners.offsets, corners.codes,
                    [&](std::int64_t f, std::int64_t e) { return std::int32_t(f * k + e); });
    return corners;
}

}  // namespace dsreg
