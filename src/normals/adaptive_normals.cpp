// Integral-invariant normals with a per-surfel radius chosen from the local reach of the object
// and of the background (include/dsreg/adaptive_normals.hpp).
#include "dsreg/adaptive_normals.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>

#include "dsreg/distance_transform.hpp"
#include "dsreg/error.hpp"
#include "integral_invariant_sums.hpp"

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

/// The reach along one ray: the largest distance[y] over the voxels y of the given kind met by
/// from + t·direction (0 ≤ t ≤ cap, steps of half the smallest spacing) before the ray leaves
/// them, among those whose ball of radius distance[y] contains `anchor` (a voxel centre).
/// At least the smallest spacing (the anchor's own ball).
double reach_along(const BinaryVolume& volume, const std::vector<float>& distance, bool object_side,
                   const Eigen::Vector3d& from, const Eigen::Vector3d& direction, const Eigen::Vector3d& anchor,
                   double cap) {
    const VoxelGrid& grid = volume.grid;
    const double step = 0.5 * grid.spacing.minCoeff();
    double best = grid.spacing.minCoeff();
    for (double t = 0.5 * step; t <= cap; t += step) {
        Index3 y;
        if (!voxel_at(grid, from + t * direction, y)) {
            // Outside the grid is background and holds no object: a background ray leaving
            // the grid has met no object on its way, and nothing beyond bounds its balls.
            return object_side ? std::min(best, cap) : cap;
        }
        if (volume.inside(y[0], y[1], y[2]) != object_side) break;
        const double d = distance[std::size_t(grid.linear_index(y[0], y[1], y[2]))];
        const Eigen::Vector3d centre = grid.voxel_center(y[0], y[1], y[2]);
        if ((centre - anchor).norm() < d) best = std::max(best, d);
        if (best >= cap) return cap;
    }
    return std::min(best, cap);
}

double reach_cap_check(double cap) {
    if (!(cap > 0) || !std::isfinite(cap)) throw Error("surfel_reach: the cap must be positive and finite");
    return cap;
}

}  // namespace

SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap) {
    reach_cap_check(cap);
    if (directions.rows() != surface.face_count())
        throw Error("surfel_reach: one direction per surfel expected (got " + std::to_string(directions.rows()) +
                    " for " + std::to_string(surface.face_count()) + " surfels)");
    const VoxelGrid& grid = volume.grid;
    SurfelReach reach;
    reach.inner.resize(surface.face_count());
    reach.outer.resize(surface.face_count());
    {
        const std::vector<float> to_background = euclidean_distance_transform(volume, DistanceTarget::background);
#pragma omp parallel for schedule(dynamic, 1024)
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            const Surfel& s = surface.surfels[std::size_t(f)];
            const Eigen::Vector3d v = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
            Eigen::Vector3d c = v;
            c[s.axis] += 0.5 * s.sign * grid.spacing[s.axis];
            reach.inner[f] = reach_along(volume, to_background, true, c, -directions.row(f).transpose(), v, cap);
        }
    }
    const std::vector<float> to_object = euclidean_distance_transform(volume, DistanceTarget::object);
#pragma omp parallel for schedule(dynamic, 1024)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        Eigen::Vector3d w = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        w[s.axis] += s.sign * grid.spacing[s.axis];
        Eigen::Vector3d c = w;
        c[s.axis] -= 0.5 * s.sign * grid.spacing[s.axis];
        reach.outer[f] = reach_along(volume, to_object, false, c, directions.row(f).transpose(), w, cap);
    }
    return reach;
}

namespace {

/// Radii max·2^(−l/levels) for l = 0, 1, … down to min: the largest level ≤ r of each surfel.
struct RadiusLevels {
    double max_radius, min_radius;
    int per_octave;
    int count() const {
        return 1 + int(std::floor(per_octave * std::log2(max_radius / min_radius) + 1e-9));
    }
    double radius(int level) const { return max_radius * std::exp2(-double(level) / per_octave); }
    int level_of(double r) const {  // the smallest level whose radius is ≤ r (clamped)
        if (!(r < max_radius)) return 0;
        const int l = int(std::ceil(per_octave * std::log2(max_radius / r) - 1e-9));
        return std::min(std::max(l, 0), count() - 1);
    }
};

/// II normals with a per-surfel level (a negative level: not computed, zero row); one ball (six
/// stencils) per level used.
PointMatrix normals_at_levels(const BinaryVolume& volume, const detail::RowRuns& rows, const DigitalSurface& surface,
                              const RadiusLevels& levels, const std::vector<int>& level, IntegralInvariantKernel kernel) {
    std::map<int, std::vector<std::int64_t>> faces_of_level;
    for (std::int64_t f = 0; f < surface.face_count(); ++f) faces_of_level[level[std::size_t(f)]].push_back(f);
    PointMatrix u = PointMatrix::Zero(surface.face_count(), 3);
    for (const auto& [l, faces] : faces_of_level) {
        if (l < 0) continue;  // not wanted
        const detail::IntegralInvariantBall ball(volume.grid.spacing, levels.radius(l), kernel);
        const std::int64_t n = std::int64_t(faces.size());
#pragma omp parallel for schedule(dynamic, 256)
        for (std::int64_t i = 0; i < n; ++i) {
            const std::int64_t f = faces[std::size_t(i)];
            u.row(f) = ball.normal(volume, rows, surface.surfels[std::size_t(f)]).transpose();
        }
    }
    return u;
}

void check_options(const AdaptiveNormalOptions& o) {
    const auto positive = [](double r) { return r > 0 && std::isfinite(r); };
    if (!positive(o.max_radius) || !positive(o.min_radius))
        throw Error("adaptive normals: the radii must be positive and finite");
    if (o.min_radius > o.max_radius) throw Error("adaptive normals: the smallest radius exceeds the largest");
    if (!positive(o.reach_factor)) throw Error("adaptive normals: the reach factor must be positive");
    if (o.levels_per_octave < 2) throw Error("adaptive normals: at least two radius levels per octave");
}

/// The level of each surfel allowed by its reach.
std::vector<int> levels_from_reach(const SurfelReach& reach, const RadiusLevels& levels, double factor) {
    std::vector<int> level(static_cast<std::size_t>(reach.inner.size()));
    for (Eigen::Index f = 0; f < reach.inner.size(); ++f)
        level[std::size_t(f)] = levels.level_of(factor * std::min(reach.inner[f], reach.outer[f]));
    return level;
}

}  // namespace

