// Integral-invariant normals (the paper's ref. [5]) by weighted moment sums along voxel rows.
//
// For a surfel of voxel v with normal sign·e_a, the voxel centres inside the ball B_r(c) of its
// centre c = centre(v) + sign·(s_a/2)·e_a are, relative to v, the same lattice offsets
// (t, dj, dk) for every surfel of the same direction. So the ball is cut once per direction into
// rows {(dj, dk), t ∈ [t_lo, t_hi]} (a "stencil") that carry the running sums of w, w·t, w·t²
// of the kernel weight w; each surfel then sums each row over its runs of object voxels with
// two table look-ups per run. Cost O(r²/h²) per surfel; memory ∝ surface + O(r³/h³) tables.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "../common/disjoint_sets.hpp"
#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "integral_invariant_sums.hpp"

namespace dsreg {

namespace detail {

RowRuns build_row_runs(const VoxelLabels& volume) {
    const Index3& d = volume.grid().dims;
    const std::int64_t rows = d[1] * d[2];
    std::vector<std::vector<std::array<std::int32_t, 2>>> per_row(static_cast<std::size_t>(rows));
    std::vector<std::vector<std::uint32_t>> per_row_labels(static_cast<std::size_t>(rows));
#pragma omp parallel for schedule(static)
    for (std::int64_t row = 0; row < rows; ++row) {
        auto& out = per_row[static_cast<std::size_t>(row)];
        auto& out_labels = per_row_labels[static_cast<std::size_t>(row)];
        const std::int64_t first = row * d[0];
        for (std::int64_t i = 0; i < d[0]; ++i) {
            const std::uint32_t label = volume.at_linear(first + i);
            if (label == 0) continue;
            std::int64_t last = i;
            while (last + 1 < d[0] && volume.at_linear(first + last + 1) == label) ++last;
            out.push_back({std::int32_t(i), std::int32_t(last)});
            out_labels.push_back(label);
            i = last;
        }
    }
    RowRuns result;
    result.row_first.assign(static_cast<std::size_t>(rows + 1), 0);
    for (std::int64_t row = 0; row < rows; ++row)
        result.row_first[std::size_t(row + 1)] = result.row_first[std::size_t(row)] + std::int64_t(per_row[std::size_t(row)].size());
    result.runs.reserve(static_cast<std::size_t>(result.row_first.back()));
    result.labels.reserve(static_cast<std::size_t>(result.row_first.back()));
    for (std::size_t row = 0; row < per_row.size(); ++row) {
        result.runs.insert(result.runs.end(), per_row[row].begin(), per_row[row].end());
        result.labels.insert(result.labels.end(), per_row_labels[row].begin(), per_row_labels[row].end());
    }
    return result;
}

namespace {

/// Unites the runs of row `id` with those of row `other` that have the same label and share an x
/// (6-adjacent voxels, the rows being adjacent); both rows' runs are sorted.
void unite_adjacent_rows(const RowRuns& rows, std::int64_t id, std::int64_t other, DisjointSets<>& sets) {
    std::int64_t q = rows.row_first[std::size_t(id)], r = rows.row_first[std::size_t(other)];
    const std::int64_t q_end = rows.row_first[std::size_t(id + 1)], r_end = rows.row_first[std::size_t(other + 1)];
    while (q < q_end && r < r_end) {
        const auto& a = rows.runs[std::size_t(q)];
        const auto& b = rows.runs[std::size_t(r)];
        if (a[0] <= b[1] && b[0] <= a[1] && rows.labels[std::size_t(q)] == rows.labels[std::size_t(r)]) sets.unite(q, r);
        if (a[1] < b[1]) ++q;
        else ++r;
    }
}

/// The index of the run that holds voxel v, or −1.
std::int64_t run_at(const RowRuns& rows, const Index3& dims, const std::array<std::int32_t, 3>& v) {
    const std::int64_t id = v[1] + dims[1] * std::int64_t(v[2]);
    const auto begin = rows.runs.begin() + rows.row_first[std::size_t(id)];
    const auto end = rows.runs.begin() + rows.row_first[std::size_t(id + 1)];
    const auto run = std::lower_bound(begin, end, v[0], [](const std::array<std::int32_t, 2>& r, std::int32_t i) { return r[1] < i; });
    return run == end || (*run)[0] > v[0] ? -1 : std::int64_t(run - rows.runs.begin());
}

}  // namespace

RowRuns build_part_runs(const VoxelLabels& volume, const DigitalSurface& surface) {
    RowRuns rows = build_row_runs(volume);
    const Index3& d = volume.grid().dims;
    DisjointSets<> sets(rows.runs.size());
    // Voxels of one label sharing a face are one part whatever the connectivity.
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j) {
            const std::int64_t id = j + d[1] * k;
            if (j > 0) unite_adjacent_rows(rows, id, id - 1, sets);
            if (k > 0) unite_adjacent_rows(rows, id, id - d[1], sets);
        }
    // Voxels touching along an edge or at a corner are one part where the surface joins them
    // (the connectivity, less the pinches it keeps apart): their faces share a vertex. The
    // faces of one label around a vertex are those of one umbrella of that label.
    std::vector<std::int64_t> first_run(std::size_t(surface.vertex_count()), -1);
    std::vector<std::pair<std::int64_t, std::int64_t>> other_label;  // (vertex, run) where labels meet
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const std::int64_t q = run_at(rows, d, surface.surfels[std::size_t(f)].voxel);
        if (q < 0) throw Error("integral invariants: the surface does not belong to the volume");
        for (int c = 0; c < 4; ++c) {
            const std::int64_t v = surface.quads(f, c);
            std::int64_t& first = first_run[std::size_t(v)];
            if (first < 0) first = q;
            else if (rows.labels[std::size_t(first)] == rows.labels[std::size_t(q)]) sets.unite(first, q);
            else other_label.emplace_back(v, q);
        }
    }
    std::sort(other_label.begin(), other_label.end(), [&](const auto& a, const auto& b) {
        return std::make_pair(a.first, rows.labels[std::size_t(a.second)]) < std::make_pair(b.first, rows.labels[std::size_t(b.second)]);
    });
    for (std::size_t i = 1; i < other_label.size(); ++i)
        if (other_label[i].first == other_label[i - 1].first &&
            rows.labels[std::size_t(other_label[i].second)] == rows.labels[std::size_t(other_label[i - 1].second)])
            sets.unite(other_label[i].second, other_label[i - 1].second);
    std::vector<std::uint32_t> part(rows.runs.size(), 0);
    std::uint32_t parts = 0;
    for (std::size_t q = 0; q < part.size(); ++q) {
        const std::int64_t root = sets.find(std::int64_t(q));
        part[q] = std::int64_t(q) == root ? ++parts : part[std::size_t(root)];  // a root precedes its set
    }
    rows.labels = std::move(part);
    return rows;
}

