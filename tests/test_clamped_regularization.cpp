// Clamped ("reversible") regularization: the box-constrained QP solver against exhaustive
// search, optimality of the clamped minimizer, and re-digitization of the result.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "dsreg/box_qp.hpp"
#include "dsreg/clamped_regularization.hpp"
#include "dsreg/error.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/normals.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

// ---------------------------------------------------------------------------------------------
// The box QP solver on small dense problems

struct SmallQp {
    Eigen::MatrixXd R;
    Eigen::VectorXd b, lower, upper;
};

/// A random SPD matrix with positive off-diagonal entries too (not an M-matrix, like eq. 23),
/// and a right-hand side whose unconstrained minimizer leaves the box [-1, 1]^n.
SmallQp random_qp(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    SmallQp qp;
    const Eigen::MatrixXd A = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return normal(rng); });
    qp.R = A.transpose() * A + 0.05 * Eigen::MatrixXd::Identity(n, n);
    qp.b = Eigen::VectorXd::NullaryExpr(n, [&] { return 3.0 * normal(rng); });
    qp.lower = -Eigen::VectorXd::Ones(n);
    qp.upper = Eigen::VectorXd::Ones(n);
    return qp;
}

/// The KKT point found by trying every assignment free / lower / upper of the n coordinates.
Eigen::VectorXd exhaustive_box_qp(const SmallQp& qp) {
    const int n = int(qp.b.size());
    int assignments = 1;
    for (int i = 0; i < n; ++i) assignments *= 3;
    for (int code = 0; code < assignments; ++code) {
        std::vector<int> state(static_cast<std::size_t>(n));
        for (int i = 0, c = code; i < n; ++i, c /= 3) state[std::size_t(i)] = c % 3;  // 0 free, 1 lower, 2 upper
        Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
        std::vector<int> free;
        for (int i = 0; i < n; ++i) {
            if (state[std::size_t(i)] == 1) x[i] = qp.lower[i];
            if (state[std::size_t(i)] == 2) x[i] = qp.upper[i];
            if (state[std::size_t(i)] == 0) free.push_back(i);
        }
        if (!free.empty()) {
            const int m = int(free.size());
            Eigen::MatrixXd Rff(m, m);
            Eigen::VectorXd rhs(m);
            const Eigen::VectorXd fixed_part = qp.R * x;
            for (int a = 0; a < m; ++a) {
                rhs[a] = qp.b[free[std::size_t(a)]] - fixed_part[free[std::size_t(a)]];
                for (int c = 0; c < m; ++c) Rff(a, c) = qp.R(free[std::size_t(a)], free[std::size_t(c)]);
            }
            const Eigen::VectorXd xf = Rff.llt().solve(rhs);
            for (int a = 0; a < m; ++a) x[free[std::size_t(a)]] = xf[a];
        }
        const Eigen::VectorXd g = qp.R * x - qp.b;
        bool kkt = true;
        for (int i = 0; i < n; ++i) {
            if (state[std::size_t(i)] == 0) kkt = kkt && x[i] >= qp.lower[i] && x[i] <= qp.upper[i];
            if (state[std::size_t(i)] == 1) kkt = kkt && g[i] >= 0;
            if (state[std::size_t(i)] == 2) kkt = kkt && g[i] <= 0;
        }
        if (kkt) return x;  // strictly convex: the KKT point is unique
    }
    ADD_FAILURE() << "no KKT point found";
    return Eigen::VectorXd::Zero(n);
}

Eigen::VectorXd solve_small(const SmallQp& qp, const BoxQpOptions& options, BoxQpReport& report) {
    const Eigen::SparseMatrix<double> R = qp.R.sparseView();
    Eigen::VectorXd x = qp.R.llt().solve(qp.b);  // start at the unconstrained minimizer, as regularize_clamped does
    report = solve_box_qp(R, qp.b, qp.lower, qp.upper, x, options);
    return x;
}

