// Integral-invariant normals (the paper's ref. [5]) by exact integer moment sums.
//
// For a surfel of voxel v with normal sign·e_a, the voxel centres inside the ball B_r(c) of its
// centre c = centre(v) + sign·(s_a/2)·e_a are, relative to v, the same lattice offsets
// (t, dj, dk) for every surfel of the same direction. So the ball is cut once per direction into
// rows {(dj, dk), t ∈ [t_lo, t_hi]} (a "stencil"), and each surfel sums the object voxels of each
// row over the row's runs of object voxels in closed form: integer sums of 1, t, t², exact,
// with no square root or rounding per surfel. Cost O(r²/h²) per surfel, memory ∝ surface.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"

namespace dsreg {

namespace {

/// The object voxels of each row (j,k) as runs [first, last] of consecutive x indices.
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
        result.row_first[std::size_t(row + 1)] = result.row_first[std::size_t(row)] + std::int64_t(per_row[std::size_t(row)].size());
    result.runs.reserve(static_cast<std::size_t>(result.row_first.back()));
    for (const auto& r : per_row) result.runs.insert(result.runs.end(), r.begin(), r.end());
    return result;
}

/// One row of a ball stencil: offsets (dj, dk) and the x offsets t ∈ [t_lo, t_hi] inside.
struct StencilRow {
    std::int32_t dj, dk, t_lo, t_hi;
};

/// Rows of lattice offsets whose voxel centre lies in B_r(c) for a surfel of direction
/// (axis, sign), c being offset by sign·s_axis/2 along the axis from its voxel's centre.
std::vector<StencilRow> ball_stencil(const Eigen::Vector3d& spacing, int axis, int sign, double r) {
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();  // c − centre(v)
    shift[axis] = 0.5 * sign * spacing[axis];
    auto range = [&](int d, double half) {  // integer offsets q with |q·s_d − shift_d| ≤ half
        return std::make_pair(std::int32_t(std::ceil((shift[d] - half) / spacing[d])),
                              std::int32_t(std::floor((shift[d] + half) / spacing[d])));
    };
    std::vector<StencilRow> rows;
    const auto [k0, k1] = range(2, r);
    for (std::int32_t dk = k0; dk <= k1; ++dk) {
        const double z = dk * spacing.z() - shift.z();
        if (z * z > r * r) continue;
        const auto [j0, j1] = range(1, std::sqrt(r * r - z * z));
        for (std::int32_t dj = j0; dj <= j1; ++dj) {
            const double y = dj * spacing.y() - shift.y();
            const double rest = r * r - z * z - y * y;
            if (rest < 0) continue;
            const auto [t0, t1] = range(0, std::sqrt(rest));
            if (t0 <= t1) rows.push_back({dj, dk, t0, t1});
        }
    }
    return rows;
}

/// Exact integer moments of the lattice offsets (t, dj, dk) of the object voxels in a ball.
struct LatticeMoments {
    std::int64_t n = 0;
    std::int64_t st = 0, sj = 0, sk = 0;                     // first moments
    std::int64_t stt = 0, sjj = 0, skk = 0, stj = 0, stk = 0, sjk = 0;  // second moments
};

inline std::int64_t sum_to(std::int64_t k) { return k * (k + 1) / 2; }                  // Σ_{t≤k} t, up to a constant
inline std::int64_t sum_sq_to(std::int64_t k) { return k * (k + 1) * (2 * k + 1) / 6; }  // Σ_{t≤k} t², idem

LatticeMoments ball_moments(const BinaryVolume& volume, const RowRuns& rows, const Surfel& s,
                            const std::vector<StencilRow>& stencil) {
    const auto& d = volume.grid.dims;
    const std::int64_t i0 = s.voxel[0], j0 = s.voxel[1], k0 = s.voxel[2];
    LatticeMoments m;
    for (const StencilRow& row : stencil) {
        const std::int64_t j = j0 + row.dj, k = k0 + row.dk;
        if (j < 0 || k < 0 || j >= d[1] || k >= d[2]) continue;
        const std::int64_t id = j + d[1] * k;
        std::int64_t n = 0, st = 0, stt = 0;
        for (std::int64_t q = rows.row_first[std::size_t(id)]; q < rows.row_first[std::size_t(id + 1)]; ++q) {
            const auto& run = rows.runs[std::size_t(q)];
            const std::int64_t lo = std::max<std::int64_t>(run[0] - i0, row.t_lo);
            const std::int64_t hi = std::min<std::int64_t>(run[1] - i0, row.t_hi);
            if (lo > hi) continue;
            n += hi - lo + 1;
            st += sum_to(hi) - sum_to(lo - 1);  // polynomial identities: valid for negative bounds too
            stt += sum_sq_to(hi) - sum_sq_to(lo - 1);
        }
        if (n == 0) continue;
        m.n += n;
        m.st += st;
        m.stt += stt;
        m.sj += n * row.dj;
        m.sk += n * row.dk;
        m.sjj += n * row.dj * row.dj;
        m.skk += n * row.dk * row.dk;
        m.sjk += n * row.dj * row.dk;
        m.stj += st * row.dj;
        m.stk += st * row.dk;
    }
    return m;
}

/// The normal: eigenvector of the smallest eigenvalue of the covariance of the physical voxel
/// centres (spacing ⊙ offsets), oriented from their centroid towards the surfel centre.
Eigen::Vector3d normal_from_moments(const LatticeMoments& m, const Surfel& s, const Eigen::Vector3d& spacing) {
    const Eigen::Vector3d fallback = s.trivial_normal();
    if (m.n == 0) return fallback;
    const double n = double(m.n);
    const Eigen::Vector3d mean(double(m.st) / n, double(m.sj) / n, double(m.sk) / n);  // lattice units
    Eigen::Matrix3d second;
    second << double(m.stt), double(m.stj), double(m.stk),  //
        double(m.stj), double(m.sjj), double(m.sjk),          //
        double(m.stk), double(m.sjk), double(m.skk);
    const Eigen::Matrix3d lattice_cov = second / n - mean * mean.transpose();
    const Eigen::Matrix3d cov = spacing.asDiagonal() * lattice_cov * spacing.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Eigen::Vector3d normal = eig.eigenvectors().col(0);
    // centroid − c, in physical units (c is half a voxel from the voxel centre along the axis).
    Eigen::Vector3d to_centroid = spacing.cwiseProduct(mean);
    to_centroid[s.axis] -= 0.5 * s.sign * spacing[s.axis];
    const double outward = -to_centroid.dot(normal);
    const bool centroid_reliable = to_centroid.norm() > 1e-9 * spacing.maxCoeff();
    if ((centroid_reliable ? outward : fallback.dot(normal)) < 0) normal = -normal;
    return normal;
}

}  // namespace

PointMatrix integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface, double radius) {
    if (!(radius > 0) || !std::isfinite(radius))
        throw Error("integral invariant radius must be positive and finite (got " + std::to_string(radius) + ")");
    const Eigen::Vector3d& spacing = volume.grid.spacing;
    if ((radius / spacing.array()).maxCoeff() > 2000)
        throw Error("integral invariant radius " + std::to_string(radius) + " spans more than 2000 voxels (integer moment sums would overflow)");
    const RowRuns rows = build_row_runs(volume);
    std::vector<StencilRow> stencils[3][2];
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) stencils[axis][side] = ball_stencil(spacing, axis, side ? 1 : -1, radius);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const LatticeMoments m = ball_moments(volume, rows, s, stencils[s.axis][s.sign > 0 ? 1 : 0]);
        u.row(f) = normal_from_moments(m, s, spacing).transpose();
    }
    return u;
}

}  // namespace dsreg
