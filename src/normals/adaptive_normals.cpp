// Integral-invariant normals with a per-surfel radius from the local reach of the object and of
// the background, extrapolated where the radius allows (include/dsreg/adaptive_normals.hpp).
#include "dsreg/adaptive_normals.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "dsreg/error.hpp"
#include "integral_invariant_sums.hpp"

namespace dsreg {

namespace {

/// Radii max·2^(−l/per_octave) for l = 0 … count − 2, all above min, and min itself last.
struct RadiusLevels {
    double max_radius, min_radius;
    int per_octave;

    // The tolerance of 1e-6 level: radii that differ by the round-off of the spacing (a float32
    // affine) get the same level.
    int count() const { return 1 + int(std::ceil(per_octave * std::log2(max_radius / min_radius) - 1e-6)); }
    double radius(int level) const {
        return level >= count() - 1 ? min_radius : max_radius * std::exp2(-double(level) / per_octave);
    }
    /// The level of the largest radius ≤ r (the smallest radius if r is below it).
    int level_of(double r) const {
        if (!(r < max_radius)) return 0;
        const int l = int(std::ceil(per_octave * std::log2(max_radius / r) - 1e-6));
        return std::min(std::max(l, 0), count() - 1);
    }
};

/// II normals at a per-surfel level; a negative level leaves the row at zero (not wanted). One
/// ball (six stencils) per level used.
PointMatrix normals_at_levels(const VoxelLabels& volume, const detail::RowRuns& rows, const DigitalSurface& surface,
                              const RadiusLevels& levels, const std::vector<int>& level, IntegralInvariantKernel kernel) {
    std::map<int, std::vector<std::int64_t>> faces_of_level;
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        if (level[std::size_t(f)] >= 0) faces_of_level[level[std::size_t(f)]].push_back(f);
    PointMatrix u = PointMatrix::Zero(surface.face_count(), 3);
    for (const auto& [l, faces] : faces_of_level) {
        const detail::IntegralInvariantBall ball(volume.grid().spacing, levels.radius(l), kernel);
        const std::int64_t n = std::int64_t(faces.size());
#pragma omp parallel for schedule(dynamic, 256)
        for (std::int64_t i = 0; i < n; ++i) {
            const std::int64_t f = faces[std::size_t(i)];
            const Surfel& s = surface.surfels[std::size_t(f)];
            u.row(f) = ball.normal(volume.grid().dims, rows, s, detail::run_label_at(rows, volume.grid().dims, s.voxel)).transpose();
        }
    }
    return u;
}

void check_options(const AdaptiveNormalOptions& o) {
    const auto positive = [](double r) { return r > 0 && std::isfinite(r); };
    if (!positive(o.max_radius) || !positive(o.min_radius))
        throw Error("adaptive normals: the radii must be positive and finite");
    if (o.min_radius > o.max_radius) throw Error("adaptive normals: the smallest radius exceeds the largest");
    if (!positive(o.reach_factor)) throw Error("adaptive normals: the reach factor must be positive and finite");
    if (!(o.reach_cap >= 0) || !std::isfinite(o.reach_cap)) throw Error("adaptive normals: the reach cap must be finite");
    if (o.levels_per_octave < 2) throw Error("adaptive normals: at least two radius levels per octave");
}

/// Where n(r) and n(r/√2) agree, n(r) plus the Richardson correction 2·(n(r/√2) − n(r)) shrunk
/// by the threshold (soft thresholding: a difference at the level of the digitization noise is
/// no evidence of bias); where they do not (a sharp edge, a part thinner than the ball), the
/// expansion n(r) = n0 + b·r² does not hold: n(r/√2).
Eigen::RowVector3d extrapolated_normal(const Eigen::RowVector3d& wide, const Eigen::RowVector3d& narrow,
                                       const AdaptiveNormalOptions& o) {
    if (wide.dot(narrow) < std::cos(o.extrapolation_agreement_deg * M_PI / 180.0)) return narrow;
    const Eigen::RowVector3d correction = 2.0 * (narrow - wide);
    const double size = correction.norm(), threshold = o.extrapolation_threshold_deg * M_PI / 180.0;
    return (wide + (size > threshold ? (size - threshold) / size : 0.0) * correction).normalized();
}

/// The extrapolated field where the radius allows (see extrapolated_normal); `pilot` is n(r/√2)
/// where r = max_radius.
void extrapolate_field(const VoxelLabels& volume, const detail::RowRuns& rows, const DigitalSurface& surface,
                       const RadiusLevels& levels, const std::vector<int>& level, const PointMatrix& pilot,
                       int pilot_level, const AdaptiveNormalOptions& o, AdaptiveNormalField& field) {
    const std::int64_t m = surface.face_count();
    const int half_octave = o.levels_per_octave / 2, last = levels.count() - 1;
    // The narrow field n(r/√2): the pilot where r = max_radius, computed where it is missing.
    std::vector<int> missing(static_cast<std::size_t>(m), -1);
    for (std::int64_t f = 0; f < m; ++f) {
        const int narrow = std::min(level[std::size_t(f)] + half_octave, last);
        if (field.radius[f] >= o.extrapolation_min_radius && narrow != pilot_level && narrow != level[std::size_t(f)])
            missing[std::size_t(f)] = narrow;
    }
    const PointMatrix extra = normals_at_levels(volume, rows, surface, levels, missing, o.kernel);
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        const int narrow = std::min(level[std::size_t(f)] + half_octave, last);
        if (field.radius[f] < o.extrapolation_min_radius || narrow == level[std::size_t(f)]) continue;
        const Eigen::RowVector3d n_narrow = missing[std::size_t(f)] >= 0 ? extra.row(f) : pilot.row(f);
        field.normals.row(f) = extrapolated_normal(field.normals.row(f), n_narrow, o);
        field.extrapolated[f] = 1;
    }
}

/// The level of each surfel: the radius reach_factor · (robust reach), at most the local
/// thickness of the object at the surfel's object voxel and of the background at its background
/// voxel where the robust reach limits the radius at all (a part thinner than max_radius around
/// the surfel; a voxel of noise on a thick part, thin itself, keeps the radius of its
/// surroundings). The raw reach is at most half of each thickness, so only where the radius
/// exceeds twice the raw reach (the rings raised it) is the thickness searched for.
std::vector<int> radius_levels(const VoxelLabels& volume, const DigitalSurface& surface, const ReachMaps& maps,
                               const SurfelReach& raw, const SurfelReach& robust, const RadiusLevels& levels,
                               const AdaptiveNormalOptions& o) {
    const std::int64_t m = surface.face_count();
    std::vector<int> level(static_cast<std::size_t>(m));
    const Eigen::VectorXd reach = robust.smallest(), safe = 2.0 * raw.smallest();
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < m; ++f) {
        int l = levels.level_of(o.reach_factor * reach[f]);
        const double r = levels.radius(l);
        if (r > safe[f] * (1 + 1e-9) && o.reach_factor * reach[f] < o.max_radius * (1 - 1e-9)) {  // round-off: no
            const Surfel& s = surface.surfels[std::size_t(f)];
            const Index3 v{s.voxel[0], s.voxel[1], s.voxel[2]};
            Index3 w = v;
            w[std::size_t(s.axis)] += s.sign;
            const double thickness = 2.0 * std::min(half_local_thickness(volume, maps, v, 0.5 * r),
                                                    half_local_thickness(volume, maps, w, 0.5 * r));
            l = std::max(l, levels.level_of(thickness));
        }
        level[std::size_t(f)] = l;
    }
    return level;
}

