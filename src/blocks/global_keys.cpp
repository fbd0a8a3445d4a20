// Global names of surfels and vertices (include/dsreg/blocks.hpp): the order of the
// whole-volume extraction (src/surface/digital_surface.cpp).
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

}  // namespace dsreg
