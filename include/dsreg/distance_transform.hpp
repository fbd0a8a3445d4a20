// dsreg — Euclidean distance transforms of a binary volume (exact, separable).
//
// Distances are in physical units (the grid's spacing, possibly anisotropic) between voxel
// centres. Everything outside the grid is background (volume.hpp), so the voxels just outside
// the grid count as background voxels: an object voxel on the border of the grid is one voxel
// from the background.
#pragma once

#include <limits>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// Which voxels the distance is measured to.
enum class DistanceTarget {
    background,  ///< distance from each voxel centre to the nearest background voxel centre
                 ///< (0 on background voxels; outside the grid counts)
    object,      ///< distance to the nearest object voxel centre (0 on object voxels; +inf for
                 ///< every voxel of a volume without object voxels)
    other_kind,  ///< both in one map: on object voxels the distance to the background, on
                 ///< background voxels the distance to the object (never 0); the memory of one
                 ///< transform, two envelopes per line
};

/// The exact Euclidean distance transform, one value per voxel (x fastest, as the mask):
/// three passes of the lower envelope of parabolas (Felzenszwalb and Huttenlocher, "Distance
/// transforms of sampled functions", 2012), one along each axis, each weighted by the axis'
/// spacing. O(voxels), 4 bytes per voxel plus one line of work space per thread. With a finite
/// `cap` (physical units, positive), distances above it come out as the cap, which is faster when
/// most of the volume is farther than the cap from its targets (fewer sites per line).
std::vector<float> euclidean_distance_transform(const BinaryVolume& volume, DistanceTarget target,
                                                double cap = std::numeric_limits<double>::infinity());

/// The same on the grid grown by `padding` voxels on every side (background there), so that
/// distances are also known up to `padding` voxels outside the volume: voxel (i,j,k) of the
/// volume is voxel (i,j,k) + padding of `grid`. 4 bytes per voxel of the grown grid. Throws
/// dsreg::Error for a negative padding or a cap that is not positive.
struct PaddedDistanceMap {
    VoxelGrid grid;                ///< the grown grid (same spacing; origin moved out by the padding)
    std::int64_t padding = 0;
    std::vector<float> distance;   ///< one value per voxel of `grid`

    float at(std::int64_t i, std::int64_t j, std::int64_t k) const {  ///< voxel (i,j,k) of the grown grid
        return distance[std::size_t(grid.linear_index(i, j, k))];
    }
};
/// The object is every voxel of a non-zero label (a BinaryVolume's object, a label map's labels).
PaddedDistanceMap padded_distance_transform(const VoxelLabels& volume, DistanceTarget target, std::int64_t padding,
                                            double cap = std::numeric_limits<double>::infinity());

}  // namespace dsreg