TEST(BoxQp, MatchesExhaustiveActiveSetSearch) {
    for (unsigned seed = 0; seed < 25; ++seed) {
        const SmallQp qp = random_qp(6, seed);
        const Eigen::VectorXd expected = exhaustive_box_qp(qp);
        BoxQpOptions with_admm, without_admm;
        without_admm.admm_max_iterations = 0;
        for (const BoxQpOptions& options : {with_admm, without_admm}) {
            BoxQpReport report;
            const Eigen::VectorXd x = solve_small(qp, options, report);
            SCOPED_TRACE("seed " + std::to_string(seed) + (options.admm_max_iterations ? " with ADMM" : " without ADMM"));
            EXPECT_TRUE(report.converged);
            EXPECT_LE(report.kkt_residual, options.tolerance);
            EXPECT_EQ(report.constraint_violation, 0.0);
            EXPECT_LT((x - expected).lpNorm<Eigen::Infinity>(), 1e-9);
        }
    }
}

TEST(BoxQp, OptimalityOfAnAppliedMatrixIsThatOfTheStoredOne) {
    // The validity repair measures its region's KKT residual with R applied row by row, never
    // assembled: both overloads must report the same, at points inside, outside and on the box.
    for (unsigned seed = 0; seed < 10; ++seed) {
        const SmallQp qp = random_qp(6, seed);
        const Eigen::SparseMatrix<double> R = qp.R.sparseView();
        const auto multiply = [&](const Eigen::VectorXd& y) -> Eigen::VectorXd { return qp.R * y; };
        const Eigen::VectorXd solution = exhaustive_box_qp(qp);
        for (const Eigen::VectorXd& x : {Eigen::VectorXd(solution), Eigen::VectorXd(qp.lower.array() - 1.0),
                                         Eigen::VectorXd(0.5 * (qp.lower + qp.upper)), Eigen::VectorXd(qp.R.llt().solve(qp.b))}) {
            SCOPED_TRACE("seed " + std::to_string(seed));
            const BoxQpReport stored = box_qp_optimality(R, qp.b, qp.lower, qp.upper, x, 1e-9);
            const BoxQpReport applied = box_qp_optimality(multiply, qp.b, qp.lower, qp.upper, x, 1e-9);
            EXPECT_NEAR(applied.kkt_residual, stored.kkt_residual, 1e-12 * (1 + stored.kkt_residual));
            EXPECT_NEAR(applied.stationarity, stored.stationarity, 1e-12 * (1 + stored.stationarity));
            EXPECT_EQ(applied.constraint_violation, stored.constraint_violation);
            EXPECT_EQ(applied.at_lower, stored.at_lower);
            EXPECT_EQ(applied.at_upper, stored.at_upper);
        }
        // At the solution the KKT conditions hold; below the box they do not.
        EXPECT_LE(box_qp_optimality(multiply, qp.b, qp.lower, qp.upper, solution, 1e-9).kkt_residual, 1e-9);
        EXPECT_GT(box_qp_optimality(multiply, qp.b, qp.lower, qp.upper, qp.lower.array() - 1.0, 1e-9).constraint_violation, 0.0);
    }
}

TEST(BoxQp, StartingFromTheUnconstrainedMinimizerItComputes) {
    for (unsigned seed = 50; seed < 60; ++seed) {
        const SmallQp qp = random_qp(6, seed);
        const Eigen::SparseMatrix<double> R = qp.R.sparseView();
        Eigen::VectorXd unconstrained, x;
        const BoxQpReport report = solve_box_qp_from_unconstrained(R, qp.b, qp.lower, qp.upper, unconstrained, x);
        SCOPED_TRACE("seed " + std::to_string(seed));
        EXPECT_LT((unconstrained - qp.R.llt().solve(qp.b)).norm(), 1e-9 * unconstrained.norm());
        EXPECT_LT(report.unconstrained_residual, 1e-12);
        EXPECT_GT(report.factor_nonzeros, 0);
        EXPECT_TRUE(report.converged);
        EXPECT_LT((x - exhaustive_box_qp(qp)).lpNorm<Eigen::Infinity>(), 1e-9);
    }
}

