// The local reach of the object and of the background at each surfel, along rays through the
// distance maps, and the local thickness at a voxel (include/dsreg/local_reach.hpp).
#include "dsreg/local_reach.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "dsreg/distance_transform.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

constexpr double kStepsPerVoxel = 16;  // stored distances: 1/16 of the smallest spacing

/// The grown-grid voxel whose box contains the physical point p, or false outside the grown grid.
bool voxel_at(const VoxelGrid& grid, const Eigen::Vector3d& p, Index3& voxel) {
    for (int a = 0; a < 3; ++a) {
        voxel[std::size_t(a)] = std::int64_t(std::floor((p[a] - grid.origin[a]) / grid.spacing[a] + 0.5));
        if (voxel[std::size_t(a)] < 0 || voxel[std::size_t(a)] >= grid.dims[std::size_t(a)]) return false;
    }
    return true;
}

/// Whether grown-grid voxel y is an object voxel of the volume.
bool object_at(const BinaryVolume& volume, const ReachMaps& maps, const Index3& y) {
    return volume.inside(y[0] - maps.padding, y[1] - maps.padding, y[2] - maps.padding);
}

/// The reach along one ray from `from` (local_reach.hpp): voxels of the kind `object_side`,
/// `anchor` the voxel centre the balls must contain.
double reach_along(const BinaryVolume& volume, const ReachMaps& maps, bool object_side, const Eigen::Vector3d& from,
                   const Eigen::Vector3d& direction, const Eigen::Vector3d& anchor) {
    const double step = 0.5 * maps.grid.spacing.minCoeff();
    double best = maps.grid.spacing.minCoeff();
    for (double t = 0.5 * step; t <= maps.cap; t += step) {
        Index3 y;
        if (!voxel_at(maps.grid, from + t * direction, y)) break;
        if (object_at(volume, maps, y) != object_side) break;
        const double d = maps.at(y[0], y[1], y[2]);
        if ((maps.grid.voxel_center(y[0], y[1], y[2]) - anchor).norm() < d) best = std::max(best, d);
        if (best >= maps.cap) break;
    }
    return std::min(best, maps.cap);
}

}  // namespace

ReachMaps reach_maps(const BinaryVolume& volume, double cap) {
    if (!(cap > 0) || !std::isfinite(cap)) throw Error("reach maps: the cap must be positive and finite");
    ReachMaps maps;
    maps.unit = volume.grid.spacing.minCoeff() / kStepsPerVoxel;
    if (cap / maps.unit > 0.5 * std::numeric_limits<std::uint16_t>::max())
        throw Error("reach maps: a cap of " + std::to_string(cap) + " spans too many voxels");
    maps.cap = cap;
    maps.padding = std::int64_t(std::ceil(cap / volume.grid.spacing.minCoeff())) + 1;
    for (DistanceTarget target : {DistanceTarget::background, DistanceTarget::object}) {
        const PaddedDistanceMap map = padded_distance_transform(volume, target, maps.padding);
        if (maps.distance.empty()) {
            maps.grid = map.grid;
            maps.distance.assign(map.distance.size(), 0);
        }
        // Each voxel keeps the distance to the other kind: D_bg where it is object, D_obj where not.
        const std::uint16_t largest = std::numeric_limits<std::uint16_t>::max();
        for (std::size_t v = 0; v < map.distance.size(); ++v)
            if (map.distance[v] > 0)
                maps.distance[v] = std::uint16_t(std::min<double>(largest, std::floor(map.distance[v] / maps.unit)));
    }
    return maps;
}

SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         const ReachMaps& maps) {
    if (directions.rows() != surface.face_count())
        throw Error("surfel_reach: one direction per surfel expected (got " + std::to_string(directions.rows()) +
                    " for " + std::to_string(surface.face_count()) + " surfels)");
    SurfelReach reach;
    reach.inner.resize(surface.face_count());
    reach.outer.resize(surface.face_count());
    const VoxelGrid& grid = volume.grid;
#pragma omp parallel for schedule(dynamic, 1024)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const Eigen::Vector3d v = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        Eigen::Vector3d w = v, c = v;
        w[s.axis] += s.sign * grid.spacing[s.axis];
        c[s.axis] += 0.5 * s.sign * grid.spacing[s.axis];
        const Eigen::Vector3d n = directions.row(f).transpose();
        reach.inner[f] = reach_along(volume, maps, true, c, -n, v);
        reach.outer[f] = reach_along(volume, maps, false, c, n, w);
    }
    return reach;
}

SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap) {
    return surfel_reach(volume, surface, directions, reach_maps(volume, cap));
}

double half_local_thickness(const BinaryVolume& volume, const ReachMaps& maps, const Index3& v, double limit) {
    limit = std::min(limit, maps.cap);
    const bool kind = volume.inside(v[0], v[1], v[2]);
    const Eigen::Vector3d& s = maps.grid.spacing;
    const Index3 centre{v[0] + maps.padding, v[1] + maps.padding, v[2] + maps.padding};
    Index3 reach;  // a ball of radius ≤ limit containing v has its centre within limit of v
    for (int a = 0; a < 3; ++a) reach[std::size_t(a)] = std::int64_t(std::ceil(limit / s[a]));
    double best = 0;
    for (std::int64_t k = centre[2] - reach[2]; k <= centre[2] + reach[2]; ++k)
        for (std::int64_t j = centre[1] - reach[1]; j <= centre[1] + reach[1]; ++j)
            for (std::int64_t i = centre[0] - reach[0]; i <= centre[0] + reach[0]; ++i) {
                if (!maps.grid.contains(i, j, k) || object_at(volume, maps, {i, j, k}) != kind) continue;
                const double d = maps.at(i, j, k);
                if (d <= best) continue;
                const Eigen::Vector3d offset(double(i - centre[0]) * s.x(), double(j - centre[1]) * s.y(),
                                             double(k - centre[2]) * s.z());
                if (offset.norm() < d) best = std::min(d, limit);
                if (best >= limit) return limit;
            }
    return best;
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