std::uint32_t run_label_at(const RowRuns& rows, const Index3& dims, const std::array<std::int32_t, 3>& v) {
    const std::int64_t q = run_at(rows, dims, v);
    return q < 0 ? 0 : rows.labels[std::size_t(q)];
}

}  // namespace detail

namespace {

using detail::RowRuns;
using detail::RowSums;
using detail::Stencil;
using detail::StencilRow;

/// The kernel weight of a voxel centre at squared distance d2 (in units of r²) from the ball
/// centre, d2 ≤ 1.
double kernel_weight(IntegralInvariantKernel kernel, double d2) {
    if (kernel == IntegralInvariantKernel::ball) return 1.0;
    const double q = 1.0 - d2;  // biweight (1 − |x−c|²/r²)²: continuous, zero on the sphere
    return q * q;
}

/// Rows of lattice offsets whose voxel centre lies in B_r(c) for a surfel of direction
/// (axis, sign), c being offset by sign·s_axis/2 along the axis from its voxel's centre, with
/// the running sums of each row's kernel weights.
Stencil ball_stencil(const Eigen::Vector3d& spacing, int axis, int sign, double r, IntegralInvariantKernel kernel) {
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();  // c − centre(v)
    shift[axis] = 0.5 * sign * spacing[axis];
    auto range = [&](int d, double half) {  // integer offsets q with |q·s_d − shift_d| ≤ half
        return std::make_pair(std::int32_t(std::ceil((shift[d] - half) / spacing[d])),
                              std::int32_t(std::floor((shift[d] + half) / spacing[d])));
    };
    Stencil stencil;
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
            if (t0 > t1) continue;
            const std::int64_t first = std::int64_t(stencil.prefix_sums.size());
            RowSums sum;
            stencil.prefix_sums.push_back(sum);
            for (std::int32_t t = t0; t <= t1; ++t) {
                const double x = t * spacing.x() - shift.x();
                const double w = kernel_weight(kernel, std::min(1.0, (x * x + y * y + z * z) / (r * r)));
                sum.w += w;
                sum.wt += w * t;
                sum.wtt += w * double(t) * t;
                stencil.prefix_sums.push_back(sum);
            }
            stencil.rows.push_back({dj, dk, t0, t1, first, sum});
        }
    }
    return stencil;
}

