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

/// II normals of the faces at up to two levels each, into `first` at first_level[f] and `second`
/// at second_level[f] (a negative level: not wanted; both wanted: first_level < second_level, the
/// larger ball first). One ball (six stencils) per level or pair of levels used; a face that wants
/// both has them from one pass over its larger ball's rows (NestedIntegralInvariantBalls).
void normals_at_levels(const VoxelLabels& volume, const detail::RowRuns& rows, const DigitalSurface& surface,
                       const RadiusLevels& levels, const std::vector<int>& first_level,
                       const std::vector<int>& second_level, IntegralInvariantKernel kernel, PointMatrix& first,
                       PointMatrix& second) {
    std::map<std::pair<int, int>, std::vector<std::int64_t>> faces_of_levels;
    for (int direction = 0; direction < 6; ++direction)  // faces of one direction together: one stencil's tables in cache
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            const Surfel& s = surface.surfels[std::size_t(f)];
            if (2 * s.axis + (s.sign > 0 ? 1 : 0) != direction) continue;
            const int a = first_level[std::size_t(f)], b = second_level[std::size_t(f)];
            if (a >= 0 || b >= 0) faces_of_levels[{a, b}].push_back(f);
        }
    const Index3& dims = volume.grid().dims;
    const Eigen::Vector3d& spacing = volume.grid().spacing;
    for (const auto& [pair, faces] : faces_of_levels) {
        const auto [a, b] = pair;
        const std::int64_t n = std::int64_t(faces.size());
        if (a >= 0 && b >= 0) {
            const detail::NestedIntegralInvariantBalls balls(spacing, levels.radius(a), levels.radius(b), kernel);
#pragma omp parallel for schedule(dynamic, 256)
            for (std::int64_t i = 0; i < n; ++i) {
                const std::int64_t f = faces[std::size_t(i)];
                const Surfel& s = surface.surfels[std::size_t(f)];
                const auto [n_first, n_second] = balls.normals(dims, rows, s, detail::run_label_at(rows, dims, s.voxel));
                first.row(f) = n_first.transpose();
                second.row(f) = n_second.transpose();
            }
            continue;
        }
        const detail::IntegralInvariantBall ball(spacing, levels.radius(std::max(a, b)), kernel);
        PointMatrix& out = a >= 0 ? first : second;
#pragma omp parallel for schedule(dynamic, 256)
        for (std::int64_t i = 0; i < n; ++i) {
            const std::int64_t f = faces[std::size_t(i)];
            const Surfel& s = surface.surfels[std::size_t(f)];
            out.row(f) = ball.normal(dims, rows, s, detail::run_label_at(rows, dims, s.voxel)).transpose();
        }
    }
}

