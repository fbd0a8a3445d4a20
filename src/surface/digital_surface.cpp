#include "dsreg/digital_surface.hpp"

#include <algorithm>
#include <numeric>
#include <string>
#include <tuple>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

using Pointel = std::array<std::int64_t, 3>;

/// Disjoint sets with path halving and union by index (deterministic roots).
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

private:
    std::vector<std::uint32_t> parent_;
};

/// Corner offsets (along the two tangent axes b = axis+1, c = axis+2) listed counter-clockwise
/// seen from outside: e_b × e_c = e_axis, so (0,0),(1,0),(1,1),(0,1) turns positively around
/// +e_axis and must be reversed for a face whose normal is −e_axis.
constexpr int kCornerOffsets[2][4][2] = {
    {{0, 0}, {0, 1}, {1, 1}, {1, 0}},  // sign −1
    {{0, 0}, {1, 0}, {1, 1}, {0, 1}},  // sign +1
};

std::array<Pointel, 4> corner_pointels(const Surfel& s) {
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

/// The in-plane axis direction that crosses edge e (corner e → corner e+1) of surfel s,
/// pointing away from the face: returns (axis, sign).
std::pair<int, int> edge_crossing_direction(const Surfel& s, int e) {
    const int a = s.axis, b = (a + 1) % 3, c = (a + 2) % 3;
    const int side = s.sign > 0 ? 1 : 0;
    const int* o0 = kCornerOffsets[side][e];
    const int* o1 = kCornerOffsets[side][(e + 1) % 4];
    if (o0[0] == o1[0]) return {b, o0[0] == 1 ? 1 : -1};
    return {c, o0[1] == 1 ? 1 : -1};
}

int direction_code(int axis, int sign) { return 2 * axis + (sign > 0 ? 1 : 0); }

/// Surfels sorted by key = 6·(voxel linear index) + direction code, with an index of the first
/// surfel of every voxel row for fast look-up.
struct SurfelIndex {
    std::vector<Surfel> surfels;
    std::vector<std::int64_t> keys;
    std::vector<std::int64_t> row_first;  ///< size ny·nz + 1
};

SurfelIndex enumerate_surfels(const BinaryVolume& volume) {
    const VoxelGrid& g = volume.grid;
    const std::int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
    std::vector<std::vector<Surfel>> per_slice(static_cast<std::size_t>(nz));
#pragma omp parallel for schedule(dynamic)
    for (std::int64_t k = 0; k < nz; ++k) {
        std::vector<Surfel>& out = per_slice[static_cast<std::size_t>(k)];
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                if (!volume.inside(i, j, k)) continue;
                const std::int64_t v[3] = {i, j, k};
                for (int axis = 0; axis < 3; ++axis)
                    for (int sign : {-1, 1}) {
                        std::int64_t w[3] = {v[0], v[1], v[2]};
                        w[axis] += sign;
                        if (volume.inside(w[0], w[1], w[2])) continue;
                        out.push_back(Surfel{{std::int32_t(i), std::int32_t(j), std::int32_t(k)},
                                             std::int8_t(axis), std::int8_t(sign)});
                    }
            }
    }
    SurfelIndex index;
    std::size_t total = 0;
    for (const auto& s : per_slice) total += s.size();
    index.surfels.reserve(total);
    for (auto& s : per_slice) {
        index.surfels.insert(index.surfels.end(), s.begin(), s.end());
        std::vector<Surfel>().swap(s);
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

/// The surfel across edge e of surfel s: with n the outward normal and t the crossing direction,
/// the candidates are the concave turn (voxel v+t+n, normal −t), the flat continuation (voxel v+t,
/// normal n) and the convex turn (voxel v, normal t). Where v and v+t+n touch only along this
/// edge (v+t is background), 26-connectivity joins them (concave) and 6-connectivity keeps
/// them apart (convex). Both rules are symmetric, so faces pair up consistently.
/// `four_surfels` tells whether the linel has four surfels (v and v+t+n touch only along it).
std::int64_t neighbor_across_edge(const BinaryVolume& volume, const SurfelIndex& index, const Surfel& s, int e,
                                  Connectivity connectivity, bool& four_surfels) {
    const auto [t_axis, t_sign] = edge_crossing_direction(s, e);
    const std::int64_t v[3] = {s.voxel[0], s.voxel[1], s.voxel[2]};
    std::int64_t flat[3] = {v[0], v[1], v[2]};
    flat[t_axis] += t_sign;
    std::int64_t diagonal[3] = {flat[0], flat[1], flat[2]};
    diagonal[s.axis] += s.sign;
    const bool flat_inside = volume.inside(flat[0], flat[1], flat[2]);
    const bool diagonal_inside = volume.inside(diagonal[0], diagonal[1], diagonal[2]);
    four_surfels = diagonal_inside && !flat_inside;
    const bool concave = diagonal_inside && (flat_inside || connectivity == Connectivity::TwentySix);
    if (concave) return find_surfel(index, volume.grid, diagonal, t_axis, -t_sign);
    if (flat_inside) return find_surfel(index, volume.grid, flat, s.axis, s.sign);
    return find_surfel(index, volume.grid, v, t_axis, t_sign);
}

/// Index of the edge of `corners` that runs from `from` to `to`, or −1.
int edge_joining(const std::array<Pointel, 4>& corners, const Pointel& from, const Pointel& to) {
    for (int m = 0; m < 4; ++m)
        if (corners[m] == from && corners[(m + 1) % 4] == to) return m;
    return -1;
}

/// Fills adjacent_face and returns, per face edge, the matching edge index in the adjacent face.
/// `four_surfel_edges` gets, per face, bit e set when its edge e lies on a linel of four surfels.
std::vector<std::int8_t> pair_face_edges(const BinaryVolume& volume, const SurfelIndex& index, Connectivity connectivity,
                                         FaceMatrix& adjacent_face, std::vector<std::uint8_t>& four_surfel_edges) {
    const std::int64_t m = static_cast<std::int64_t>(index.surfels.size());
    adjacent_face.resize(m, 4);
    std::vector<std::int8_t> adjacent_edge(static_cast<std::size_t>(4 * m));
    four_surfel_edges.assign(static_cast<std::size_t>(m), 0);
    bool inconsistent = false;
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        const Surfel& s = index.surfels[static_cast<std::size_t>(f)];
        const auto corners = corner_pointels(s);
        for (int e = 0; e < 4; ++e) {
            bool four_surfels = false;
            const std::int64_t g = neighbor_across_edge(volume, index, s, e, connectivity, four_surfels);
            const int edge = g < 0 ? -1 : edge_joining(corner_pointels(index.surfels[static_cast<std::size_t>(g)]),
                                                       corners[(e + 1) % 4], corners[e]);
            if (edge < 0) {
                inconsistent = true;  // benign race: only ever set to true
                continue;
            }
            adjacent_face(f, e) = static_cast<std::int32_t>(g);
            adjacent_edge[static_cast<std::size_t>(4 * f + e)] = static_cast<std::int8_t>(edge);
            if (four_surfels) four_surfel_edges[static_cast<std::size_t>(f)] |= std::uint8_t(1u << e);
        }
    }
    if (inconsistent) throw Error("internal error: digital surface edge pairing is inconsistent");
    return adjacent_edge;
}

/// Groups face corners into umbrellas (one vertex each): across every glued edge, the corners
/// at the same pointel belong to the same umbrella.
void build_vertices(DigitalSurface& surface, const std::vector<std::int8_t>& adjacent_edge) {
    const std::int64_t m = static_cast<std::int64_t>(surface.surfels.size());
    UnionFind corners(static_cast<std::size_t>(4 * m));
    for (std::int64_t f = 0; f < m; ++f)
        for (int e = 0; e < 4; ++e) {
            const std::int64_t g = surface.adjacent_face(f, e);
            if (g < f) continue;  // each edge once
            const int edge = adjacent_edge[static_cast<std::size_t>(4 * f + e)];
            corners.unite(std::uint32_t(4 * f + e), std::uint32_t(4 * g + (edge + 1) % 4));
            corners.unite(std::uint32_t(4 * f + (e + 1) % 4), std::uint32_t(4 * g + edge));
        }
    std::vector<std::int32_t> vertex_of_root(static_cast<std::size_t>(4 * m), -1);
    std::vector<std::int64_t> first_corner;
    surface.quads.resize(m, 4);
    for (std::int64_t c = 0; c < 4 * m; ++c) {
        const std::uint32_t root = corners.find(std::uint32_t(c));
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

/// Glues edge e of face f to edge h of face g (both ways).
void glue(DigitalSurface& surface, std::vector<std::int8_t>& adjacent_edge, std::int32_t f, int e, std::int32_t g, int h) {
    surface.adjacent_face(f, e) = g;
    surface.adjacent_face(g, h) = f;
    adjacent_edge[static_cast<std::size_t>(4 * f + e)] = static_cast<std::int8_t>(h);
    adjacent_edge[static_cast<std::size_t>(4 * g + h)] = static_cast<std::int8_t>(e);
}

/// A linel of four surfels f1, f2, f3, f4 (f1 and f3 run along it in the same direction, f2 and
/// f4 the other way) is glued f1–f2, f3–f4 or f1–f4, f3–f2. If both its end pointels come out
/// with a single vertex, its two glued edges join the same two vertices: the surface is pinched
/// along the linel, and no mesh with straight edges can separate the two sheets there (e.g. two
/// voxels touching by one edge, joined by 26-connectivity). The other gluing splits both end
/// vertices in two (around each end pointel the umbrella through the linel twice becomes two
/// umbrellas), which the regularization can pull apart. Re-glues such linels, at most one per
/// vertex per call (two re-gluings at one pointel could merge its umbrellas again); returns how
/// many. The vertices must be rebuilt afterwards.
std::int64_t reglue_pinched_linels(DigitalSurface& surface, std::vector<std::int8_t>& adjacent_edge,
                                   const std::vector<std::uint8_t>& four_surfel_edges) {
    struct FaceEdge {
        std::int32_t from, to, face;
        int edge;
        bool operator<(const FaceEdge& o) const { return std::tie(from, to, face) < std::tie(o.from, o.to, o.face); }
    };
    std::vector<FaceEdge> edges;
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        for (int e = 0; e < 4; ++e)
            if (four_surfel_edges[static_cast<std::size_t>(f)] & (1u << e))
                edges.push_back({surface.quads(f, e), surface.quads(f, (e + 1) % 4), std::int32_t(f), e});
    std::sort(edges.begin(), edges.end());
    std::vector<std::int32_t> touched;
    std::int64_t reglued = 0;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
        const FaceEdge &one = edges[i], &three = edges[i + 1];
        if (one.from != three.from || one.to != three.to) continue;
        if (std::find(touched.begin(), touched.end(), one.from) != touched.end() ||
            std::find(touched.begin(), touched.end(), one.to) != touched.end())
            continue;
        touched.push_back(one.from);
        touched.push_back(one.to);
        const std::int32_t two = surface.adjacent_face(one.face, one.edge), four = surface.adjacent_face(three.face, three.edge);
        const int two_edge = adjacent_edge[static_cast<std::size_t>(4 * one.face + one.edge)];
        const int four_edge = adjacent_edge[static_cast<std::size_t>(4 * three.face + three.edge)];
        glue(surface, adjacent_edge, one.face, one.edge, four, four_edge);
        glue(surface, adjacent_edge, three.face, three.edge, two, two_edge);
        ++reglued;
        ++i;
    }
    return reglued;
}

void label_components(DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    UnionFind faces(static_cast<std::size_t>(m));
    for (std::int64_t f = 0; f < m; ++f)
        for (int e = 0; e < 4; ++e) faces.unite(std::uint32_t(f), std::uint32_t(surface.adjacent_face(f, e)));
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

}  // namespace

DigitalSurface extract_digital_surface(const BinaryVolume& volume, Connectivity connectivity) {
    const VoxelGrid& g = volume.grid;
    if (g.dims[0] <= 0 || g.dims[1] <= 0 || g.dims[2] <= 0 ||
        static_cast<std::int64_t>(volume.mask.size()) != g.voxel_count())
        throw Error("invalid volume: dimensions do not match the voxel data");
    if (g.dims[0] >= INT32_MAX || g.dims[1] >= INT32_MAX || g.dims[2] >= INT32_MAX)
        throw Error("invalid volume: a dimension exceeds 2^31 - 2 voxels");

    SurfelIndex index = enumerate_surfels(volume);
    if (index.surfels.empty()) throw Error("the object is empty: no voxel has a value in the selected range");
    if (index.surfels.size() >= (std::size_t(1) << 30))
        throw Error("the surface has " + std::to_string(index.surfels.size()) + " surfels; at most 2^30 are supported");

    DigitalSurface surface;
    surface.grid = g;
    std::vector<std::uint8_t> four_surfel_edges;
    std::vector<std::int8_t> adjacent_edge =
        pair_face_edges(volume, index, connectivity, surface.adjacent_face, four_surfel_edges);
    surface.surfels = std::move(index.surfels);
    index = SurfelIndex();
    build_vertices(surface, adjacent_edge);
    while (reglue_pinched_linels(surface, adjacent_edge, four_surfel_edges) > 0) {
        const std::int64_t before = surface.vertex_count();
        build_vertices(surface, adjacent_edge);
        if (surface.vertex_count() <= before) throw Error("internal error: re-gluing a pinched linel split no vertex");
    }
    label_components(surface);
    surface.split_pointel_count = count_split_pointels(surface);
    return surface;
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

VertexLinks vertex_links(const FaceMatrix& faces, std::int64_t vertex_count) {
    VertexLinks links;
    links.offsets.assign(static_cast<std::size_t>(vertex_count + 1), 0);
    const std::int64_t k = faces.cols();
    for (std::int64_t f = 0; f < faces.rows(); ++f)
        for (std::int64_t e = 0; e < k; ++e) ++links.offsets[static_cast<std::size_t>(faces(f, e) + 1)];
    std::partial_sum(links.offsets.begin(), links.offsets.end(), links.offsets.begin());
    links.neighbors.resize(static_cast<std::size_t>(links.offsets.back()));
    std::vector<std::int64_t> cursor(links.offsets.begin(), links.offsets.end() - 1);
    for (std::int64_t f = 0; f < faces.rows(); ++f)
        for (std::int64_t e = 0; e < k; ++e)
            links.neighbors[static_cast<std::size_t>(cursor[static_cast<std::size_t>(faces(f, e))]++)] = faces(f, (e + 1) % k);
    return links;
}

}  // namespace dsreg
