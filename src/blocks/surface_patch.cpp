// The patch of the digital surface a block needs (include/dsreg/blocks.hpp).
#include <algorithm>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>

#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

Index3 plus(const Index3& a, const Index3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Index3 minus(const Index3& a, const Index3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

/// The patch's faces: the faces of `local` (extracted from the voxels of `box`) whose voxel lies in
/// `face_box`, in their (global) order.
std::vector<std::int32_t> faces_in(const DigitalSurface& local, const VoxelBox& box, const VoxelBox& face_box) {
    std::vector<std::int32_t> kept;
    for (std::int64_t f = 0; f < local.face_count(); ++f) {
        const auto& v = local.surfels[std::size_t(f)].voxel;
        if (face_box.contains(v[0] + box.lo[0], v[1] + box.lo[1], v[2] + box.lo[2])) kept.push_back(std::int32_t(f));
    }
    return kept;
}

}  // namespace

BinaryVolume crop_volume(const BinaryVolume& volume, const VoxelBox& volume_box, const VoxelBox& box) {
    if (!volume_box.contains(box)) throw Error("internal error: crop_volume outside the volume");
    BinaryVolume out;
    out.grid = volume.grid;
    out.grid.dims = box.size();
    const Index3 offset = minus(box.lo, volume_box.lo);
    out.grid.origin = volume.grid.voxel_center(offset[0], offset[1], offset[2]);
    out.mask.resize(std::size_t(box.voxel_count()));
    const Index3 d = box.size();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            std::memcpy(out.mask.data() + out.grid.linear_index(0, j, k),
                        volume.mask.data() + volume.grid.linear_index(offset[0], j + offset[1], k + offset[2]),
                        std::size_t(d[0]));
    return out;
}

SurfacePatch extract_surface_patch(const BinaryVolume& volume, const VoxelBox& volume_box, const VoxelGrid& grid,
                                   const VoxelBox& owned, const VoxelBox& rows, Connectivity connectivity,
                                   std::int64_t surface_margin) {
    if (volume.grid.dims != volume_box.size() || std::int64_t(volume.mask.size()) != volume_box.voxel_count())
        throw Error("internal error: the block volume does not match its box");
    if (!rows.contains(owned) || !VoxelBox{{0, 0, 0}, grid.dims}.contains(rows))
        throw Error("internal error: block boxes out of order");
    const VoxelBox box = rows.grown(kPatchVolumeMargin + surface_margin).clipped(grid.dims);
    if (!volume_box.contains(box)) throw Error("internal error: the block volume does not cover its patch");

    SurfacePatch patch;
    patch.surface.grid = volume.grid;
    const BinaryVolume sub = crop_volume(volume, volume_box, box);
    if (sub.object_voxel_count() == 0) return patch;
    const DigitalSurface local = extract_digital_surface(sub, connectivity);
    const std::vector<std::int32_t> kept = faces_in(local, box, rows.grown(kPatchFaceMargin + surface_margin).clipped(grid.dims));
    const std::vector<std::int64_t> local_keys = vertex_keys_of(local, box.lo, grid.dims);  // kept faces: whole umbrellas

    // Vertices of the kept faces, in key order.
    std::vector<std::int32_t> used;
    std::vector<char> seen(static_cast<std::size_t>(local.vertex_count()), 0);
    for (std::int32_t f : kept)
        for (int k = 0; k < 4; ++k) {
            const std::int32_t v = local.quads(f, k);
            if (!seen[std::size_t(v)]) seen[std::size_t(v)] = 1, used.push_back(v);
        }
    std::sort(used.begin(), used.end(), [&](std::int32_t a, std::int32_t b) { return local_keys[std::size_t(a)] < local_keys[std::size_t(b)]; });
    std::vector<std::int32_t> patch_vertex(static_cast<std::size_t>(local.vertex_count()), -1);
    for (std::size_t i = 0; i < used.size(); ++i) patch_vertex[std::size_t(used[i])] = std::int32_t(i);
    std::vector<std::int32_t> patch_face(static_cast<std::size_t>(local.face_count()), -1);
    for (std::size_t f = 0; f < kept.size(); ++f) patch_face[std::size_t(kept[f])] = std::int32_t(f);

    DigitalSurface& s = patch.surface;
    const std::int64_t m = std::int64_t(kept.size()), n = std::int64_t(used.size());
    const Index3 to_volume = minus(box.lo, volume_box.lo);  // extraction box → volume coordinates
    s.surfels.resize(std::size_t(m));
    s.quads.resize(m, 4);
    s.adjacent_face.resize(m, 4);
    patch.face_keys.resize(std::size_t(m));
    patch.face_owned.resize(std::size_t(m));
    for (std::int64_t f = 0; f < m; ++f) {
        const std::int32_t g = kept[std::size_t(f)];
        Surfel surfel = local.surfels[std::size_t(g)];
        const Index3 voxel = plus({surfel.voxel[0], surfel.voxel[1], surfel.voxel[2]}, box.lo);
        patch.face_keys[std::size_t(f)] = surfel_key(grid.dims, voxel, surfel.axis, surfel.sign);
        patch.face_owned[std::size_t(f)] = owned.contains(voxel[0], voxel[1], voxel[2]);
        for (int a = 0; a < 3; ++a) surfel.voxel[std::size_t(a)] += std::int32_t(to_volume[a]);
        s.surfels[std::size_t(f)] = surfel;
        for (int k = 0; k < 4; ++k) {
            s.quads(f, k) = patch_vertex[std::size_t(local.quads(g, k))];
            s.adjacent_face(f, k) = patch_face[std::size_t(local.adjacent_face(g, k))];
        }
    }
    s.vertices.resize(n, 3);
    s.vertex_pointels.resize(n, 3);
    patch.vertex_keys.resize(std::size_t(n));
    patch.vertex_owned.resize(std::size_t(n));
    patch.vertex_row.resize(std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t key = local_keys[std::size_t(used[std::size_t(i)])];
        const Index3 p = pointel_of_vertex_key(grid.dims, key);
        const Index3 voxel = key_voxel_of_vertex(grid.dims, key);
        patch.vertex_keys[std::size_t(i)] = key;
        patch.vertex_owned[std::size_t(i)] = owned.contains(voxel[0], voxel[1], voxel[2]);
        patch.vertex_row[std::size_t(i)] = rows.contains(voxel[0], voxel[1], voxel[2]);
        s.vertices.row(i) = grid.pointel_position(p[0], p[1], p[2]).transpose();
        for (int a = 0; a < 3; ++a) s.vertex_pointels(i, a) = std::int32_t(p[a] - volume_box.lo[a]);
    }
    s.split_pointel_count = count_split_pointels(s);
    return patch;
}

BlockPiece patch_piece(const SurfacePatch& patch, const PointMatrix& positions, const PointMatrix& normals) {
    BlockPiece piece;
    const std::int64_t m = patch.face_count(), n = patch.vertex_count();
    const std::int64_t owned_faces = std::count(patch.face_owned.begin(), patch.face_owned.end(), 1);
    const std::int64_t owned_vertices = std::count(patch.vertex_owned.begin(), patch.vertex_owned.end(), 1);
    piece.face_keys.reserve(std::size_t(owned_faces));
    piece.face_corners.reserve(std::size_t(owned_faces));
    piece.face_neighbors.reserve(std::size_t(owned_faces));
    piece.face_normals.resize(owned_faces, 3);
    for (std::int64_t f = 0; f < m; ++f) {
        if (!patch.face_owned[std::size_t(f)]) continue;
        piece.face_normals.row(std::int64_t(piece.face_keys.size())) = normals.row(f);
        piece.face_keys.push_back(patch.face_keys[std::size_t(f)]);
        std::array<std::int64_t, 4> corners{}, neighbors{};
        for (int k = 0; k < 4; ++k) {
            corners[std::size_t(k)] = patch.vertex_keys[std::size_t(patch.surface.quads(f, k))];
            const std::int32_t g = patch.surface.adjacent_face(f, k);
            if (g < 0) throw Error("internal error: an owned face of a block has a neighbour outside its patch");
            neighbors[std::size_t(k)] = patch.face_keys[std::size_t(g)];
        }
        piece.face_corners.push_back(corners);
        piece.face_neighbors.push_back(neighbors);
    }
    piece.vertex_keys.reserve(std::size_t(owned_vertices));
    piece.positions.resize(owned_vertices, 3);
    for (std::int64_t i = 0; i < n; ++i) {
        if (!patch.vertex_owned[std::size_t(i)]) continue;
        piece.positions.row(std::int64_t(piece.vertex_keys.size())) = positions.row(i);
        piece.vertex_keys.push_back(patch.vertex_keys[std::size_t(i)]);
    }
    return piece;
}

}  // namespace dsreg
