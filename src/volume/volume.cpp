#include "dsreg/volume.hpp"

#include <algorithm>

#include "dsreg/error.hpp"

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

std::vector<std::int64_t> LabelVolume::voxel_counts() const {
    std::vector<std::int64_t> counts(values.size(), 0);
    for (const std::uint32_t label : labels) ++counts[label];
    return counts;
}

LabelVolume label_volume_from_mask(const BinaryVolume& volume) {
    LabelVolume labels;
    labels.grid = volume.grid;
    labels.values = {0, 1};
    labels.labels.resize(volume.mask.size());
    std::transform(volume.mask.begin(), volume.mask.end(), labels.labels.begin(),
                   [](std::uint8_t m) { return m != 0 ? 1u : 0u; });
    return labels;
}

void keep_labels(LabelVolume& volume, const std::vector<std::int64_t>& values, const std::string& option) {
    const std::vector<std::int64_t> counts = volume.voxel_counts();
    std::vector<std::uint32_t> renumbered(volume.values.size(), 0);
    std::vector<char> kept(volume.values.size(), 0);
    for (const std::int64_t value : values) {
        if (value == 0) throw Error(option + ": 0 is the background, not a label");
        const auto it = std::lower_bound(volume.values.begin() + 1, volume.values.end(), value);
        const std::size_t index = static_cast<std::size_t>(it - volume.values.begin());
        if (it == volume.values.end() || *it != value || counts[index] == 0)
            throw Error(option + ": no voxel has the label " + std::to_string(value));
        kept[index] = 1;
    }
    std::vector<std::int64_t> kept_values = {0};
    for (std::size_t index = 1; index < volume.values.size(); ++index) {
        if (!kept[index]) continue;
        renumbered[index] = static_cast<std::uint32_t>(kept_values.size());
        kept_values.push_back(volume.values[index]);
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < static_cast<std::int64_t>(volume.labels.size()); ++v)
        volume.labels[std::size_t(v)] = renumbered[volume.labels[std::size_t(v)]];
    volume.values = std::move(kept_values);
}

}  // namespace dsreg