/// Steps of averaging each normal of `smooth` with its four edge-adjacent faces, a neighbour g
/// weighing max(0, u_f·u_g)^power (so that the field is not averaged across a sharp edge, nor
/// across the rim of a plate).
void smooth_field(const DigitalSurface& surface, PointMatrix& u, int steps, double power,
                  const std::vector<std::uint8_t>& smooth) {
    PointMatrix next = u;
    for (int step = 0; step < steps; ++step) {
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            if (!smooth[std::size_t(f)]) continue;
            Eigen::RowVector3d sum = u.row(f);
            for (int e = 0; e < 4; ++e) {
                const Eigen::RowVector3d g = u.row(surface.adjacent_face(f, e));
                sum += std::pow(std::max(0.0, g.dot(u.row(f))), power) * g;
            }
            next.row(f) = sum.normalized();
        }
        u = next;
    }
}

}  // namespace

AdaptiveNormalField adaptive_integral_invariant_normals(const VoxelLabels& volume, const DigitalSurface& surface,
                                                        const AdaptiveNormalOptions& o) {
    check_options(o);
    const detail::RowRuns rows = detail::build_part_runs(volume, surface);  // each face sums its own part
    const RadiusLevels levels{o.max_radius, o.min_radius, o.levels_per_octave};
    const std::int64_t m = surface.face_count();
    const int half_octave = o.levels_per_octave / 2;  // r/√2 is this many levels down (exactly for even counts)
    const int last = levels.count() - 1;

    // The first field, at the narrow radius of the thick parts: the reach rays follow it, and it
    // is n(r/√2) wherever the reach allows r = max_radius.
    const int pilot_level = std::min(half_octave, last);
    const PointMatrix pilot = normals_at_levels(volume, rows, surface, levels,
                                                std::vector<int>(static_cast<std::size_t>(m), pilot_level), o.kernel);
    AdaptiveNormalField field;
    field.reach_cap = std::max(o.reach_cap, o.max_radius / o.reach_factor + volume.grid().spacing.maxCoeff());
    auto kept = std::make_shared<const ReachMaps>(reach_maps(volume, std::max(field.reach_cap, 0.5 * o.max_radius)));
    const ReachMaps& maps = *kept;
    const SurfelReach raw = surfel_reach(volume, surface, pilot, maps);
    field.reach.inner = max_over_rings(surface, raw.inner, o.reach_rings);
    field.reach.outer = max_over_rings(surface, raw.outer, o.reach_rings);
    const std::vector<int> level = radius_levels(volume, surface, maps, raw, field.reach, levels, o);
    // Faces at the pilot's level have their normal already (the same ball, the same sums).
    std::vector<int> to_compute = level;
    for (int& l : to_compute)
        if (l == pilot_level) l = -1;
    field.normals = normals_at_levels(volume, rows, surface, levels, to_compute, o.kernel);
    for (std::int64_t f = 0; f < m; ++f)
        if (level[std::size_t(f)] == pilot_level) field.normals.row(f) = pilot.row(f);
    field.radius.resize(m);
    for (std::int64_t f = 0; f < m; ++f) field.radius[f] = levels.radius(level[std::size_t(f)]);
    field.extrapolated = Eigen::VectorXd::Zero(m);
    if (o.extrapolate) extrapolate_field(volume, rows, surface, levels, level, pilot, pilot_level, o, field);
    if (o.smoothing_steps > 0) {
        std::vector<std::uint8_t> smooth(static_cast<std::size_t>(m));
        for (std::int64_t f = 0; f < m; ++f) smooth[std::size_t(f)] = field.radius[f] < o.smoothing_below ? 1 : 0;
        smooth_field(surface, field.normals, o.smoothing_steps, o.smoothing_power, smooth);
    }
    if (o.keep_reach_maps) field.reach_maps = std::move(kept);
    return field;
}

}  // namespace dsreg
