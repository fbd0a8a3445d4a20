#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>

#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "../src/normals/integral_invariant_sums.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

/// The part of each object voxel (index i + nx·(j + ny·k); −1 outside the object) as the surface
/// joins them, voxel by voxel: voxels sharing a face, and the voxels of faces sharing a vertex.
std::vector<std::int64_t> voxel_parts(const BinaryVolume& v, const DigitalSurface& s) {
    const Index3& d = v.grid.dims;
    const auto index = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + d[0] * (j + d[1] * k); };
    std::vector<std::int64_t> parent(std::size_t(d[0] * d[1] * d[2]));
    std::iota(parent.begin(), parent.end(), std::int64_t(0));
    const std::function<std::int64_t(std::int64_t)> find = [&](std::int64_t x) {
        return parent[std::size_t(x)] == x ? x : parent[std::size_t(x)] = find(parent[std::size_t(x)]);
    };
    const auto unite = [&](std::int64_t a, std::int64_t b) { parent[std::size_t(find(a))] = find(b); };
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                if (!v.inside(i, j, k)) continue;
                if (i + 1 < d[0] && v.inside(i + 1, j, k)) unite(index(i, j, k), index(i + 1, j, k));
                if (j + 1 < d[1] && v.inside(i, j + 1, k)) unite(index(i, j, k), index(i, j + 1, k));
                if (k + 1 < d[2] && v.inside(i, j, k + 1)) unite(index(i, j, k), index(i, j, k + 1));
            }
    std::vector<std::int64_t> voxel_of_vertex(std::size_t(s.vertex_count()), -1);
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const auto& x = s.surfels[std::size_t(f)].voxel;
        for (int c = 0; c < 4; ++c) {
            std::int64_t& other = voxel_of_vertex[std::size_t(s.quads(f, c))];
            if (other >= 0) unite(other, index(x[0], x[1], x[2]));
            other = index(x[0], x[1], x[2]);
        }
    }
    std::vector<std::int64_t> part(parent.size(), -1);
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i)
                if (v.inside(i, j, k)) part[std::size_t(index(i, j, k))] = find(index(i, j, k));
    return part;
}

/// Brute force: weighted covariance of the centres of the voxels of the face's part (voxel_parts)
/// within distance r of c, with weight 1 (ball) or (1 − d²/r²)² (biweight); its eigenvector of the
/// smallest eigenvalue, blended with the direction from the centroid to c below the relative
/// eigen-gap 0.1 (integral_invariant_normals, include/dsreg/normals.hpp).
Eigen::Vector3d brute_force_ii_normal(const BinaryVolume& v, const std::vector<std::int64_t>& parts, std::int64_t part,
                                      const Eigen::Vector3d& c, double r, IntegralInvariantKernel kernel) {
    double n = 0;
    Eigen::Vector3d s1 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();
    const Index3& d = v.grid.dims;
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const Eigen::Vector3d x = v.grid.voxel_center(i, j, k) - c;
                if (parts[std::size_t(i + d[0] * (j + d[1] * k))] != part || x.squaredNorm() > r * r) continue;
                const double q = 1.0 - x.squaredNorm() / (r * r);
                const double w = kernel == IntegralInvariantKernel::ball ? 1.0 : q * q;
                n += w;
                s1 += w * x;
                s2 += w * x * x.transpose();
            }
    const Eigen::Vector3d mean = s1 / n;
    const Eigen::Matrix3d cov = s2 / n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Eigen::Vector3d normal = eig.eigenvectors().col(0);
    if (mean.dot(normal) > 0) normal = -normal;
    const Eigen::Vector3d l = eig.eigenvalues();
    const double gap = l[1] > 1e-12 * v.grid.spacing.squaredNorm() ? (l[1] - l[0]) / l[1] : 0.0;
    if (gap < 0.1) normal = (gap / 0.1 * normal - (1 - gap / 0.1) * mean.normalized()).normalized();
    return normal;
}