/// Weighted moments of the lattice offsets (t, dj, dk) of the object voxels in a ball.
struct LatticeMoments {
    double n = 0;
    double st = 0, sj = 0, sk = 0;                            // first moments
    double stt = 0, sjj = 0, skk = 0, stj = 0, stk = 0, sjk = 0;  // second moments
};

/// Adds the part [lo, hi] (offsets from the surfel's voxel) of a run to the sums of one stencil
/// row, where it meets the row's range.
inline void add_run(const StencilRow& row, const RowSums* prefix, std::int64_t lo, std::int64_t hi, RowSums& sum) {
    lo = std::max<std::int64_t>(lo, row.t_lo);
    hi = std::min<std::int64_t>(hi, row.t_hi);
    if (lo > hi) return;
    const RowSums& b = hi == row.t_hi ? row.total : prefix[hi - row.t_lo + 1];
    if (lo == row.t_lo) {  // prefix[0] = 0: b − 0 is b, to the bit
        sum.w += b.w;
        sum.wt += b.wt;
        sum.wtt += b.wtt;
        return;
    }
    const RowSums& a = prefix[lo - row.t_lo];
    sum.w += b.w - a.w;
    sum.wt += b.wt - a.wt;
    sum.wtt += b.wtt - a.wtt;
}

/// Adds a row's sums, at offsets (dj, dk), to the moments.
inline void add_row(const StencilRow& row, const RowSums& sum, LatticeMoments& m) {
    if (sum.w == 0) return;
    m.n += sum.w;
    m.st += sum.wt;
    m.stt += sum.wtt;
    m.sj += sum.w * row.dj;
    m.sk += sum.w * row.dk;
    m.sjj += sum.w * row.dj * row.dj;
    m.skk += sum.w * row.dk * row.dk;
    m.sjk += sum.w * row.dj * row.dk;
    m.stj += sum.wt * row.dj;
    m.stk += sum.wt * row.dk;
}

/// The runs of grid row (j0 + row.dj, k0 + row.dk) as indices [first, last) into rows.runs, or
/// false if the row is outside the grid.
inline bool row_runs(const Index3& d, const RowRuns& rows, std::int64_t j0, std::int64_t k0, const StencilRow& row,
                     std::int64_t& first, std::int64_t& last) {
    const std::int64_t j = j0 + row.dj, k = k0 + row.dk;
    if (j < 0 || k < 0 || j >= d[1] || k >= d[2]) return false;
    const std::int64_t id = j + d[1] * k;
    first = rows.row_first[std::size_t(id)];
    last = rows.row_first[std::size_t(id + 1)];
    return true;
}

/// Calls add(lo, hi) with the x offsets from i0 of each run of `label` among runs [first, last)
/// of a row that may meet the stencil row's range (runs in x order: the scan stops at the first
/// run beyond t_hi).
template <class Add>
inline void for_each_run(const RowRuns& rows, std::int64_t first, std::int64_t last, std::int64_t i0,
                         std::int32_t t_hi, std::uint32_t label, Add&& add) {
    for (std::int64_t q = first; q < last; ++q) {
        const auto& run = rows.runs[std::size_t(q)];
        if (run[0] - i0 > t_hi) break;
        if (rows.labels[std::size_t(q)] != label) continue;
        add(run[0] - i0, run[1] - i0);
    }
}

