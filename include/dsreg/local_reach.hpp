// dsreg — how far the object and the background extend around each surfel: its local reach, and
// the local thickness of the object and of the background at a voxel.
//
// The reach says where a surfel's neighbourhood stops looking like a half-space: a part thinner
// than it (a tube, a plate, a narrow gap of background), a strongly curved place, a sharp edge.
// Integral invariants use it to bound their radius (adaptive_normals.hpp), the regularization to
// weight its data term on thin parts (local_weights.hpp).
//
// Both rest on the distance maps D_bg (from each object voxel centre to the nearest background
// voxel centre) and D_obj (from each background voxel centre to the nearest object voxel centre),
// distance_transform.hpp, computed on the grid grown by the cap so that the background outside
// the volume counts, and kept in 1/16 of the smallest spacing (rounded down; 2 bytes per voxel).
// On a label map (VoxelLabels, volume.hpp) every label is an "object" of its own: a voxel keeps
// the distance to the nearest voxel of another label, and a face's inner side is its inner
// label, its outer side its outer label (the background being label 0).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// D_bg on the object voxels and D_obj on the background voxels, on the bounding box of the
/// labelled voxels grown by `padding` voxels on every side (volume voxel v is map voxel v −
/// first + padding), in units of `unit`; on the whole grid grown so when that box is not much
/// smaller (first = 0). Everything outside the box is background, so every voxel within
/// `padding` of a labelled one is in the maps, whatever the volume around it (a small structure
/// in a large image costs its box, not the image). Distances above 2·(cap + the
/// largest spacing) are stored as that value (reach_maps): every length the reaches and
/// thicknesses compare with them is shorter, so they come out as with the exact distances.
struct ReachMaps {
    VoxelGrid grid;  ///< the grown box, in the volume's physical frame
    std::int64_t padding = 0;
    Index3 first{0, 0, 0};  ///< the volume voxel where the box starts (before its padding)
    double unit = 1;  ///< physical length of one step of the stored distances
    double cap = 0;   ///< distances and reaches are meaningful up to this (physical)
    std::vector<std::uint16_t> distance;  ///< per voxel of `grid`: D_bg (object) or D_obj (background)

    double at(std::int64_t i, std::int64_t j, std::int64_t k) const {  ///< physical distance, map voxel
        return unit * distance[std::size_t(grid.linear_index(i, j, k))];
    }
    Index3 map_voxel(const Index3& v) const {  ///< of volume voxel v
        return {v[0] - first[0] + padding, v[1] - first[1] + padding, v[2] - first[2] + padding};
    }
    Index3 volume_voxel(const Index3& y) const {  ///< of map voxel y
        return {y[0] + first[0] - padding, y[1] + first[1] - padding, y[2] + first[2] - padding};
    }
};

/// The maps for reaches up to `cap` (physical units): the distance transform of the labelled
/// voxels on their grown bounding box (4 bytes per voxel while it runs), then that of each label
/// on its own bounding box grown by one voxel (enough for the exact distances). Throws dsreg::Error for a cap that is
/// not positive and finite, or so large that the distances would not fit (about 4000 voxels).
ReachMaps reach_maps(const VoxelLabels& volume, double cap);

/// Local reach of the object and of the background at every surfel, physical units. With c the
/// surfel centre, n its outward direction, v its object voxel and w its background voxel:
///  * inner: the largest D_bg(y) over the centres y of the object voxels met by the ray c − t·n
///    (t ≥ 0, steps of half the smallest spacing, until it leaves the object) such that
///    |y − v| < D_bg(y): the radius of the largest ball centred on the inward ray that holds only
///    object voxel centres and contains v;
///  * outer: the same for the background along c + t·n, containing w (the background beyond the
///    volume included).
/// Each is at least the smallest spacing (the voxel's own ball) and at most the cap. So each is
/// at most half the local thickness at v (resp. w).
struct SurfelReach {
    Eigen::VectorXd inner, outer;

    /// min(inner, outer) of each surfel.
    Eigen::VectorXd smallest() const { return inner.cwiseMin(outer); }
};

/// The reach of every surfel along `directions` (one outward unit vector per surfel, e.g. a
/// normal field). Throws dsreg::Error for a wrong number of directions.
SurfelReach surfel_reach(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         const ReachMaps& maps);
/// The same, computing the maps for `cap`.
SurfelReach surfel_reach(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap);

/// Half the local thickness at voxel v of the volume (of the object if v is an object voxel, of
/// the background otherwise): the radius of the largest ball centred at a voxel centre y of the
/// same kind that holds no centre of the other kind (radius D(y)) and contains v (|y − v| <
/// D(y)), the local-thickness measure of Hildebrand and Rüegsegger. Balls are searched up to
/// `limit` (physical, at most the maps' cap): the result is min(half thickness, limit).
double half_local_thickness(const VoxelLabels& volume, const ReachMaps& maps, const Index3& v, double limit);

/// Each value replaced by the largest over the faces within `rings` steps of edge adjacency:
/// features of one or two voxels (digitization noise: a voxel sticking out, a pit) no longer
/// count as thin parts, while a part thin all along keeps its reach.
Eigen::VectorXd max_over_rings(const DigitalSurface& surface, Eigen::VectorXd face_values, int rings);

}  // namespace dsreg