TEST(Normals, TrivialNormalsAreTheAxisNormals) {
    const auto s = extract_digital_surface(test::make_ball(10, 3.5, 4.5), Connectivity::Six);
    const PointMatrix u = trivial_normals(s);
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        EXPECT_DOUBLE_EQ(u.row(f).norm(), 1.0);
        EXPECT_EQ(u.row(f).transpose(), s.surfels[std::size_t(f)].trivial_normal());
    }
}

TEST(Normals, RowSumsEqualBruteForceOnAnisotropicGrid) {
    std::mt19937 rng(3);
    std::bernoulli_distribution coin(0.6);
    BinaryVolume v = test::make_volume({9, 8, 7}, [&](double, double, double) { return coin(rng); });
    v.grid.spacing = Eigen::Vector3d(0.7, 1.0, 1.9);
    v.grid.origin = Eigen::Vector3d(-3.0, 2.0, 0.25);
    const auto s = extract_digital_surface(v, Connectivity::TwentySix);
    const double r = 2.3;
    const PointMatrix c = surfel_centers(s);
    const std::vector<std::int64_t> parts = voxel_parts(v, s);
    for (IntegralInvariantKernel kernel : {IntegralInvariantKernel::ball, IntegralInvariantKernel::biweight}) {
        const PointMatrix u = integral_invariant_normals(v, s, r, kernel);
        for (std::int64_t f = 0; f < s.face_count(); f += 7) {
            const auto& x = s.surfels[std::size_t(f)].voxel;
            const std::int64_t part = parts[std::size_t(x[0] + v.grid.dims[0] * (x[1] + v.grid.dims[1] * x[2]))];
            const Eigen::Vector3d expected = brute_force_ii_normal(v, parts, part, c.row(f).transpose(), r, kernel);
            // Same sums up to rounding (row tables vs direct sums), amplified by small eigen-gaps.
            EXPECT_LT(angle_deg(u.row(f).transpose(), expected), 1e-4) << kernel_name(kernel) << " face " << f;
        }
    }
}

TEST(Normals, NestedBallsGiveEachBallsOwnNormalToTheBit) {
    // Two concentric balls summed in one pass over the larger one's rows: the same sums in the
    // same order as each ball alone, so the same normals bit for bit, whatever the kernel, the
    // spacing and the label (runs of three labels and of the background in every row).
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> label(0, 3);
    LabelVolume v;
    v.grid.dims = {13, 11, 9};
    v.grid.spacing = Eigen::Vector3d(0.8, 1.0, 1.7);
    v.labels.resize(std::size_t(v.grid.voxel_count()));
    for (auto& l : v.labels) l = std::uint32_t(label(rng));
    v.values = {0, 10, 20, 30};
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    const detail::RowRuns rows = detail::build_part_runs(v, s);
    ASSERT_GT(s.face_count(), 500);
    for (IntegralInvariantKernel kernel : {IntegralInvariantKernel::ball, IntegralInvariantKernel::biweight})
        for (const auto& [outer, inner] : {std::pair{4.1, 2.9}, std::pair{3.0, 2.99}, std::pair{5.5, 1.2}}) {
            const detail::IntegralInvariantBall big(v.grid.spacing, outer, kernel), small(v.grid.spacing, inner, kernel);
            const detail::NestedIntegralInvariantBalls both(v.grid.spacing, outer, inner, kernel);
            std::int64_t different = 0;
            for (std::int64_t f = 0; f < s.face_count(); ++f) {
                const Surfel& x = s.surfels[std::size_t(f)];
                const std::uint32_t part = detail::run_label_at(rows, v.grid.dims, x.voxel);
                const auto [n_outer, n_inner] = both.normals(v.grid.dims, rows, x, part);
                different += n_outer != big.normal(v.grid.dims, rows, x, part) ? 1 : 0;
                different += n_inner != small.normal(v.grid.dims, rows, x, part) ? 1 : 0;
            }
            EXPECT_EQ(different, 0) << kernel_name(kernel) << " radii " << outer << ", " << inner;
        }
    EXPECT_THROW(detail::NestedIntegralInvariantBalls(v.grid.spacing, 2.0, 2.0, IntegralInvariantKernel::ball), Error);
}

