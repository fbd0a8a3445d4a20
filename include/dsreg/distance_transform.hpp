// dsreg — Euclidean distance transforms of a binary volume (exact, separable).
//
// Distances are in physical units (the grid's spacing, possibly anisotropic) between voxel
// centres. Everything outside the grid is background (volume.hpp), so the voxels just outside
// the grid count as background voxels: an object voxel on the border of the grid is one voxel
// from the background.
#pragma once

#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// Which voxels the distance is measured to.
enum class DistanceTarget {
    background,  ///< distance from each voxel centre to the nearest background voxel centre
                 ///< (0 on background voxels; outside the grid counts)
    object,      ///< distance to the nearest object voxel centre (0 on object voxels; +inf for
                 ///< every voxel of a volume without object voxels)
};

/// The exact Euclidean distance transform, one value per voxel (x fastest, as the mask):
/// three passes of the lower envelope of parabolas (Felzenszwalb and Huttenlocher, "Distance
/// transforms of sampled functions", 2012), one along each axis, each weighted by the axis'
/// spacing. O(voxels), 4 bytes per voxel plus one line of work space per thread.
std::vector<float> euclidean_distance_transform(const BinaryVolume& volume, DistanceTarget target);

}  // namespace dsreg