AdaptiveNormalField adaptive_integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface,
                                                        const AdaptiveNormalOptions& o) {
    check_options(o);
    const detail::RowRuns rows = detail::build_row_runs(volume);
    const RadiusLevels levels{o.max_radius, o.min_radius, o.levels_per_octave};
    const int half_octave = o.levels_per_octave / 2;  // r/√2 is this many levels down
    const std::int64_t m = surface.face_count();
    const int narrow_top = std::min(half_octave, levels.count() - 1);
    // The pilot: the whole surface at the narrow radius of the thick parts, whose directions the
    // reach rays follow and which is n(r/√2) wherever the reach allows r = max_radius.
    const PointMatrix pilot =
        normals_at_levels(volume, rows, surface, levels, std::vector<int>(static_cast<std::size_t>(m), narrow_top), o.kernel);
    const double cap = o.max_radius / o.reach_factor + volume.grid.spacing.maxCoeff();
    AdaptiveNormalField field;
    field.reach = surfel_reach(volume, surface, pilot, cap);
    std::vector<int> level = levels_from_reach(field.reach, levels, o.reach_factor);
    field.normals = normals_at_levels(volume, rows, surface, levels, level, o.kernel);
    for (int pass = 0; pass < o.reach_passes; ++pass) {
        field.reach = surfel_reach(volume, surface, field.normals, cap);
        level = levels_from_reach(field.reach, levels, o.reach_factor);
        field.normals = normals_at_levels(volume, rows, surface, levels, level, o.kernel);
    }
    field.radius.resize(m);
    for (std::int64_t f = 0; f < m; ++f) field.radius[f] = levels.radius(level[std::size_t(f)]);
    if (!o.extrapolate) return field;

    // Richardson extrapolation n0 ≈ 2·n(r/√2) − n(r) (the O(r²) bias cancels) where r is large
    // enough for the narrower ball to be reliable; the pilot is n(r/√2) where r = max_radius.
    std::vector<int> narrow_level(level);
    std::vector<int> missing(static_cast<std::size_t>(m), -1);
    bool any_missing = false;
    for (std::int64_t f = 0; f < m; ++f) {
        narrow_level[std::size_t(f)] = std::min(level[std::size_t(f)] + half_octave, levels.count() - 1);
        if (narrow_level[std::size_t(f)] != narrow_top) missing[std::size_t(f)] = narrow_level[std::size_t(f)], any_missing = true;
    }
    PointMatrix narrow = pilot;
    if (any_missing) {
        const PointMatrix extra = normals_at_levels(volume, rows, surface, levels, missing, o.kernel);
        for (std::int64_t f = 0; f < m; ++f)
            if (missing[std::size_t(f)] >= 0) narrow.row(f) = extra.row(f);
    }
    const double agreement = std::cos(o.extrapolation_agreement_deg * M_PI / 180.0);
    const double threshold = o.extrapolation_threshold_deg * M_PI / 180.0;
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        if (field.radius[f] < o.extrapolation_min_radius) continue;
        const Eigen::RowVector3d wide = field.normals.row(f);
        if (wide.dot(narrow.row(f)) < agreement) {
            field.normals.row(f) = narrow.row(f);
            continue;
        }
        // The correction 2·(n(r/√2) − n(r)), shrunk by the threshold (soft thresholding: a
        // difference at the noise level is no evidence of bias).
        const Eigen::RowVector3d correction = 2.0 * (narrow.row(f) - wide);
        const double size = correction.norm();
        const double kept = size > threshold ? (size - threshold) / size : 0.0;
        field.normals.row(f) = (wide + kept * correction).normalized();
    }
    return field;
}

}  // namespace dsreg
