// Global names of surfels and vertices (include/dsreg/blocks.hpp): the order of the
// whole-volume extraction (src/surface/digital_surface.cpp).
#include <algorithm>
#include <limits>

#include "dsreg/blocks.hpp"

namespace dsreg {

std::int64_t surfel_key(const Index3& dims, const Index3& voxel, int axis, int sign) {
    const std::int64_t linear = voxel[0] + dims[0] * (voxel[1] + dims[1] * voxel[2]);
    return 6 * linear + 2 * axis + (sign > 0 ? 1 : 0);
}

Surfel surfel_of_key(const Index3& dims, std::int64_t key) {
    const std::int64_t linear = key / 6, code = key % 6;
    const std::int64_t i = linear % dims[0], j = (linear / dims[0]) % dims[1], k = linear / (dims[0] * dims[1]);
    return Surfel{{std::int32_t(i), std::int32_t(j), std::int32_t(k)}, std::int8_t(code / 2), std::int8_t(code % 2 ? 1 : -1)};
}

Index3 key_voxel_of_vertex(const Index3& dims, std::int64_t vertex_key) {
    const Surfel s = surfel_of_key(dims, vertex_key / 4);
    return {s.voxel[0], s.voxel[1], s.voxel[2]};
}

Index3 pointel_of_vertex_key(const Index3& dims, std::int64_t vertex_key) {
    return surfel_corner_pointel(surfel_of_key(dims, vertex_key / 4), int(vertex_key % 4));
}

std::vector<std::int64_t> vertex_keys_of(const DigitalSurface& surface, const Index3& offset, const Index3& dims) {
    std::vector<std::int64_t> keys(static_cast<std::size_t>(surface.vertex_count()), std::numeric_limits<std::int64_t>::max());
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const Index3 voxel{s.voxel[0] + offset[0], s.voxel[1] + offset[1], s.voxel[2] + offset[2]};
        const std::int64_t key = surfel_key(dims, voxel, s.axis, s.sign);
        for (int k = 0; k < 4; ++k) {
            std::int64_t& v = keys[std::size_t(surface.quads(f, k))];
            v = std::min(v, 4 * key + k);
        }
    }
    return keys;
}

}  // namespace dsreg