TEST(BoxQp, ProjectedNewtonFallbackReachesTheSameSolution) {
    for (unsigned seed = 100; seed < 110; ++seed) {
        const SmallQp qp = random_qp(6, seed);
        BoxQpOptions options;
        options.admm_max_iterations = 0;
        options.active_set_max_iterations = 0;  // only the monotone fallback
        BoxQpReport report;
        const Eigen::VectorXd x = solve_small(qp, options, report);
        SCOPED_TRACE("seed " + std::to_string(seed));
        EXPECT_TRUE(report.converged);
        EXPECT_GT(report.newton_iterations, 0);
        EXPECT_LT((x - exhaustive_box_qp(qp)).lpNorm<Eigen::Infinity>(), 1e-9);
    }
}

TEST(BoxQp, ReturnsAnInteriorUnconstrainedMinimizerUntouched) {
    SmallQp qp = random_qp(5, 7);
    qp.lower = -1e6 * Eigen::VectorXd::Ones(5);
    qp.upper = 1e6 * Eigen::VectorXd::Ones(5);
    BoxQpReport report;
    const Eigen::VectorXd x = solve_small(qp, {}, report);
    EXPECT_TRUE(report.converged);
    EXPECT_EQ(report.factorizations, 0);
    EXPECT_EQ(report.at_lower + report.at_upper, 0);
    EXPECT_LT((qp.R * x - qp.b).norm(), 1e-10 * qp.b.norm());
}

TEST(BoxQp, InfiniteBoundsLeaveCoordinatesFree) {
    const double infinity = std::numeric_limits<double>::infinity();
    for (unsigned seed = 200; seed < 210; ++seed) {
        SmallQp open = random_qp(6, seed), far = open;
        for (int i : {0, 3}) open.lower[i] = -infinity, far.lower[i] = -1e8;  // free below
        for (int i : {1, 3, 4}) open.upper[i] = infinity, far.upper[i] = 1e8;  // free above
        BoxQpReport report;
        const Eigen::VectorXd x = solve_small(open, {}, report);
        SCOPED_TRACE("seed " + std::to_string(seed));
        EXPECT_TRUE(report.converged);
        EXPECT_LT((x - exhaustive_box_qp(far)).lpNorm<Eigen::Infinity>(), 1e-9);
    }
}

TEST(BoxQp, RejectsInconsistentProblems) {
    SmallQp qp = random_qp(4, 3);
    qp.lower[2] = 2.0;  // above upper[2] = 1
    BoxQpReport report;
    EXPECT_THROW(solve_small(qp, {}, report), Error);
    for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
        SmallQp empty = random_qp(4, 3);
        empty.lower[1] = bad;  // NaN, or a lower bound of +inf: no point
        EXPECT_THROW(solve_small(empty, {}, report), Error);
    }
}

// ---------------------------------------------------------------------------------------------
// Clamped regularization of digitized shapes

struct ShapeCase {
    BinaryVolume volume;
    DigitalSurface surface;
    PointMatrix normals;
};

ShapeCase shape_case(const std::string& name, double h) {
    ShapeCase c;
    c.volume = digitize(make_shape(name), h);
    c.surface = extract_digital_surface(c.volume, Connectivity::TwentySix);
    c.normals = integral_invariant_normals(c.volume, c.surface, 3.0 * std::cbrt(h));
    return c;
}

/// sphere9 at h = 1 with II normals: the unclamped minimizer leaves the boxes of many vertices.
const ShapeCase& sphere_case() {
    static const ShapeCase c = shape_case("sphere9", 1.0);
    return c;
}

ClampOptions default_clamp() { return ClampOptions{}; }

