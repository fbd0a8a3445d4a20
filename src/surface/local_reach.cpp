// The local reach of the object and of the background at each surfel, along rays through the
// distance transforms (include/dsreg/local_reach.hpp).
#include "dsreg/local_reach.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/distance_transform.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// The voxel whose box contains the physical point p, or false outside the grid.
bool voxel_at(const VoxelGrid& grid, const Eigen::Vector3d& p, Index3& voxel) {
    for (int a = 0; a < 3; ++a) {
        voxel[std::size_t(a)] = std::int64_t(std::floor((p[a] - grid.origin[a]) / grid.spacing[a] + 0.5));
        if (voxel[std::size_t(a)] < 0 || voxel[std::size_t(a)] >= grid.dims[std::size_t(a)]) return false;
    }
    return true;
}

/// The reach along one ray from `from` (see local_reach.hpp): voxels of the kind `object_side`,
/// `distance` the distance transform to the other kind, `anchor` the voxel centre the balls
/// must contain.
double reach_along(const BinaryVolume& volume, const std::vector<float>& distance, bool object_side,
                   const Eigen::Vector3d& from, const Eigen::Vector3d& direction, const Eigen::Vector3d& anchor,
                   double cap) {
    const VoxelGrid& grid = volume.grid;
    const double step = 0.5 * grid.spacing.minCoeff();
    double best = grid.spacing.minCoeff();
    for (double t = 0.5 * step; t <= cap; t += step) {
        Index3 y;
        // Outside the grid is background and holds no object: a background ray leaving the grid
        // has met no object on its way, and nothing beyond bounds its balls.
        if (!voxel_at(grid, from + t * direction, y)) return object_side ? std::min(best, cap) : cap;
        if (volume.inside(y[0], y[1], y[2]) != object_side) break;
        const double d = distance[std::size_t(grid.linear_index(y[0], y[1], y[2]))];
        if ((grid.voxel_center(y[0], y[1], y[2]) - anchor).norm() < d) best = std::max(best, d);
        if (best >= cap) return cap;
    }
    return std::min(best, cap);
}

/// The reach of every surfel on one side: the object (from its object voxel, against the
/// outward direction) or the background (from its background voxel, along it).
Eigen::VectorXd side_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                           double cap, bool object_side) {
    const VoxelGrid& grid = volume.grid;
    const std::vector<float> distance = euclidean_distance_transform(
        volume, object_side ? DistanceTarget::background : DistanceTarget::object);
    Eigen::VectorXd reach(surface.face_count());
    const double sense = object_side ? -1.0 : 1.0;
#pragma omp parallel for schedule(dynamic, 1024)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        Eigen::Vector3d anchor = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);  // v
        if (!object_side) anchor[s.axis] += s.sign * grid.spacing[s.axis];                // w
        Eigen::Vector3d centre = anchor;
        centre[s.axis] -= sense * 0.5 * s.sign * grid.spacing[s.axis];
        reach[f] = reach_along(volume, distance, object_side, centre, sense * directions.row(f).transpose(), anchor, cap);
    }
    return reach;
}

}  // namespace

SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap) {
    if (!(cap > 0) || !std::isfinite(cap)) throw Error("surfel_reach: the cap must be positive and finite");
    if (directions.rows() != surface.face_count())
        throw Error("surfel_reach: one direction per surfel expected (got " + std::to_string(directions.rows()) +
                    " for " + std::to_string(surface.face_count()) + " surfels)");
    SurfelReach reach;
    reach.inner = side_reach(volume, surface, directions, cap, true);  // one distance map at a time
    reach.outer = side_reach(volume, surface, directions, cap, false);
    return reach;
}

Eigen::VectorXd max_over_rings(const DigitalSurface& surface, Eigen::VectorXd values, int rings) {
    for (int ring = 0; ring < rings; ++ring) {
        Eigen::VectorXd next = values;
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < surface.face_count(); ++f)
            for (int e = 0; e < 4; ++e) next[f] = std::max(next[f], values[surface.adjacent_face(f, e)]);
        values.swap(next);
    }
    return values;
}

}  // namespace dsreg
