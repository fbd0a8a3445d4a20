#include "dsreg/normals.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numeric>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// The object voxels of each row (j,k) as runs [first, last] of consecutive x indices:
/// memory proportional to the surface, not to the volume.
struct RowRuns {
    std::vector<std::int64_t> row_first;  ///< size ny·nz + 1, into `runs`
    std::vector<std::array<std::int32_t, 2>> runs;
};

RowRuns build_row_runs(const BinaryVolume& volume) {
    const auto& d = volume.grid.dims;
    const std::int64_t rows = d[1] * d[2];
    std::vector<std::vector<std::array<std::int32_t, 2>>> per_row(static_cast<std::size_t>(rows));
#pragma omp parallel for schedule(static)
    for (std::int64_t row = 0; row < rows; ++row) {
        const std::uint8_t* x = volume.mask.data() + row * d[0];
        auto& out = per_row[static_cast<std::size_t>(row)];
        for (std::int64_t i = 0; i < d[0]; ++i) {
            if (!x[i]) continue;
            std::int64_t last = i;
            while (last + 1 < d[0] && x[last + 1]) ++last;
            out.push_back({std::int32_t(i), std::int32_t(last)});
            i = last;
        }
    }
    RowRuns result;
    result.row_first.assign(static_cast<std::size_t>(rows + 1), 0);
    for (std::int64_t row = 0; row < rows; ++row)
        result.row_first[static_cast<std::size_t>(row + 1)] =
            result.row_first[static_cast<std::size_t>(row)] + static_cast<std::int64_t>(per_row[static_cast<std::size_t>(row)].size());
    result.runs.reserve(static_cast<std::size_t>(result.row_first.back()));
    for (const auto& r : per_row) result.runs.insert(result.runs.end(), r.begin(), r.end());
    return result;
}

/// Zeroth, first and second moments of a set of points, in coordinates relative to a centre.
struct Moments {
    double count = 0;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
};

/// Adds the voxel centres x = x0 + sx·i, i ∈ [lo, hi], of one row at offsets (dy, dz) from the
/// ball centre, using Σ1, Σi, Σi² in closed form.
void add_row_segment(Moments& m, std::int64_t lo, std::int64_t hi, double x0, double sx, double dy, double dz) {
    const double n = double(hi - lo + 1);
    const double sum_i = 0.5 * (double(lo) + double(hi)) * n;
    auto sum_sq = [](double k) { return k * (k + 1) * (2 * k + 1) / 6.0; };  // Σ_{i=0..k} i²
    const double sum_ii = sum_sq(double(hi)) - sum_sq(double(lo - 1));  // lo ≥ 0, sum_sq(−1) = 0
    const double sx_ = n * x0 + sx * sum_i;                                // Σ dx
    const double sxx = n * x0 * x0 + 2 * x0 * sx * sum_i + sx * sx * sum_ii;  // Σ dx²
    m.count += n;
    m.first += Eigen::Vector3d(sx_, n * dy, n * dz);
    m.second(0, 0) += sxx;
    m.second(1, 1) += n * dy * dy;
    m.second(2, 2) += n * dz * dz;
    m.second(0, 1) += dy * sx_;
    m.second(0, 2) += dz * sx_;
    m.second(1, 2) += n * dy * dz;
}

Moments ball_moments(const BinaryVolume& volume, const RowRuns& rows, const Eigen::Vector3d& c, double r) {
    const VoxelGrid& g = volume.grid;
    const Eigen::Vector3d& o = g.origin;
    const Eigen::Vector3d& s = g.spacing;
    auto index_range = [&](int axis, double centre, double half) {
        const std::int64_t lo = std::max<std::int64_t>(0, std::int64_t(std::ceil((centre - half - o[axis]) / s[axis])));
        const std::int64_t hi = std::min<std::int64_t>(g.dims[axis] - 1, std::int64_t(std::floor((centre + half - o[axis]) / s[axis])));
        return std::make_pair(lo, hi);
    };
    Moments m;
    const auto [k0, k1] = index_range(2, c.z(), r);
    for (std::int64_t k = k0; k <= k1; ++k) {
        const double dz = o.z() + s.z() * double(k) - c.z();
        const double rz = r * r - dz * dz;
        if (rz < 0) continue;
        const auto [j0, j1] = index_range(1, c.y(), std::sqrt(rz));
        for (std::int64_t j = j0; j <= j1; ++j) {
            const double dy = o.y() + s.y() * double(j) - c.y();
            const double ry = rz - dy * dy;
            if (ry < 0) continue;
            const auto [i0, i1] = index_range(0, c.x(), std::sqrt(ry));
            if (i0 > i1) continue;
            const std::int64_t row = j + g.dims[1] * k;
            for (std::int64_t q = rows.row_first[std::size_t(row)]; q < rows.row_first[std::size_t(row + 1)]; ++q) {
                const auto& run = rows.runs[std::size_t(q)];
                const std::int64_t lo = std::max<std::int64_t>(run[0], i0), hi = std::min<std::int64_t>(run[1], i1);
                if (lo <= hi) add_row_segment(m, lo, hi, o.x() - c.x(), s.x(), dy, dz);
            }
        }
    }
    return m;
}

/// Normal from the moments: smallest-eigenvalue eigenvector of the covariance, oriented from
/// the centroid towards the ball centre (falls back to `fallback` when the centroid is at c).
Eigen::Vector3d normal_from_moments(const Moments& m, const Eigen::Vector3d& fallback, double r) {
    if (m.count <= 0) return fallback;
    const Eigen::Vector3d mean = m.first / m.count;  // centroid − c
    Eigen::Matrix3d cov = m.second / m.count - mean * mean.transpose();
    cov = cov.selfadjointView<Eigen::Upper>();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Eigen::Vector3d n = eig.eigenvectors().col(0);
    const double outward = -mean.dot(n);
    const bool centroid_reliable = mean.norm() > 1e-9 * r;
    if ((centroid_reliable ? outward : fallback.dot(n)) < 0) n = -n;
    return n;
}

}  // namespace

PointMatrix trivial_normals(const DigitalSurface& surface) {
    PointMatrix u(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
    return u;
}

PointMatrix integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface, double radius) {
    if (!(radius > 0) || !std::isfinite(radius))
        throw Error("integral invariant radius must be positive and finite (got " + std::to_string(radius) + ")");
    const RowRuns rows = build_row_runs(volume);
    const PointMatrix centers = surfel_centers(surface);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Eigen::Vector3d c = centers.row(f).transpose();
        const Moments m = ball_moments(volume, rows, c, radius);
        u.row(f) = normal_from_moments(m, surface.surfels[std::size_t(f)].trivial_normal(), radius).transpose();
    }
    return u;
}

PointMatrix exact_normals(const ImplicitShape& shape, const DigitalSurface& surface) {
    const PointMatrix centers = surfel_centers(surface);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = true_normal(shape, closest_point(shape, centers.row(f).transpose())).transpose();
    return u;
}

}  // namespace dsreg