/// The moments of the voxels of `label` in the ball of surfel s.
LatticeMoments ball_moments(const Index3& d, const RowRuns& rows, const Surfel& s, std::uint32_t label,
                            const Stencil& stencil) {
    const std::int64_t i0 = s.voxel[0];
    LatticeMoments m;
    for (const StencilRow& row : stencil.rows) {
        std::int64_t first, last;
        if (!row_runs(d, rows, s.voxel[1], s.voxel[2], row, first, last)) continue;
        const RowSums* prefix = stencil.prefix_sums.data() + row.prefix;
        RowSums sum;
        for_each_run(rows, first, last, i0, row.t_hi, label,
                     [&](std::int64_t lo, std::int64_t hi) { add_run(row, prefix, lo, hi, sum); });
        add_row(row, sum, m);
    }
    return m;
}

/// The moments of two concentric balls in one pass over the outer stencil's rows (ball_moments of
/// each, the same sums in the same order): `inner_row_of` maps an outer row to the inner row of
/// the same (dj, dk), or −1; the inner rows' t ranges lie within the outer ones'.
std::pair<LatticeMoments, LatticeMoments> nested_ball_moments(const Index3& d, const RowRuns& rows, const Surfel& s,
                                                              std::uint32_t label, const Stencil& outer,
                                                              const Stencil& inner,
                                                              const std::vector<std::int32_t>& inner_row_of) {
    const std::int64_t i0 = s.voxel[0];
    LatticeMoments m_outer, m_inner;
    for (std::size_t r = 0; r < outer.rows.size(); ++r) {
        const StencilRow& row = outer.rows[r];
        std::int64_t first, last;
        if (!row_runs(d, rows, s.voxel[1], s.voxel[2], row, first, last)) continue;
        const RowSums* prefix = outer.prefix_sums.data() + row.prefix;
        const std::int32_t r_inner = inner_row_of[r];
        RowSums sum;
        if (r_inner < 0) {
            for_each_run(rows, first, last, i0, row.t_hi, label,
                         [&](std::int64_t lo, std::int64_t hi) { add_run(row, prefix, lo, hi, sum); });
            add_row(row, sum, m_outer);
            continue;
        }
        const StencilRow& row_inner = inner.rows[std::size_t(r_inner)];
        const RowSums* prefix_inner = inner.prefix_sums.data() + row_inner.prefix;
        RowSums sum_inner;
        for_each_run(rows, first, last, i0, row.t_hi, label, [&](std::int64_t lo, std::int64_t hi) {
            add_run(row, prefix, lo, hi, sum);
            add_run(row_inner, prefix_inner, lo, hi, sum_inner);
        });
        add_row(row, sum, m_outer);
        add_row(row_inner, sum_inner, m_inner);
    }
    return {m_outer, m_inner};
}

/// Below this relative gap (λ2 − λ1)/λ2 between the two smallest eigenvalues of the covariance,
/// its eigenvector of λ1 is blended with the centroid direction (normal_from_moments). A half
/// ball has 0.70 (λ1 = 0.059 r², λ2 = r²/5); a wire, a bar or a voxel of debris thinner than the
/// ball across two directions has 0: its cross-section is whole in the ball. 0.1 by the accuracy
/// suite (docs/accuracy.md, "Parts thinner than the ball"): 0.25 gives leopold h = 0.5 better
/// normals but 0.5 % of its voxel centres on the wrong side.
constexpr double kEigenGapRamp = 0.1;