TEST(Normals, VoxelsWiresAndBarsThinnerThanTheBallGetTheirOwnFacesNormals) {
    // Ball radius 3 across an isolated voxel, a wire one voxel thick and a bar two voxels thick:
    // the covariance of what the ball holds is isotropic across them (λ1 = λ2), so its eigenvector
    // is any direction of the cross-section (a y face of the voxel got +x); the direction from the
    // centroid is radial: each face of the voxel and of the wire gets its own axis, a face of the
    // bar the direction from the bar's axis to its centre (as on a round tube: 26.6° from its
    // axis, towards the nearer edge; with the ball kernel). Exactly, by symmetry, away from the
    // wire's and bar's ends.
    const BinaryVolume v = test::make_volume({30, 30, 30}, [](double x, double y, double z) {
        const bool voxel = x == 5 && y == 5 && z == 5;
        const bool wire = x == 20 && y == 8 && z >= 3 && z <= 26;
        const bool bar = y >= 20 && y <= 21 && z >= 20 && z <= 21 && x >= 3 && x <= 26;
        return voxel || wire || bar;
    });
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    for (IntegralInvariantKernel kernel : {IntegralInvariantKernel::ball, IntegralInvariantKernel::biweight}) {
        const PointMatrix u = integral_invariant_normals(v, s, 3.0, kernel);
        std::int64_t checked = 0;
        for (std::int64_t f = 0; f < s.face_count(); ++f) {
            const Surfel& surfel = s.surfels[std::size_t(f)];
            const auto& x = surfel.voxel;
            const bool isolated = x[0] == 5 && x[1] == 5;
            const bool wire_middle = x[0] == 20 && x[1] == 8 && x[2] >= 8 && x[2] <= 21 && surfel.axis != 2;
            // The biweight weighs the bar's nearer voxels more: not isotropic across it.
            const bool bar_middle = kernel == IntegralInvariantKernel::ball && x[1] >= 20 && x[0] >= 8 && x[0] <= 21 &&
                                    surfel.axis != 0;
            if (!isolated && !wire_middle && !bar_middle) continue;
            Eigen::Vector3d expected = surfel.trivial_normal();
            if (bar_middle) {  // from the axis (y, z) = (20.5, 20.5) to the face centre
                const Eigen::Vector3d centre = v.grid.voxel_center(x[0], x[1], x[2]) + 0.5 * surfel.trivial_normal();
                expected = Eigen::Vector3d(0, centre.y() - 20.5, centre.z() - 20.5).normalized();
            }
            EXPECT_LT(angle_deg(u.row(f).transpose(), expected), 1e-9) << kernel_name(kernel) << " face " << f;
            ++checked;
        }
        EXPECT_EQ(checked, 6 + 4 * 14 + (kernel == IntegralInvariantKernel::ball ? 8 * 14 : 0));
    }
}

TEST(Normals, AnotherPartAVoxelAwayIsNotInTheBall) {
    // A flat slab and, one background voxel above it, a voxel of debris: each sums its own part
    // only. The debris keeps its faces' own normals (its bottom face saw the slab through the ball
    // and pointed up, into the voxel), and the slab's top stays flat under it.
    const BinaryVolume v = test::make_volume({24, 24, 16}, [](double x, double y, double z) {
        return (z >= 2 && z <= 7) || (z == 9 && y == 12 && x == 11);
    });
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    for (IntegralInvariantKernel kernel : {IntegralInvariantKernel::ball, IntegralInvariantKernel::biweight}) {
        const PointMatrix u = integral_invariant_normals(v, s, 3.0, kernel);
        std::int64_t debris = 0, slab = 0;
        for (std::int64_t f = 0; f < s.face_count(); ++f) {
            const Surfel& surfel = s.surfels[std::size_t(f)];
            const auto& x = surfel.voxel;
            if (x[2] == 9) {
                EXPECT_LT(angle_deg(u.row(f).transpose(), surfel.trivial_normal()), 1e-9) << "debris face " << f;
                ++debris;
            }
            if (x[2] == 7 && surfel.axis == 2 && std::abs(x[0] - 11) < 5 && std::abs(x[1] - 12) < 5) {
                EXPECT_LT(angle_deg(u.row(f).transpose(), Eigen::Vector3d::UnitZ()), 1e-9) << "slab face " << f;
                ++slab;
            }
        }
        EXPECT_EQ(debris, 6);
        EXPECT_EQ(slab, 81);
    }
}

