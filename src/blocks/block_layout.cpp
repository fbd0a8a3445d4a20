// Block layouts (include/dsreg/blocks.hpp).
#include <algorithm>
#include <limits>
#include <string>

#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

Index3 BlockLayout::block_counts() const {
    Index3 counts{};
    for (int a = 0; a < 3; ++a) counts[a] = std::int64_t(cuts[a].size()) - 1;
    return counts;
}

std::int64_t BlockLayout::block_count() const {
    const Index3 c = block_counts();
    return c[0] * c[1] * c[2];
}

VoxelBox BlockLayout::box(std::int64_t block) const {
    const Index3 c = block_counts();
    const Index3 b{block % c[0], (block / c[0]) % c[1], block / (c[0] * c[1])};
    VoxelBox result;
    for (int a = 0; a < 3; ++a) {
        result.lo[a] = cuts[a][std::size_t(b[a])];
        result.hi[a] = cuts[a][std::size_t(b[a] + 1)];
    }
    return result;
}

std::int64_t BlockLayout::block_of(const Index3& voxel) const {
    const Index3 c = block_counts();
    Index3 b{};
    for (int a = 0; a < 3; ++a) {
        const auto& cut = cuts[a];
        b[a] = std::int64_t(std::upper_bound(cut.begin() + 1, cut.end() - 1, voxel[a]) - (cut.begin() + 1));
    }
    return b[0] + c[0] * (b[1] + c[1] * b[2]);
}

BlockLayout blocks_of_size(const Index3& dims, const Index3& block_size) {
    BlockLayout layout;
    layout.dims = dims;
    for (int a = 0; a < 3; ++a) {
        if (block_size[a] <= 0) throw Error("--block-size: every block size must be positive");
        for (std::int64_t c = 0; c < dims[a]; c += block_size[a]) layout.cuts[a].push_back(c);
        layout.cuts[a].push_back(dims[a]);
    }
    return layout;
}

BlockLayout blocks_for_parts(const Index3& dims, int parts) {
    if (parts < 1) throw Error("the number of blocks must be positive (got " + std::to_string(parts) + ")");
    // Among the factorizations parts = px·py·pz that the grid allows, the one with the least cut
    // area (the voxels the blocks exchange as halos): cuts across the longest axes.
    Index3 best{0, 0, 0};
    double best_area = std::numeric_limits<double>::infinity();
    for (std::int64_t px = 1; px <= parts; ++px) {
        if (parts % px) continue;
        for (std::int64_t py = 1; py <= parts / px; ++py) {
            if ((parts / px) % py) continue;
            const Index3 p{px, py, parts / px / py};
            if (p[0] > dims[0] || p[1] > dims[1] || p[2] > dims[2]) continue;
            const double area = double(p[0] - 1) * double(dims[1] * dims[2]) + double(p[1] - 1) * double(dims[0] * dims[2]) +
                                double(p[2] - 1) * double(dims[0] * dims[1]);
            if (area < best_area) best_area = area, best = p;
        }
    }
    if (best[0] == 0)
        throw Error("a grid of " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                    std::to_string(dims[2]) + " voxels cannot be cut into " + std::to_string(parts) + " blocks");
    BlockLayout layout;
    layout.dims = dims;
    for (int a = 0; a < 3; ++a)
        for (std::int64_t b = 0; b <= best[a]; ++b) layout.cuts[a].push_back(b * dims[a] / best[a]);
    return layout;
}

BlockLayout staggered_blocks(const BlockLayout& layout) {
    BlockLayout staggered;
    staggered.dims = layout.dims;
    for (int a = 0; a < 3; ++a) {
        const auto& cuts = layout.cuts[a];
        auto& out = staggered.cuts[a];
        out.push_back(0);
        for (std::size_t b = 0; b + 1 < cuts.size(); ++b) {
            const std::int64_t middle = (cuts[b] + cuts[b + 1]) / 2;
            if (middle > out.back()) out.push_back(middle);
        }
        if (layout.dims[a] > out.back()) out.push_back(layout.dims[a]);
    }
    return staggered;
}

}  // namespace dsreg