/// The normal: eigenvector of the smallest eigenvalue of the covariance of the physical voxel
/// centres (spacing ⊙ offsets), oriented from their centroid towards the surfel centre. Where the
/// object is thinner than the ball across two directions (λ1 ≈ λ2), that eigenvector is any
/// direction of their plane (an isolated voxel's y face got +x, and a thin tube's normals were
/// over 20° off with a ball across it): there the direction from the centroid to the surfel
/// centre is the estimator — radial on a wire, a bar or a tube, a face's own axis on an isolated
/// voxel. The two are blended linearly over the relative gap (λ2 − λ1)/λ2 in [0, kEigenGapRamp],
/// so that the field stays continuous; above it the eigenvector alone.
Eigen::Vector3d normal_from_moments(const LatticeMoments& m, const Surfel& s, const Eigen::Vector3d& spacing) {
    const Eigen::Vector3d fallback = s.trivial_normal();
    if (!(m.n > 0)) return fallback;
    const double n = m.n;
    const Eigen::Vector3d mean(m.st / n, m.sj / n, m.sk / n);  // lattice units
    Eigen::Matrix3d second;
    second << m.stt, m.stj, m.stk,  //
        m.stj, m.sjj, m.sjk,          //
        m.stk, m.sjk, m.skk;
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
    const Eigen::Vector3d l = eig.eigenvalues();  // ascending
    const double gap = l[1] > 1e-12 * spacing.squaredNorm() ? (l[1] - l[0]) / l[1] : 0.0;
    if (gap < kEigenGapRamp) {
        const Eigen::Vector3d centroid_direction = centroid_reliable ? Eigen::Vector3d(-to_centroid.normalized()) : fallback;
        const double w = gap / kEigenGapRamp;
        const Eigen::Vector3d blended = w * normal + (1 - w) * centroid_direction;
        if (blended.norm() > 1e-9) normal = blended.normalized();
    }
    return normal;
}

/// Entries of the six stencils' row tables for a ball of `radius` (an upper bound, before any
/// allocation): about 4/3·π·r³ voxels plus one entry per row, per direction.
double stencil_table_entries(const Eigen::Vector3d& spacing, double radius) {
    const Eigen::Vector3d reach = (radius / spacing.array() + 1.0).matrix();
    return 6.0 * (4.0 / 3.0 * M_PI * reach.prod() + M_PI * reach.y() * reach.z());
}

}  // namespace

std::string kernel_name(IntegralInvariantKernel kernel) {
    return kernel == IntegralInvariantKernel::ball ? "ball" : "biweight";
}

IntegralInvariantKernel parse_integral_invariant_kernel(const std::string& name) {
    if (name == "ball") return IntegralInvariantKernel::ball;
    if (name == "biweight") return IntegralInvariantKernel::biweight;
    throw Error("unknown integral-invariant kernel '" + name + "' (expected ball or biweight)");
}