TEST(Normals, ALabelsFragmentsAreApartToo) {
    // Label 2 in two pieces one voxel apart (label 1 between them, then background): the faces of
    // the small piece sum that piece only, as in a binary volume.
    const LabelVolume v = test::make_labels({20, 20, 20}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        if (k >= 3 && k <= 8 && i >= 2 && i <= 17 && j >= 2 && j <= 17) return 2;
        if (k == 9 && i == 9 && j == 9) return 1;
        if (k == 10 && i == 9 && j == 9) return 2;
        return 0;
    });
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(v, s, 3.0, IntegralInvariantKernel::biweight);
    std::int64_t checked = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Surfel& surfel = s.surfels[std::size_t(f)];
        if (surfel.voxel[2] != 10) continue;
        EXPECT_LT(angle_deg(u.row(f).transpose(), surfel.trivial_normal()), 1e-9) << "face " << f;
        ++checked;
    }
    EXPECT_EQ(checked, 6);
}

/// Mean angle between a field and the true normals of a digitized shape.
double mean_error_deg(const PointMatrix& u, const PointMatrix& truth) {
    double sum = 0;
    for (std::int64_t f = 0; f < u.rows(); ++f) sum += angle_deg(u.row(f).transpose(), truth.row(f).transpose());
    return sum / double(u.rows());
}

/// Goursat at h = 0.25 with r = 3·h^(1/3) = 7.56 voxels: the reference set-up of docs/accuracy.md.
struct GoursatQuarter {
    const ImplicitShape shape = make_shape("goursat");
    const double h = 0.25, r = 3.0 * std::cbrt(h);
    const BinaryVolume volume = digitize(shape, h);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix truth = exact_normals(shape, surface);
};

TEST(Normals, BiweightKernelIsCloserToTheTrueNormalsThanTheBall) {
    // The ball field is 1.32° off, mostly from the curvature variation across the ball (O(r²));
    // the biweight weighs the nearer voxels more and fades out those entering or leaving the ball.
    const GoursatQuarter g;
    const double ball =
        mean_error_deg(integral_invariant_normals(g.volume, g.surface, g.r, IntegralInvariantKernel::ball), g.truth);
    const double biweight = mean_error_deg(integral_invariant_normals(g.volume, g.surface, g.r), g.truth);
    EXPECT_LT(biweight, 0.85 * ball) << "ball " << ball << "°, biweight " << biweight << "°";
    EXPECT_LT(biweight, 1.0);
}

TEST(Normals, ExtrapolationRemovesTheRadiusBias) {
    // The single-scale field's error is mostly a bias growing like r², which the extrapolation
    // 2·n(r/√2) − n(r) cancels; so twice the radius (half the noise) can be used.
    const GoursatQuarter g;
    const double single = mean_error_deg(integral_invariant_normals(g.volume, g.surface, g.r), g.truth);
    const double single_wide = mean_error_deg(integral_invariant_normals(g.volume, g.surface, 2 * g.r), g.truth);
    const PointMatrix u = extrapolated_integral_invariant_normals(g.volume, g.surface, 2 * g.r);
    const double extrapolated = mean_error_deg(u, g.truth);
    EXPECT_LT(extrapolated, 0.7 * single) << "single scale r " << single << "°, extrapolated 2r " << extrapolated << "°";
    EXPECT_LT(extrapolated, 0.4 * single_wide) << "single scale 2r " << single_wide << "°";
    for (std::int64_t f = 0; f < u.rows(); ++f) EXPECT_NEAR(u.row(f).norm(), 1.0, 1e-12);
}

