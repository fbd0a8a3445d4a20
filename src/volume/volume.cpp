#include "dsreg/volume.hpp"

#include <algorithm>

namespace dsreg {

bool VoxelBox::contains(const VoxelBox& box) const {
    if (box.empty()) return true;
    for (int a = 0; a < 3; ++a)
        if (box.lo[a] < lo[a] || box.hi[a] > hi[a]) return false;
    return true;
}

VoxelBox VoxelBox::grown(std::int64_t margin) const { return grown(Index3{margin, margin, margin}); }

VoxelBox VoxelBox::grown(const Index3& margin) const {
    VoxelBox box = *this;
    for (int a = 0; a < 3; ++a) {
        box.lo[a] -= margin[a];
        box.hi[a] += margin[a];
    }
    return box;
}

VoxelBox VoxelBox::clipped(const Index3& dims) const {
    VoxelBox box = *this;
    for (int a = 0; a < 3; ++a) {
        box.lo[a] = std::clamp<std::int64_t>(box.lo[a], 0, dims[a]);
        box.hi[a] = std::clamp<std::int64_t>(box.hi[a], box.lo[a], dims[a]);
    }
    return box;
}

std::int64_t BinaryVolume::object_voxel_count() const {
    return static_cast<std::int64_t>(std::count_if(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; }));
}

}  // namespace dsreg