const ClampedRegularizationResult& sphere_result() {
    static const ClampedRegularizationResult r =
        regularize_clamped(sphere_case().surface, sphere_case().normals, RegularizationWeights{}, default_clamp());
    return r;
}

double total_energy(const ShapeCase& c, const PointMatrix& candidate, const RegularizationWeights& w) {
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    return regularization_energy(candidate, c.surface.vertices, c.surface.quads, links, c.normals, w).total(w);
}

TEST(ClampedRegularization, EveryVertexStaysInItsBox) {
    const ShapeCase& c = sphere_case();
    const ClampedRegularizationResult& r = sphere_result();
    ASSERT_GT(r.clamp.unclamped_vertices_outside, 0) << "the test needs a shape where the unclamped solution leaves the boxes";
    Eigen::VectorXd lower, upper;
    clamp_bounds(c.surface, default_clamp().half_width, lower, upper);
    const Eigen::VectorXd x = flatten_points(r.positions);
    for (Eigen::Index q = 0; q < x.size(); ++q) {
        ASSERT_GE(x[q], lower[q]) << "coordinate " << q;
        ASSERT_LE(x[q], upper[q]) << "coordinate " << q;
    }
    // The same in physical terms, up to the rounding of p ± 0.499 s.
    const double half_width = default_clamp().half_width;
    for (std::int64_t i = 0; i < c.surface.vertex_count(); ++i)
        for (int d = 0; d < 3; ++d)
            ASSERT_LE(std::abs(r.positions(i, d) - c.surface.vertices(i, d)), half_width * c.surface.grid.spacing[d] * (1 + 1e-12))
                << "vertex " << i << " axis " << d;
    EXPECT_EQ(r.clamp.qp.constraint_violation, 0.0);
    EXPECT_GT(r.clamp.clamped_vertices, 0);
}

/// Independent KKT check of a clamped result: g = R x − b (R assembled here) vanishes on the free
/// coordinates and points outward at the bounds. Returns the worst violation relative to ‖b‖;
/// `at_bounds` counts the coordinates on a bound.
double kkt_violation(const DigitalSurface& surface, const PointMatrix& normals, const PointMatrix& positions, double half_width,
                     std::int64_t& at_bounds) {
    const VertexLinks links = fairness_links(surface);  // the quad links on a binary surface
    const RegularizationSystem s = assemble_regularization_system(surface.vertices, surface.quads, links, normals, RegularizationWeights{});
    Eigen::VectorXd lower, upper;
    clamp_bounds(surface, half_width, lower, upper);
    const Eigen::VectorXd x = flatten_points(positions);
    const Eigen::VectorXd g = s.matrix * x - s.rhs;
    double worst = 0;
    at_bounds = 0;
    for (Eigen::Index q = 0; q < x.size(); ++q) {
        if (x[q] == lower[q]) ++at_bounds, worst = std::max(worst, -g[q]);
        else if (x[q] == upper[q]) ++at_bounds, worst = std::max(worst, g[q]);
        else worst = std::max(worst, std::abs(g[q]));
    }
    return worst / s.rhs.norm();
}

TEST(ClampedRegularization, KktConditionsHoldToTheTolerance) {
    const ShapeCase& c = sphere_case();
    const ClampedRegularizationResult& r = sphere_result();
    EXPECT_TRUE(r.clamp.qp.converged);
    EXPECT_LE(r.clamp.qp.kkt_residual, default_clamp().qp.tolerance);
    std::int64_t at_bounds = 0;
    EXPECT_LT(kkt_violation(c.surface, c.normals, r.positions, default_clamp().half_width, at_bounds), 1e-10);
    EXPECT_GT(at_bounds, 0);
}

