// dsreg — how far the object and the background extend around each surfel: its local reach.
//
// The reach says where a surfel's neighbourhood stops looking like a half-space: a part thinner
// than it (a tube, a plate, a narrow gap of background), a strongly curved place, a sharp edge.
// Integral invariants use it to bound their radius (adaptive_normals.hpp), the regularization to
// weight its data term on thin parts (local_weights.hpp).
#pragma once

#include <Eigen/Core>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// Local reach of the object and of the background at every surfel, physical units. With c the
/// surfel centre, n its outward direction, v its object voxel and w its background voxel:
///  * inner: the largest D_bg(y) over the centres y of the object voxels met by the ray c − t·n
///    (t ≥ 0, steps of half the smallest spacing, until it leaves the object) such that
///    |y − v| < D_bg(y), D_bg being the distance to the nearest background voxel centre
///    (distance_transform.hpp): the radius of the largest ball centred on the inward ray that
///    holds only object voxel centres and contains v;
///  * outer: the same for the background along c + t·n, containing w (a ray that leaves the
///    grid has met no object: the cap).
/// Each is at least the smallest spacing and at most `cap` (the rays stop there). So each is
/// at most half the local thickness of the object at v (resp. of the background at w): the
/// diameter of the largest ball of object (background) voxel centres that contains v (w).
struct SurfelReach {
    Eigen::VectorXd inner, outer;

    /// min(inner, outer) of each surfel.
    Eigen::VectorXd smallest() const { return inner.cwiseMin(outer); }
};

/// The reach of every surfel along `directions` (one outward unit vector per surfel, e.g. a
/// normal field). Two distance transforms (4 bytes per voxel, one at a time) and two rays per
/// surfel. Throws dsreg::Error for a cap that is not positive and finite or a wrong number of
/// directions.
SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap);

/// Each value replaced by the largest over the faces within `rings` steps of edge adjacency:
/// features of one or two voxels (digitization noise: a voxel sticking out, a pit) no longer
/// count as thin parts, while a part thin all along keeps its reach.
Eigen::VectorXd max_over_rings(const DigitalSurface& surface, Eigen::VectorXd face_values, int rings);

}  // namespace dsreg