namespace detail {

IntegralInvariantBall::IntegralInvariantBall(const Eigen::Vector3d& spacing, double radius, IntegralInvariantKernel kernel)
    : spacing_(spacing), radius_(radius) {
    if (!(radius > 0) || !std::isfinite(radius))
        throw Error("integral invariant radius must be positive and finite (got " + std::to_string(radius) + ")");
    constexpr double max_table_entries = double(1 << 25);  // 768 MiB of row sums
    if (stencil_table_entries(spacing, radius) > max_table_entries)
        throw Error("integral invariant radius " + std::to_string(radius) + " spans " +
                    std::to_string(std::lround((radius / spacing.array()).maxCoeff())) +
                    " voxels: its ball tables would exceed 768 MiB (use a radius below about 100 voxels)");
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            stencils_[axis][side] = ball_stencil(spacing, axis, side ? 1 : -1, radius, kernel);
}

Eigen::Vector3d IntegralInvariantBall::normal(const Index3& dims, const RowRuns& rows, const Surfel& s,
                                              std::uint32_t label) const {
    const LatticeMoments m = ball_moments(dims, rows, s, label, stencil(s));
    return normal_from_moments(m, s, spacing_);
}

NestedIntegralInvariantBalls::NestedIntegralInvariantBalls(const Eigen::Vector3d& spacing, double outer_radius,
                                                           double inner_radius, IntegralInvariantKernel kernel)
    : outer_(spacing, outer_radius, kernel), inner_(spacing, inner_radius, kernel) {
    if (!(inner_radius < outer_radius)) throw Error("nested integral-invariant balls: the inner radius must be the smaller");
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const Stencil& outer = outer_.stencils_[axis][side];
            const Stencil& inner = inner_.stencils_[axis][side];
            std::vector<std::int32_t>& map = inner_row_of_[axis][side];
            map.assign(outer.rows.size(), -1);
            // Both stencils list their rows by (dk, dj) ascending: one merge.
            std::size_t q = 0;
            for (std::size_t r = 0; r < outer.rows.size() && q < inner.rows.size(); ++r) {
                const StencilRow& a = outer.rows[r];
                const StencilRow& b = inner.rows[q];
                if (a.dk != b.dk || a.dj != b.dj) continue;
                if (b.t_lo < a.t_lo || b.t_hi > a.t_hi) throw Error("nested integral-invariant balls: rows not nested");
                map[r] = std::int32_t(q++);
            }
            if (q != inner.rows.size()) throw Error("nested integral-invariant balls: rows not nested");
        }
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> NestedIntegralInvariantBalls::normals(const Index3& dims,
                                                                                  const RowRuns& rows, const Surfel& s,
                                                                                  std::uint32_t label) const {
    const int side = s.sign > 0 ? 1 : 0;
    const auto [outer, inner] =
        nested_ball_moments(dims, rows, s, label, outer_.stencil(s), inner_.stencil(s), inner_row_of_[s.axis][side]);
    return {normal_from_moments(outer, s, outer_.spacing_), normal_from_moments(inner, s, inner_.spacing_)};
}

}  // namespace detail

namespace {

/// The field for one radius, from row runs built once by the caller: each face gets the normal
/// of the indicator of its own part of its inner label (the object of a binary volume), from runs
/// by part (build_part_runs).
PointMatrix normals_from_runs(const VoxelGrid& grid, const RowRuns& rows, const DigitalSurface& surface,
                              double radius, IntegralInvariantKernel kernel) {
    const detail::IntegralInvariantBall ball(grid.spacing, radius, kernel);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = ball.normal(grid.dims, rows, surface.surfels[std::size_t(f)],
                               detail::run_label_at(rows, grid.dims, surface.surfels[std::size_t(f)].voxel))
                       .transpose();
    return u;
}

}  // namespace

namespace {

/// A label map's complex must say which label each face bounds (a binary surface may leave it
/// empty: its faces all bound the object, label 1).
void check_surface_labels(const DigitalSurface& surface) {
    if (std::int64_t(surface.face_labels.size()) != surface.face_count())
        throw Error("integral invariants: the surface has no face labels (it was not made by extract_digital_surface)");
}

PointMatrix extrapolated_from_runs(const VoxelGrid& grid, const RowRuns& rows, const DigitalSurface& surface,
                                   double radius, IntegralInvariantKernel kernel) {
    // n(r) = n0 + b·r² + O(r⁴) (b: the curvature variation across the ball), so with
    // r' = r/√2, 2·n(r') − n(r) = n0 + O(r⁴): Richardson extrapolation to r = 0.
    const detail::NestedIntegralInvariantBalls balls(grid.spacing, radius, radius / std::sqrt(2.0), kernel);
    PointMatrix wide(surface.face_count(), 3), narrow(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const auto [n_wide, n_narrow] = balls.normals(grid.dims, rows, s, detail::run_label_at(rows, grid.dims, s.voxel));
        wide.row(f) = n_wide.transpose();
        narrow.row(f) = n_narrow.transpose();
    }
    const double agreement = std::cos(30.0 * M_PI / 180.0);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        // Where the two scales disagree (a sharp edge, a thin part) the expansion does not hold:
        // keep the narrow estimate.
        if (wide.row(f).dot(narrow.row(f)) < agreement) {
            u.row(f) = narrow.row(f);
            continue;
        }
        u.row(f) = (2.0 * narrow.row(f) - wide.row(f)).normalized();
    }
    return u;
}

}  // namespace