/// A sphere of radius 9 and eight balls of radius 2 around it: one large component, eight small.
BinaryVolume sphere_and_small_balls() {
    return test::make_volume({30, 30, 30}, [](double i, double j, double k) {
        if (Eigen::Vector3d(i - 14.5, j - 14.5, k - 14.5).norm() <= 9.0) return true;
        for (double a : {3.0, 26.0})
            for (double b : {3.0, 26.0})
                for (double d : {3.0, 26.0})
                    if (Eigen::Vector3d(i - a, j - b, k - d).norm() <= 2.0) return true;
        return false;
    });
}

TEST(ClampedRegularization, IterativeAndFactoredSolvesReachTheSameKktPoint) {
    ShapeCase c;
    c.volume = sphere_and_small_balls();
    c.surface = extract_digital_surface(c.volume, Connectivity::TwentySix);
    ASSERT_EQ(c.surface.component_count, 9);
    c.normals = integral_invariant_normals(c.volume, c.surface, 3.0);
    ClampOptions direct, iterative;
    direct.solver.kind = SolverKind::Cholmod;
    iterative.solver.kind = SolverKind::Amg;
    const ClampedRegularizationResult a = regularize_clamped(c.surface, c.normals, RegularizationWeights{}, direct);
    const ClampedRegularizationResult b = regularize_clamped(c.surface, c.normals, RegularizationWeights{}, iterative);
    EXPECT_EQ(a.clamp.qp.cg_iterations, 0);
    EXPECT_GT(b.clamp.qp.cg_iterations, 0) << "the large component must take the iterative path";
    EXPECT_EQ(b.solve.solver, "amg");
    for (const ClampedRegularizationResult* r : {&a, &b}) {
        EXPECT_TRUE(r->clamp.qp.converged);
        EXPECT_LE(r->clamp.qp.kkt_residual, direct.qp.tolerance);
        EXPECT_GT(r->clamp.unclamped_vertices_outside, 0);
        std::int64_t at_bounds = 0;
        EXPECT_LT(kkt_violation(c.surface, c.normals, r->positions, direct.half_width, at_bounds), 1e-10);
        EXPECT_GT(at_bounds, 0);
        EXPECT_EQ(classify_voxel_centres(c.volume, r->positions, c.surface.quads).wrong(), 0);
    }
    // a strictly convex QP has one minimizer: both are within rounding of it
    EXPECT_LT((a.positions - b.positions).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(ClampedRegularization, OnALabelMapIterativeAndFactoredSolvesReachTheKktPointOfTheJunctionLinks) {
    // The library's clamped mode on a label complex (the pipeline refuses --clamp with
    // --multi-label): R has the junction-aware links on every path, the large component by amg
    // and CG, the small ones (one with a junction curve) by CHOLMOD.
    const LabelVolume labels = test::sectors_and_small_parts();
    const DigitalSurface surface = extract_digital_surface(labels, Connectivity::TwentySix);
    const PointMatrix normals = integral_invariant_normals(labels, surface, 3.0);
    ClampOptions direct, iterative;
    direct.solver.kind = SolverKind::Cholmod;
    iterative.solver.kind = SolverKind::Amg;
    const ClampedRegularizationResult a = regularize_clamped(surface, normals, RegularizationWeights{}, direct);
    const ClampedRegularizationResult b = regularize_clamped(surface, normals, RegularizationWeights{}, iterative);
    EXPECT_GT(b.clamp.qp.cg_iterations, 0) << "the large component must take the iterative path";
    for (const ClampedRegularizationResult* r : {&a, &b}) {
        EXPECT_TRUE(r->clamp.qp.converged);
        EXPECT_GT(r->clamp.unclamped_vertices_outside, 0);
        std::int64_t at_bounds = 0;
        EXPECT_LT(kkt_violation(surface, normals, r->positions, direct.half_width, at_bounds), 1e-10);
        EXPECT_GT(at_bounds, 0);
    }
    EXPECT_LT((a.positions - b.positions).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(ClampedRegularization, EnergyIsBetweenUnclampedAndEveryFeasiblePointTried) {
    const ShapeCase& c = sphere_case();
    const ClampedRegularizationResult& r = sphere_result();
    const RegularizationWeights w;
    const double clamped = total_energy(c, r.positions, w);
    EXPECT_NEAR(clamped, r.energy_after.total(w), 1e-12 * clamped);
    EXPECT_GE(clamped, total_energy(c, r.unclamped_positions, w));

    Eigen::VectorXd lower, upper;
    clamp_bounds(c.surface, default_clamp().half_width, lower, upper);
    const auto feasible = [&](const Eigen::VectorXd& y) { return unflatten_points(y.cwiseMax(lower).cwiseMin(upper)); };
    const Eigen::VectorXd x = flatten_points(r.positions);
    std::vector<PointMatrix> tried = {c.surface.vertices, feasible(flatten_points(r.unclamped_positions))};
    std::mt19937 rng(5);
    for (const double size : {0.3, 0.03, 0.003}) {
        std::uniform_real_distribution<double> offset(-size, size);
        for (int k = 0; k < 4; ++k) tried.push_back(feasible(x + Eigen::VectorXd::NullaryExpr(x.size(), [&] { return offset(rng); })));
    }
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int k = 0; k < 4; ++k)  // uniform in the boxes
        tried.push_back(unflatten_points(lower + (upper - lower).cwiseProduct(Eigen::VectorXd::NullaryExpr(x.size(), [&] { return unit(rng); }))));
    for (std::size_t k = 0; k < tried.size(); ++k) EXPECT_GE(total_energy(c, tried[k], w), clamped) << "feasible point " << k;
}

TEST(ClampedRegularization, ReDigitizesTheInputOnNamedShapes) {
    for (const auto& [name, h] : std::vector<std::pair<std::string, double>>{
             {"sphere9", 1.0}, {"sphere9", 0.5}, {"torus", 0.5}, {"goursat", 0.75}}) {
        SCOPED_TRACE(name + " at h=" + std::to_string(h));
        const ShapeCase c = shape_case(name, h);
        const ClampedRegularizationResult r = regularize_clamped(c.surface, c.normals, RegularizationWeights{}, default_clamp());
        EXPECT_TRUE(r.clamp.qp.converged);
        const VoxelAgreement clamped = classify_voxel_centres(c.volume, r.positions, c.surface.quads);
        const VoxelAgreement unclamped = classify_voxel_centres(c.volume, r.unclamped_positions, c.surface.quads);
        EXPECT_EQ(clamped.total, c.volume.grid.voxel_count());
        EXPECT_EQ(clamped.wrong(), 0);
        EXPECT_GT(unclamped.wrong(), 0);  // the unclamped surface cuts some voxel centres off
    }
}

/// Any half-width below ½ gives back the input whatever the normal field and the weights (the
/// argument is in docs/clamped.md): random volumes, random unit normals, random local weights.
TEST(ClampedRegularization, ReDigitizesRandomVolumesForAnyNormalField) {
    for (unsigned seed = 0; seed < 12; ++seed) {
        std::mt19937 rng(seed);
        std::bernoulli_distribution coin(0.45);
        const BinaryVolume volume = test::make_volume({9, 9, 9}, [&](double x, double y, double z) {
            const bool interior = x > 0 && y > 0 && z > 0 && x < 8 && y < 8 && z < 8;
            return interior && coin(rng);
        });
        const Connectivity connectivity = seed % 2 ? Connectivity::Six : Connectivity::TwentySix;
        const DigitalSurface surface = extract_digital_surface(volume, connectivity);
        std::normal_distribution<double> normal(0.0, 1.0);
        PointMatrix u(surface.face_count(), 3);
        for (std::int64_t f = 0; f < surface.face_count(); ++f)
            u.row(f) = Eigen::RowVector3d(normal(rng), normal(rng), normal(rng)).normalized();
        std::uniform_real_distribution<double> positive(0.1, 10.0);
        RegularizationWeights w{1e-4, 1.0, 0.1, {}, {}};
        w.vertex_gamma = Eigen::VectorXd::NullaryExpr(surface.vertex_count(), [&] { return positive(rng); });
        w.face_beta = Eigen::VectorXd::NullaryExpr(surface.face_count(), [&] { return positive(rng); });
        const ClampedRegularizationResult r = regularize_clamped(surface, u, w, default_clamp());
        SCOPED_TRACE("seed " + std::to_string(seed));
        EXPECT_TRUE(r.clamp.qp.converged);
        EXPECT_EQ(classify_voxel_centres(volume, r.positions, surface.quads).wrong(), 0);
    }
}

/// Vertices of the mesh that sit exactly on a voxel centre of the grid.
std::int64_t vertices_on_voxel_centres(const VoxelGrid& grid, const PointMatrix& positions) {
    std::int64_t count = 0;
    for (std::int64_t i = 0; i < positions.rows(); ++i) {
        const Eigen::Vector3d index = (positions.row(i).transpose() - grid.origin).cwiseQuotient(grid.spacing);
        count += (index - index.array().round().matrix()).cwiseAbs().maxCoeff() == 0.0 ? 1 : 0;
    }
    return count;
}

/// With the closed boxes of half-width exactly ½ the minimizer puts vertices on the corners of
/// their boxes, which are voxel centres: those centres lie on the surface and re-digitization
/// is ambiguous there. This is why the default half-width is 0.499.
TEST(ClampedRegularization, HalfWidthOneHalfPutsVoxelCentresOnTheSurface) {
    const ShapeCase& c = sphere_case();
    ClampOptions options;
    options.half_width = 0.5;
    const ClampedRegularizationResult r = regularize_clamped(c.surface, c.normals, RegularizationWeights{}, options);
    EXPECT_TRUE(r.clamp.qp.converged);
    EXPECT_GT(vertices_on_voxel_centres(c.volume.grid, r.positions), 0);
    EXPECT_EQ(vertices_on_voxel_centres(c.volume.grid, sphere_result().positions), 0);
}

TEST(ClampedRegularization, AnisotropicBoxesFollowTheSpacingOfEachAxis) {
    const Eigen::Vector3d spacing(1.0, 1.0, 2.5);
    const double radius = 9.0;
    BinaryVolume volume = test::make_volume({23, 23, 11}, [&](double i, double j, double k) {
        const Eigen::Vector3d p = spacing.cwiseProduct(Eigen::Vector3d(i - 11, j - 11, k - 5));
        return p.norm() <= radius;
    });
    volume.grid.spacing = spacing;
    volume.grid.origin = -spacing.cwiseProduct(Eigen::Vector3d(11, 11, 5));
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(volume, surface, 3.0 * spacing.maxCoeff());
    const ClampedRegularizationResult r = regularize_clamped(surface, u, RegularizationWeights{}, default_clamp());
    EXPECT_TRUE(r.clamp.qp.converged);
    EXPECT_GT(r.clamp.clamped_vertices, 0);
    Eigen::Vector3d largest = Eigen::Vector3d::Zero();
    for (std::int64_t i = 0; i < surface.vertex_count(); ++i)
        largest = largest.cwiseMax((r.positions.row(i) - surface.vertices.row(i)).cwiseAbs().transpose());
    for (int d = 0; d < 3; ++d) EXPECT_LE(largest[d], default_clamp().half_width * spacing[d] * (1 + 1e-12));
    EXPECT_GT(largest[2], 0.5 * spacing[0]);  // along z the vertices use their longer reach
    EXPECT_EQ(classify_voxel_centres(volume, r.positions, surface.quads).wrong(), 0);
}

TEST(ClampedRegularization, RejectsANonPositiveHalfWidth) {
    ClampOptions options;
    options.half_width = 0;
    EXPECT_THROW(regularize_clamped(sphere_case().surface, sphere_case().normals, RegularizationWeights{}, options), Error);
}

}  // namespace
}  // namespace dsreg
