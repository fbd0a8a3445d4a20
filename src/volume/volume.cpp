#include "dsreg/volume.hpp"

#include <algorithm>

namespace dsreg {

std::int64_t BinaryVolume::object_voxel_count() const {
    return static_cast<std::int64_t>(std::count_if(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; }));
}

}  // namespace dsreg
