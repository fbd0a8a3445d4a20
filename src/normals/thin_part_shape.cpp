// Sheets against tubes: covariance of the thinner side's voxels in a ball around the medial
// point, summed over the voxel runs of each row (include/dsreg/thin_part_shape.hpp).
#include "dsreg/thin_part_shape.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/error.hpp"
#include "integral_invariant_sums.hpp"

namespace dsreg {

namespace {

/// Rows sampled per ball radius along y and z, at least: 4 gives the suite's figures of 6
/// (docs/accuracy.md, "Sheets and tubes") for 0.2 s less on a packed 100-label map at 128³.
constexpr double kRowsPerRadius = 4;

/// Sums Σ1, Σp, Σp·pᵀ of voxel centres p relative to a centre.
struct Moments {
    double count = 0;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();

    /// Adds the voxels i = first … last of one row, whose centres are at x = x0 + s·i and at
    /// (y, z) from the centre.
    void add_row(std::int64_t first_i, std::int64_t last_i, double x0, double s, double y, double z) {
        if (last_i < first_i) return;
        const double n = double(last_i - first_i + 1);
        const double a = double(first_i), b = double(last_i);
        const double sum_i = 0.5 * n * (a + b);
        const double sum_ii = (b * (b + 1) * (2 * b + 1) - (a - 1) * a * (2 * a - 1)) / 6.0;  // Σ_{i=a}^{b} i²
        const double sum_x = s * sum_i + n * x0, sum_xx = s * s * sum_ii + 2 * s * x0 * sum_i + n * x0 * x0;
        count += n;
        first += Eigen::Vector3d(sum_x, n * y, n * z);
        second(0, 0) += sum_xx;
        second(1, 1) += n * y * y;
        second(2, 2) += n * z * z;
        second(0, 1) += y * sum_x;
        second(0, 2) += z * sum_x;
        second(1, 2) += n * y * z;
    }