TEST(Normals, ExtrapolationKeepsTheNarrowScaleWhereScalesDisagree) {
    // A random set of voxels has no smooth boundary: the wide and narrow estimates often differ
    // by more than 30°, where the expansion behind the extrapolation does not hold; there the
    // narrow estimate is kept as it is, elsewhere the result is 2·narrow − wide, normalized.
    std::mt19937 rng(5);
    std::bernoulli_distribution coin(0.5);
    const BinaryVolume v = test::make_volume({14, 14, 14}, [&](double, double, double) { return coin(rng); });
    const auto s = extract_digital_surface(v, Connectivity::TwentySix);
    const double r = 3.0;
    const PointMatrix wide = integral_invariant_normals(v, s, r);
    const PointMatrix narrow = integral_invariant_normals(v, s, r / std::sqrt(2.0));
    const PointMatrix u = extrapolated_integral_invariant_normals(v, s, r);
    int disagreeing = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d w = wide.row(f).transpose(), n = narrow.row(f).transpose();
        if (angle_deg(w, n) > 30.0) {
            ++disagreeing;
            EXPECT_EQ(u.row(f), narrow.row(f)) << "face " << f;
        } else {
            EXPECT_LT(angle_deg(u.row(f).transpose(), 2.0 * n - w), 1e-5) << "face " << f;
        }
    }
    EXPECT_GT(disagreeing, 0);
    EXPECT_LT(disagreeing, s.face_count());
}

TEST(Normals, KernelNamesRoundTrip) {
    for (IntegralInvariantKernel kernel : {IntegralInvariantKernel::ball, IntegralInvariantKernel::biweight})
        EXPECT_EQ(parse_integral_invariant_kernel(kernel_name(kernel)), kernel);
    EXPECT_THROW(parse_integral_invariant_kernel("gauss"), Error);
}

TEST(Normals, IntegralInvariantsOnABallPointRadially) {
    const double radius = 14.0, centre = 19.5;
    const auto ball = test::make_ball(40, radius, centre);
    const auto s = extract_digital_surface(ball, Connectivity::Six);
    const PointMatrix u = integral_invariant_normals(ball, s, 5.0);
    const PointMatrix c = surfel_centers(s);
    double sum = 0, worst = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const double e = angle_deg(u.row(f).transpose(), c.row(f).transpose() - Eigen::Vector3d::Constant(centre));
        sum += e;
        worst = std::max(worst, e);
        EXPECT_NEAR(u.row(f).norm(), 1.0, 1e-12);
    }
    const PointMatrix t = trivial_normals(s);
    double trivial_sum = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        trivial_sum += angle_deg(t.row(f).transpose(), c.row(f).transpose() - Eigen::Vector3d::Constant(centre));
    EXPECT_LT(sum / double(s.face_count()), 3.0);
    EXPECT_LT(worst, 12.0);
    EXPECT_LT(sum, 0.2 * trivial_sum);  // far better than the axis normals
}

TEST(Normals, IntegralInvariantsOnATiltedPlane) {
    const Eigen::Vector3d n = Eigen::Vector3d(1.0, 2.0, 3.0).normalized();
    const auto slab = test::make_volume({40, 40, 40}, [&](double x, double y, double z) {
        return n.dot(Eigen::Vector3d(x, y, z) - Eigen::Vector3d::Constant(19.3)) <= 0;
    });
    const auto s = extract_digital_surface(slab, Connectivity::Six);
    const PointMatrix u = integral_invariant_normals(slab, s, 6.0);
    const PointMatrix c = surfel_centers(s);
    int checked = 0;
    double sum = 0, worst = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d x = c.row(f).transpose();
        const bool interior = (x.array() > 8.0).all() && (x.array() < 31.0).all();
        if (!interior || std::abs(n.dot(x - Eigen::Vector3d::Constant(19.3))) > 1.0) continue;
        const double e = angle_deg(u.row(f).transpose(), n);
        sum += e;
        worst = std::max(worst, e);
        ++checked;
    }
    ASSERT_GT(checked, 500);
    // Digitization noise of a plane seen through a ball of radius r is O(h/r): here about 1° on average.
    EXPECT_LT(sum / checked, 1.5);
    EXPECT_LT(worst, 3.0);
}

