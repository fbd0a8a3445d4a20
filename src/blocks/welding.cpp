// Welding the blocks' pieces into the whole surface (include/dsreg/blocks.hpp).
#include <algorithm>
#include <numeric>
#include <string>

#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// The permutation that sorts `keys`; throws if a key repeats (two owners).
std::vector<std::int64_t> sorting_order(const std::vector<std::int64_t>& keys, const char* what) {
    std::vector<std::int64_t> order(keys.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) { return keys[std::size_t(a)] < keys[std::size_t(b)]; });
    for (std::size_t q = 1; q < order.size(); ++q)
        if (keys[std::size_t(order[q])] == keys[std::size_t(order[q - 1])])
            throw Error(std::string("block seams do not match: ") + what + " " + std::to_string(keys[std::size_t(order[q])]) +
                        " is owned by two blocks");
    return order;
}

/// Index of `key` in the ascending `keys`, or throws naming what is missing.
std::int32_t index_of(const std::vector<std::int64_t>& keys, std::int64_t key, const std::string& missing) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), key);
    if (it == keys.end() || *it != key) throw Error("block seams do not match: " + missing + " that no block holds");
    return std::int32_t(it - keys.begin());
}

/// Throws unless the face across edge e of f has that edge the other way round, with f across it.
void check_closed(const DigitalSurface& s) {
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        for (int e = 0; e < 4; ++e) {
            const std::int64_t g = s.adjacent_face(f, e);
            bool matched = false;
            for (int k = 0; k < 4 && !matched; ++k)
                matched = s.adjacent_face(g, k) == f && s.quads(g, k) == s.quads(f, (e + 1) % 4) && s.quads(g, (k + 1) % 4) == s.quads(f, e);
            if (!matched)
                throw Error("block seams do not match: the welded surface is not closed at the edge between faces " +
                            std::to_string(f) + " and " + std::to_string(g));
        }
}

}  // namespace

WeldedSurface weld_pieces(std::vector<BlockPiece>& pieces, const VoxelGrid& grid) {
    std::vector<std::int64_t> vertex_keys, face_keys;
    for (const BlockPiece& p : pieces) {
        vertex_keys.insert(vertex_keys.end(), p.vertex_keys.begin(), p.vertex_keys.end());
        face_keys.insert(face_keys.end(), p.face_keys.begin(), p.face_keys.end());
    }
    const std::vector<std::int64_t> vertex_order = sorting_order(vertex_keys, "vertex");
    const std::vector<std::int64_t> face_order = sorting_order(face_keys, "surfel");
    const std::int64_t n = std::int64_t(vertex_keys.size()), m = std::int64_t(face_keys.size());
    if (n >= std::int64_t(1) << 31 || m >= std::int64_t(1) << 30)
        throw Error("the welded surface has " + std::to_string(m) + " surfels; at most 2^30 are supported in one mesh");

    // Rows of the concatenated pieces, then in key order.
    PointMatrix positions(n, 3), normals(m, 3);
    std::vector<std::array<std::int64_t, 4>> corners(static_cast<std::size_t>(m)), neighbors(static_cast<std::size_t>(m));
    {
        std::int64_t v = 0, f = 0;
        for (BlockPiece& p : pieces) {
            for (std::int64_t i = 0; i < std::int64_t(p.vertex_keys.size()); ++i) positions.row(v++) = p.positions.row(i);
            for (std::int64_t i = 0; i < std::int64_t(p.face_keys.size()); ++i) {
                normals.row(f) = p.face_normals.row(i);
                neighbors[std::size_t(f)] = p.face_neighbors[std::size_t(i)];
                corners[std::size_t(f++)] = p.face_corners[std::size_t(i)];
            }
            p = BlockPiece();
        }
    }
    WeldedSurface w;
    DigitalSurface& s = w.surface;
    s.grid = grid;
    w.positions.resize(n, 3);
    s.vertices.resize(n, 3);
    s.vertex_pointels.resize(n, 3);
    std::vector<std::int64_t> sorted_vertex_keys(static_cast<std::size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t from = vertex_order[std::size_t(i)];
        const std::int64_t key = vertex_keys[std::size_t(from)];
        sorted_vertex_keys[std::size_t(i)] = key;
        w.positions.row(i) = positions.row(from);
        const Index3 p = pointel_of_vertex_key(grid.dims, key);
        s.vertices.row(i) = grid.pointel_position(p[0], p[1], p[2]).transpose();
        for (int a = 0; a < 3; ++a) s.vertex_pointels(i, a) = std::int32_t(p[a]);
    }
    positions = PointMatrix();
    vertex_keys = {};
    std::vector<std::int64_t> sorted_face_keys(static_cast<std::size_t>(m));
    for (std::int64_t f = 0; f < m; ++f) sorted_face_keys[std::size_t(f)] = face_keys[std::size_t(face_order[std::size_t(f)])];
    w.normals.resize(m, 3);
    s.quads.resize(m, 4);
    s.adjacent_face.resize(m, 4);
    s.surfels.resize(std::size_t(m));
    for (std::int64_t f = 0; f < m; ++f) {
        const std::int64_t from = face_order[std::size_t(f)];
        const std::int64_t key = sorted_face_keys[std::size_t(f)];
        s.surfels[std::size_t(f)] = surfel_of_key(grid.dims, key);
        w.normals.row(f) = normals.row(from);
        const std::string face = "surfel " + std::to_string(key) + " has ";
        for (int k = 0; k < 4; ++k) {
            const std::int64_t corner = corners[std::size_t(from)][std::size_t(k)];
            s.quads(f, k) = index_of(sorted_vertex_keys, corner, face + "a corner (vertex " + std::to_string(corner) + ")");
            const std::int64_t neighbor = neighbors[std::size_t(from)][std::size_t(k)];
            s.adjacent_face(f, k) = index_of(sorted_face_keys, neighbor, face + "a neighbour (surfel " + std::to_string(neighbor) + ")");
        }
    }
    check_closed(s);
    label_components(s);
    s.split_pointel_count = count_split_pointels(s);
    return w;
}

}  // namespace dsreg