void check_options(const AdaptiveNormalOptions& o) {
    const auto positive = [](double r) { return r > 0 && std::isfinite(r); };
    if (!positive(o.max_radius) || !positive(o.min_radius))
        throw Error("adaptive normals: the radii must be positive and finite");
    if (o.min_radius > o.max_radius) throw Error("adaptive normals: the smallest radius exceeds the largest");
    if (!positive(o.reach_factor)) throw Error("adaptive normals: the reach factor must be positive and finite");
    if (!(o.reach_cap >= 0) || !std::isfinite(o.reach_cap)) throw Error("adaptive normals: the reach cap must be finite");
    if (o.levels_per_octave < 2) throw Error("adaptive normals: at least two radius levels per octave");
    if (o.noisy_smoothing_steps < 0 || o.noisy_share_passes < 0 || !(o.noisy_share >= 0 && o.noisy_share <= 1))
        throw Error("adaptive normals: the noisy smoothing needs steps and passes >= 0 and a share in [0, 1]");
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

/// The level of the narrow field n(r/√2) that the extrapolation of face f needs, or −1 where it
/// does not extrapolate (r below extrapolation_min_radius, or r the smallest level already).
int narrow_level(const RadiusLevels& levels, int level, double radius, const AdaptiveNormalOptions& o) {
    const int narrow = std::min(level + o.levels_per_octave / 2, levels.count() - 1);
    return radius < o.extrapolation_min_radius || narrow == level ? -1 : narrow;
}

/// The extrapolated field where the radius allows (see extrapolated_normal): `narrow` holds
/// n(r/√2) of each face that extrapolates.
void extrapolate_field(const DigitalSurface& surface, const RadiusLevels& levels, const std::vector<int>& level,
                       const PointMatrix& narrow, const AdaptiveNormalOptions& o, AdaptiveNormalField& field) {
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        if (narrow_level(levels, level[std::size_t(f)], field.radius[f], o) < 0) continue;
        field.normals.row(f) = extrapolated_normal(field.normals.row(f), narrow.row(f), o);
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

/// A guess of the faces that get max_radius (a part thick on both sides), from the distance maps
/// alone: the voxels `depth` away along the face's axis, on either side, have the face's label of
/// that side and a distance to the other labels of at least depth/2 (a smooth thick surface is
/// within 55° of its axis). It decides which balls are summed together, not any normal.
std::vector<std::uint8_t> likely_thick(const VoxelLabels& volume, const DigitalSurface& surface, const ReachMaps& maps,
                                       double depth) {
    const std::int64_t m = surface.face_count();
    std::vector<std::uint8_t> thick(static_cast<std::size_t>(m), 0);
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < m; ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const FaceLabels labels = surface.face_labels.empty() ? FaceLabels{1, 0} : surface.face_labels[std::size_t(f)];
        const std::int64_t steps = std::int64_t(std::ceil(depth / volume.grid().spacing[s.axis]));
        const auto deep_enough = [&](std::int64_t offset, std::uint32_t label) {
            Index3 y = maps.map_voxel({s.voxel[0], s.voxel[1], s.voxel[2]});
            y[std::size_t(s.axis)] += offset;
            if (!maps.grid.contains(y[0], y[1], y[2])) return false;
            const Index3 v = maps.volume_voxel(y);
            const std::uint32_t here = volume.at(v[0], v[1], v[2]);
            return here == label && maps.at(y[0], y[1], y[2]) >= 0.5 * depth;
        };
        thick[std::size_t(f)] = deep_enough(-s.sign * steps, labels.inner) && deep_enough(s.sign * (steps + 1), labels.outer);
    }
    return thick;
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

/// Per face, the share of the faces around it that are in `against` (those whose normal points
/// against their surfel): the indicator averaged with the four edge-adjacent faces `passes` times.
Eigen::VectorXd share_against_surfels(const DigitalSurface& surface, const std::vector<std::int32_t>& against,
                                      int passes) {
    const std::int64_t m = surface.face_count();
    Eigen::VectorXd share = Eigen::VectorXd::Zero(m);
    for (const std::int32_t f : against) share[f] = 1;
    Eigen::VectorXd next(m);
    for (int pass = 0; pass < passes; ++pass) {
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < m; ++f) {
            double sum = share[f];
            for (int e = 0; e < 4; ++e) sum += share[surface.adjacent_face(f, e)];
            next[f] = sum / 5;
        }
        share.swap(next);
    }
    return share;
}

/// The smoothing of the thin parts' small balls (AdaptiveNormalOptions::smoothing_steps), then
/// the longer one of the noisy thin faces (noisy_smoothing_steps).
void smooth_thin_parts(const DigitalSurface& surface, const AdaptiveNormalOptions& o, AdaptiveNormalField& field) {
    const std::int64_t m = surface.face_count();
    std::vector<std::uint8_t> smooth(static_cast<std::size_t>(m));
    for (std::int64_t f = 0; f < m; ++f) smooth[std::size_t(f)] = field.radius[f] < o.smoothing_below ? 1 : 0;
    smooth_field(surface, field.normals, o.smoothing_steps, o.smoothing_power, smooth);
    if (o.noisy_smoothing_steps <= 0) return;
    const std::vector<std::int32_t> against = faces_against_their_surfels(surface, field.normals);
    if (against.empty()) return;  // a clean smooth object: no share to average
    const Eigen::VectorXd share = share_against_surfels(surface, against, o.noisy_share_passes);
    for (std::int64_t f = 0; f < m; ++f) {
        smooth[std::size_t(f)] = smooth[std::size_t(f)] && share[f] >= o.noisy_share ? 1 : 0;
        field.noisy_smoothed_faces += smooth[std::size_t(f)];
    }
    if (field.noisy_smoothed_faces > 0) smooth_field(surface, field.normals, o.noisy_smoothing_steps, o.smoothing_power, smooth);
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

    AdaptiveNormalField field;
    field.reach_cap = std::max(o.reach_cap, o.max_radius / o.reach_factor + volume.grid().spacing.maxCoeff());
    auto kept = std::make_shared<const ReachMaps>(reach_maps(volume, std::max(field.reach_cap, 0.5 * o.max_radius)));
    const ReachMaps& maps = *kept;
    // The first field, at the narrow radius of the thick parts: the reach rays follow it, and it
    // is n(r/√2) wherever the reach allows r = max_radius. Where that is likely, the field at
    // max_radius comes with it from the same pass over the rows.
    const int pilot_level = std::min(half_octave, last);
    const std::vector<std::uint8_t> thick = likely_thick(volume, surface, maps, o.max_radius / o.reach_factor);
    std::vector<int> wide_first(static_cast<std::size_t>(m), -1);
    for (std::int64_t f = 0; f < m; ++f)
        if (thick[std::size_t(f)] && pilot_level > 0) wide_first[std::size_t(f)] = 0;
    PointMatrix pilot(m, 3), normals(m, 3);
    normals_at_levels(volume, rows, surface, levels, wide_first, std::vector<int>(static_cast<std::size_t>(m), pilot_level),
                      o.kernel, normals, pilot);
    const SurfelReach raw = surfel_reach(volume, surface, pilot, maps);
    field.reach.inner = max_over_rings(surface, raw.inner, o.reach_rings);
    field.reach.outer = max_over_rings(surface, raw.outer, o.reach_rings);
    const std::vector<int> level = radius_levels(volume, surface, maps, raw, field.reach, levels, o);
    field.radius.resize(m);
    for (std::int64_t f = 0; f < m; ++f) field.radius[f] = levels.radius(level[std::size_t(f)]);
    // The faces at another level: their field, and with it the narrow field their extrapolation
    // needs (the pilot's where that is its level).
    std::vector<int> to_compute(static_cast<std::size_t>(m), -1), narrow_to_compute(static_cast<std::size_t>(m), -1);
    for (std::int64_t f = 0; f < m; ++f) {
        const int l = level[std::size_t(f)];
        if (l == pilot_level) normals.row(f) = pilot.row(f);
        else if (wide_first[std::size_t(f)] != l) to_compute[std::size_t(f)] = l;
        const int narrow = o.extrapolate ? narrow_level(levels, l, field.radius[f], o) : -1;
        if (narrow >= 0 && narrow != pilot_level) narrow_to_compute[std::size_t(f)] = narrow;
    }
    PointMatrix narrow = PointMatrix::Zero(m, 3);
    normals_at_levels(volume, rows, surface, levels, to_compute, narrow_to_compute, o.kernel, normals, narrow);
    for (std::int64_t f = 0; f < m; ++f)
        if (narrow_to_compute[std::size_t(f)] < 0) narrow.row(f) = pilot.row(f);  // where used, the pilot's level
    field.normals = std::move(normals);
    field.extrapolated = Eigen::VectorXd::Zero(m);
    if (o.extrapolate) extrapolate_field(surface, levels, level, narrow, o, field);
    smooth_thin_parts(surface, o, field);
    if (o.keep_reach_maps) field.reach_maps = std::move(kept);
    return field;
}

}  // namespace dsreg