TEST(Normals, RadiusMustBePositive) {
    const auto ball = test::make_ball(8, 2.5, 3.5);
    const auto s = extract_digital_surface(ball, Connectivity::Six);
    EXPECT_THROW(integral_invariant_normals(ball, s, 0.0), Error);
    EXPECT_THROW(integral_invariant_normals(ball, s, -1.0), Error);
    EXPECT_THROW(integral_invariant_normals(ball, s, std::nan("")), Error);
    EXPECT_THROW(integral_invariant_normals(ball, s, 500.0), Error);  // tables of 500³ voxels: refused
}

TEST(Normals, LiftGivesTheNearestUnitVectorInTheSurfelsHalfSpaceAndLeavesTheOthers) {
    const auto s = extract_digital_surface(test::make_ball(12, 4.5, 6), Connectivity::Six);
    std::mt19937 random(7);
    std::normal_distribution<double> gauss;
    PointMatrix u(s.face_count(), 3);
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        u.row(f) = Eigen::RowVector3d(gauss(random), gauss(random), gauss(random)).normalized();
    const PointMatrix before = u;
    const double margin = 0.05;
    const std::int64_t lifted = lift_into_surfel_half_spaces(s, u, margin);
    std::int64_t changed = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d n = s.surfels[std::size_t(f)].trivial_normal();
        const Eigen::Vector3d b = before.row(f).transpose(), a = u.row(f).transpose();
        if (b.dot(n) >= margin) {
            EXPECT_EQ(a, b) << "face " << f;
            continue;
        }
        ++changed;
        EXPECT_NEAR(a.norm(), 1.0, 1e-12);
        EXPECT_NEAR(a.dot(n), margin, 1e-12);
        // Same tangential direction, and no unit vector of the half-space is closer to b.
        EXPECT_LT(((a - a.dot(n) * n).normalized() - (b - b.dot(n) * n).normalized()).norm(), 1e-9);
        for (int trial = 0; trial < 20; ++trial) {
            Eigen::Vector3d w(gauss(random), gauss(random), gauss(random));
            w.normalize();
            if (w.dot(n) < margin) w = (w - (w.dot(n) - margin - 0.5) * n).normalized();  // into the half-space
            if (w.dot(n) < margin) continue;
            EXPECT_GE(angle_deg(w, b), angle_deg(a, b) - 1e-9);
        }
    }
    EXPECT_GT(changed, s.face_count() / 4);  // random vectors: about half are below
    EXPECT_EQ(lifted, changed);
    EXPECT_THROW(lift_into_surfel_half_spaces(s, u, 1.0), Error);
    EXPECT_THROW(lift_into_surfel_half_spaces(s, u, -0.1), Error);
    PointMatrix short_field = u.topRows(3);
    EXPECT_THROW(lift_into_surfel_half_spaces(s, short_field, margin), Error);
}

TEST(Normals, FacesAgainstTheirSurfelsAreThoseWhoseFieldPointsIntoTheObject) {
    const auto s = extract_digital_surface(test::make_ball(12, 4.5, 6), Connectivity::Six);
    PointMatrix u = trivial_normals(s);
    EXPECT_TRUE(faces_against_their_surfels(s, u).empty());
    const std::vector<std::int32_t> turned{0, 5, std::int32_t(s.face_count() - 1)};
    for (const std::int32_t f : turned) u.row(f) = -u.row(f);
    u.row(7) = Eigen::RowVector3d(u(7, 1), u(7, 2), u(7, 0));  // along the face: u·n = 0, not against
    EXPECT_EQ(faces_against_their_surfels(s, u), turned);
    PointMatrix short_field = u.topRows(3);
    EXPECT_THROW(faces_against_their_surfels(s, short_field), Error);
    // One face lifted alone, as the whole-field lift does it.
    PointMatrix one = u;
    EXPECT_TRUE(lift_into_surfel_half_space(s, one, 7, 0.05));
    EXPECT_NEAR(one.row(7).dot(s.surfels[7].trivial_normal().transpose()), 0.05, 1e-12);
    EXPECT_FALSE(lift_into_surfel_half_space(s, one, 1, 0.05));
    EXPECT_EQ(one.row(1), u.row(1));
}

}  // namespace
}  // namespace dsreg