    /// Eigenvalues, ascending, of the covariance (zero if no voxel).
    Eigen::Vector3d covariance_eigenvalues() const {
        if (count < 1) return Eigen::Vector3d::Zero();
        const Eigen::Vector3d mean = first / count;
        Eigen::Matrix3d covariance = second.selfadjointView<Eigen::Upper>();
        covariance = covariance / count - mean * mean.transpose();
        return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues();
    }
};

/// The first index ≥ lo of the lattice through `anchor` with step `stride`.
std::int64_t first_on_lattice(std::int64_t lo, std::int64_t anchor, std::int64_t stride) {
    const std::int64_t steps = lo - anchor;
    return anchor + stride * (steps >= 0 ? (steps + stride - 1) / stride : -((-steps) / stride));
}

/// The moments of the centres of the voxels of `label` (label 0: every voxel that is in no run,
/// the outside of the grid included) in the ball B(centre, radius), physical units, over every
/// `stride`-th row along y and z through the centre's voxel (a uniform sample: the covariance of
/// a large ball needs no more than about kRowsPerRadius rows per radius).
Moments ball_moments(const VoxelGrid& grid, const detail::RowRuns& rows, std::uint32_t label,
                     const Eigen::Vector3d& centre, double radius, std::int64_t stride) {
    const Eigen::Vector3d& s = grid.spacing;
    const Eigen::Vector3d c = (centre - grid.origin).cwiseQuotient(s);  // index coordinates
    const double x0 = grid.origin.x() - centre.x();  // x of voxel i relative to the centre: x0 + s_x·i
    Moments all, labelled;
    const std::int64_t k_lo = std::int64_t(std::ceil(c.z() - radius / s.z()));
    const std::int64_t k_hi = std::int64_t(std::floor(c.z() + radius / s.z()));
    for (std::int64_t k = first_on_lattice(k_lo, std::llround(c.z()), stride); k <= k_hi; k += stride) {
        const double z = grid.origin.z() + s.z() * double(k) - centre.z();
        const double rz2 = radius * radius - z * z;
        if (rz2 < 0) continue;
        const double ry = std::sqrt(rz2);
        const std::int64_t j_lo = std::int64_t(std::ceil(c.y() - ry / s.y())), j_hi = std::int64_t(std::floor(c.y() + ry / s.y()));
        for (std::int64_t j = first_on_lattice(j_lo, std::llround(c.y()), stride); j <= j_hi; j += stride) {
            const double y = grid.origin.y() + s.y() * double(j) - centre.y();
            const double rx2 = rz2 - y * y;
            if (rx2 < 0) continue;
            const double rx = std::sqrt(rx2);
            const std::int64_t i_lo = std::int64_t(std::ceil(c.x() - rx / s.x())), i_hi = std::int64_t(std::floor(c.x() + rx / s.x()));
            if (label == 0) all.add_row(i_lo, i_hi, x0, s.x(), y, z);
            if (k < 0 || j < 0 || k >= grid.dims[2] || j >= grid.dims[1]) continue;
            const std::int64_t row = j + grid.dims[1] * k;
            const auto begin = rows.runs.begin() + rows.row_first[std::size_t(row)];
            const auto end = rows.runs.begin() + rows.row_first[std::size_t(row + 1)];
            // The first run that ends at or after i_lo; runs are sorted and disjoint.
            auto run = std::lower_bound(begin, end, i_lo, [](const std::array<std::int32_t, 2>& r, std::int64_t i) { return r[1] < i; });
            for (; run != end && (*run)[0] <= i_hi; ++run) {
                const std::uint32_t run_label = rows.labels[std::size_t(run - rows.runs.begin())];
                if (label != 0 && run_label != label) continue;
                labelled.add_row(std::max<std::int64_t>((*run)[0], i_lo), std::min<std::int64_t>((*run)[1], i_hi), x0, s.x(), y, z);
            }
        }
    }
    if (label != 0) return labelled;
    all.count -= labelled.count;  // the background: the ball less every labelled voxel
    all.first -= labelled.first;
    all.second -= labelled.second;
    return all;
}

double ramp(double value, double low, double high) { return std::clamp((value - low) / (high - low), 0.0, 1.0); }

void check(const DigitalSurface& surface, const PointMatrix& directions, const SurfelReach& reach, const SheetnessOptions& o) {
    const std::int64_t m = surface.face_count();
    if (directions.rows() != m || reach.inner.size() != m || reach.outer.size() != m)
        throw Error("thin_part_sheetness: one direction and one reach per surfel expected (" + std::to_string(m) +
                    " surfels, " + std::to_string(directions.rows()) + " directions, " +
                    std::to_string(reach.inner.size()) + " reaches)");
    const auto ratio = [](double r) { return r > 0 && r < 1; };
    if (!(o.ball_factor > 0) || !std::isfinite(o.ball_factor) || !ratio(o.tube_ratio) || !ratio(o.lump_ratio) ||
        !(o.ramp_width > 0) || !std::isfinite(o.ramp_width))
        throw Error("thin_part_sheetness: the ball factor and the ramp width must be positive, the ratios in (0, 1)");
}

}  // namespace

Eigen::VectorXd thin_part_sheetness(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                                    const SurfelReach& reach, double below, const SheetnessOptions& o) {
    check(surface, directions, reach, o);
    Eigen::VectorXd sheetness = Eigen::VectorXd::Zero(surface.face_count());
    const std::int64_t m = surface.face_count();
    const auto thin = [&](std::int64_t f) { return std::min(reach.inner[f], reach.outer[f]) < below; };
    std::int64_t thin_faces = 0;
    for (std::int64_t f = 0; f < m; ++f) thin_faces += thin(f) ? 1 : 0;
    if (thin_faces == 0) return sheetness;
    const detail::RowRuns rows = detail::build_row_runs(volume);
    const VoxelGrid& grid = volume.grid();
#pragma omp parallel for schedule(dynamic, 64)
    for (std::int64_t f = 0; f < m; ++f) {
        if (!thin(f)) continue;
        const Surfel& s = surface.surfels[std::size_t(f)];
        const FaceLabels labels = surface.face_labels.empty() ? FaceLabels{1, 0} : surface.face_labels[std::size_t(f)];
        const bool inner_side = reach.inner[f] <= reach.outer[f];
        const double rho = inner_side ? reach.inner[f] : reach.outer[f];
        Eigen::Vector3d c = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        c[s.axis] += 0.5 * s.sign * grid.spacing[s.axis];
        const Eigen::Vector3d u = directions.row(f).transpose();
        const Eigen::Vector3d medial = inner_side ? Eigen::Vector3d(c - rho * u) : Eigen::Vector3d(c + rho * u);
        const double radius = o.ball_factor * rho;
        const std::int64_t stride = std::max<std::int64_t>(1, std::int64_t(radius / (kRowsPerRadius * grid.spacing.maxCoeff())));
        const Eigen::Vector3d l = ball_moments(grid, rows, inner_side ? labels.inner : labels.outer, medial, radius, stride)
                                      .covariance_eigenvalues();
        if (!(l[2] > 0)) continue;
        const double spread = l[1] / l[2], flatness = l[1] > 0 ? l[0] / l[1] : 1.0;
        sheetness[f] = ramp(spread, o.tube_ratio, o.tube_ratio + o.ramp_width) *
                       (1.0 - ramp(flatness, o.lump_ratio - 0.5 * o.ramp_width, o.lump_ratio));
    }
    return sheetness;
}

}  // namespace dsreg