namespace {

/// Whether the ball of surfel s (its stencil rows) holds a voxel whose label is neither `a` nor
/// `b`: a run of another label, or background (a gap in a row, or a row leaving the grid) when
/// neither is the background.
bool ball_holds_third_label(const Index3& d, const RowRuns& rows, const Surfel& s, std::uint32_t a, std::uint32_t b,
                            const Stencil& stencil) {
    const bool background_is_own = a == 0 || b == 0;
    const std::int64_t i0 = s.voxel[0], j0 = s.voxel[1], k0 = s.voxel[2];
    for (const StencilRow& row : stencil.rows) {
        const std::int64_t j = j0 + row.dj, k = k0 + row.dk;
        const std::int64_t lo = i0 + row.t_lo, hi = i0 + row.t_hi;
        if (j < 0 || k < 0 || j >= d[1] || k >= d[2] || lo < 0 || hi >= d[0]) {
            if (!background_is_own) return true;
            if (j < 0 || k < 0 || j >= d[1] || k >= d[2]) continue;
        }
        const std::int64_t id = j + d[1] * k;
        std::int64_t covered_to = std::max<std::int64_t>(lo, 0);  // first x not yet seen covered
        for (std::int64_t q = rows.row_first[std::size_t(id)]; q < rows.row_first[std::size_t(id + 1)]; ++q) {
            const auto& run = rows.runs[std::size_t(q)];
            if (run[1] < lo) continue;
            if (run[0] > hi) break;
            const std::uint32_t label = rows.labels[std::size_t(q)];
            if (label != a && label != b) return true;
            if (run[0] > covered_to && !background_is_own) return true;  // a background gap
            covered_to = std::max<std::int64_t>(covered_to, std::int64_t(run[1]) + 1);
        }
        if (covered_to <= std::min<std::int64_t>(hi, d[0] - 1) && !background_is_own) return true;
    }
    return false;
}

}  // namespace

std::vector<char> faces_near_junctions(const LabelVolume& volume, const DigitalSurface& surface, double radius) {
    check_surface_labels(surface);
    if (!(radius > 0) || !std::isfinite(radius))
        throw Error("junction radius must be positive and finite (got " + std::to_string(radius) + ")");
    std::vector<char> near(static_cast<std::size_t>(surface.face_count()), 0);
    if (volume.label_count() <= 2) return near;  // a binary label map has no third label
    const RowRuns rows = detail::build_row_runs(volume);
    Stencil stencils[3][2];
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            stencils[axis][side] = ball_stencil(volume.grid.spacing, axis, side ? 1 : -1, radius, IntegralInvariantKernel::ball);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const FaceLabels& l = surface.face_labels[std::size_t(f)];
        near[std::size_t(f)] =
            ball_holds_third_label(volume.grid.dims, rows, s, l.inner, l.outer, stencils[s.axis][s.sign > 0 ? 1 : 0]) ? 1 : 0;
    }
    return near;
}

PointMatrix integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface, double radius,
                                       IntegralInvariantKernel kernel) {
    return normals_from_runs(volume.grid, detail::build_part_runs(volume, surface), surface, radius, kernel);
}

PointMatrix integral_invariant_normals(const LabelVolume& volume, const DigitalSurface& surface, double radius,
                                       IntegralInvariantKernel kernel) {
    check_surface_labels(surface);
    return normals_from_runs(volume.grid, detail::build_part_runs(volume, surface), surface, radius, kernel);  // one pass, all labels
}

PointMatrix extrapolated_integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface,
                                                    double radius, IntegralInvariantKernel kernel) {
    return extrapolated_from_runs(volume.grid, detail::build_part_runs(volume, surface), surface, radius, kernel);  // runs once for both radii
}

PointMatrix extrapolated_integral_invariant_normals(const LabelVolume& volume, const DigitalSurface& surface,
                                                    double radius, IntegralInvariantKernel kernel) {
    check_surface_labels(surface);
    return extrapolated_from_runs(volume.grid, detail::build_part_runs(volume, surface), surface, radius, kernel);
}

}  // namespace dsreg
