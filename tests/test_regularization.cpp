#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

struct Fixture {
    DigitalSurface surface;
    VertexLinks links;
    PointMatrix normals;
};

Fixture small_ball_with_ii_normals() {
    Fixture x;
    const auto ball = test::make_ball(10, 3.6, 4.5);
    x.surface = extract_digital_surface(ball, Connectivity::Six);
    x.links = vertex_links(x.surface.quads, x.surface.vertex_count());
    x.normals = integral_invariant_normals(ball, x.surface, 3.0);
    return x;
}

PointMatrix jitter(const PointMatrix& p, double amount, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> d(-amount, amount);
    PointMatrix q = p;
    for (Eigen::Index i = 0; i < q.size(); ++i) q.data()[i] += d(rng);
    return q;
}

double matrix_energy(const RegularizationSystem& s, const PointMatrix& candidate) {
    const Eigen::VectorXd x = flatten_points(candidate);
    return x.dot(s.matrix * x) - 2 * s.rhs.dot(x) + s.constant;
}

TEST(Regularization, MatrixIsSymmetricPositiveDefinite) {
    const Fixture x = small_ball_with_ii_normals();
    const RegularizationSystem s =
        assemble_regularization_system(x.surface.vertices, x.surface.quads, x.links, x.normals, RegularizationWeights{});
    const Eigen::MatrixXd dense(s.matrix);
    EXPECT_LT((dense - dense.transpose()).norm(), 1e-14 * dense.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.5 * 1e-3);  // ≥ α on the data term alone
}

TEST(Regularization, MatrixEnergyEqualsTermByTermEnergy) {
    const Fixture x = small_ball_with_ii_normals();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> positive(0.2, 3.0);
    RegularizationWeights w{0.3, 1.7, 0.6, {}, {}};
    w.vertex_weights = Eigen::VectorXd::NullaryExpr(x.surface.vertex_count(), [&] { return positive(rng); });
    w.face_weights = Eigen::VectorXd::NullaryExpr(x.surface.face_count(), [&] { return positive(rng); });
    const RegularizationSystem s = assemble_regularization_system(x.surface.vertices, x.surface.quads, x.links, x.normals, w);
    for (unsigned seed = 0; seed < 3; ++seed) {
        const PointMatrix q = jitter(x.surface.vertices, 0.8, seed);
        const double by_terms =
            regularization_energy(q, x.surface.vertices, x.surface.quads, x.links, x.normals, w).total(w);
        EXPECT_NEAR(matrix_energy(s, q), by_terms, 1e-9 * by_terms);
    }
}

TEST(Regularization, GradientVanishesAtTheSolutionForEverySolver) {
    const Fixture x = small_ball_with_ii_normals();
    const RegularizationWeights w;
    const RegularizationSystem s =
        assemble_regularization_system(x.surface.vertices, x.surface.quads, x.links, x.normals, w);
    PointMatrix reference;
    for (const std::string& name : solver_names()) {
        SolverOptions options;
        options.kind = parse_solver_kind(name);
        const RegularizationResult r = regularize(x.surface, x.normals, w, options);
        const Eigen::VectorXd gradient = 2 * (s.matrix * flatten_points(r.positions) - s.rhs);
        EXPECT_LT(gradient.norm(), 1e-8 * s.rhs.norm()) << name;
        EXPECT_LT(r.solve.relative_residual, 1e-8) << name;
        // A minimum: any perturbation raises the energy.
        const double e_star = r.energy_after.total(w);
        for (unsigned seed = 0; seed < 3; ++seed)
            EXPECT_GT(regularization_energy(jitter(r.positions, 1e-3, seed), x.surface.vertices, x.surface.quads, x.links,
                                            x.normals, w)
                          .total(w),
                      e_star);
        if (reference.size() == 0) reference = r.positions;
        EXPECT_LT((r.positions - reference).cwiseAbs().maxCoeff(), 1e-6) << name << " disagrees with cholmod";
    }
}

TEST(Regularization, EachTermShrinksWhenItsWeightGrows) {
    const Fixture x = small_ball_with_ii_normals();
    auto terms_with = [&](double a, double b, double g) {
        return regularize(x.surface, x.normals, RegularizationWeights{a, b, g, {}, {}}, SolverOptions{}).energy_after;
    };
    const EnergyTerms base = terms_with(1e-3, 1, 1e-2);
    EXPECT_LT(terms_with(1e-1, 1, 1e-2).data, base.data);
    EXPECT_LT(terms_with(1e-3, 10, 1e-2).alignment, base.alignment);
    EXPECT_LT(terms_with(1e-3, 1, 1).fairness, base.fairness);
    // And the regularized surface is better aligned than the digital one.
    EXPECT_LT(base.alignment, 0.05 * regularization_energy(x.surface.vertices, x.surface.vertices, x.surface.quads,
                                                           x.links, x.normals, RegularizationWeights{})
                                         .alignment);
}

TEST(Regularization, TiltedPlaneWithExactNormalsBecomesFlat) {
    const Eigen::Vector3d n = Eigen::Vector3d(1.0, 2.0, 3.0).normalized();
    const Eigen::Vector3d c = Eigen::Vector3d::Constant(13.3);
    const auto slab = test::make_volume({28, 28, 28}, [&](double x, double y, double z) {
        return n.dot(Eigen::Vector3d(x, y, z) - c) <= 0;
    });
    const auto s = extract_digital_surface(slab, Connectivity::Six);
    // Exact normals: n on the tilted part, the axis normal on the faces of the domain box.
    PointMatrix u = trivial_normals(s);
    const PointMatrix centers = surfel_centers(s);
    auto on_box = [&](const Eigen::Vector3d& p) { return (p.array() < 0.0).any() || (p.array() > 27.0).any(); };
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        if (!on_box(centers.row(f).transpose())) u.row(f) = n.transpose();
    const RegularizationResult r = regularize(s, u, RegularizationWeights{1e-5, 1, 1e-2, {}, {}}, SolverOptions{});
    // Interior vertices (away from the box edges) lie on one plane orthogonal to n.
    std::vector<double> before, after;
    for (std::int64_t i = 0; i < s.vertex_count(); ++i) {
        const Eigen::Vector3d p = s.vertices.row(i).transpose();
        if ((p.array() < 6.0).any() || (p.array() > 21.0).any()) continue;
        before.push_back(n.dot(p));
        after.push_back(n.dot(r.positions.row(i).transpose()));
    }
    ASSERT_GT(after.size(), 100u);
    auto spread = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end()); };
    EXPECT_GT(spread(before), 1.0);
    EXPECT_LT(spread(after), 1e-3);
}

TEST(Regularization, SphereVerticesMoveCloserToTheSphere) {
    const double radius = 12.3, centre = 15.5;
    const auto ball = test::make_ball(32, radius, centre);
    const auto s = extract_digital_surface(ball, Connectivity::Six);
    const PointMatrix u = integral_invariant_normals(ball, s, 4.0);
    const RegularizationResult r = regularize(s, u, RegularizationWeights{}, SolverOptions{});
    auto distances = [&](const PointMatrix& p) {
        return ((p.rowwise() - Eigen::RowVector3d::Constant(centre)).rowwise().norm().array() - radius).abs().eval();
    };
    const Eigen::ArrayXd d0 = distances(s.vertices), d1 = distances(r.positions);
    EXPECT_LT(d1.mean(), 0.5 * d0.mean());
    EXPECT_LT(d1.maxCoeff(), d0.maxCoeff());
}

TEST(Regularization, InvalidWeightsAreRejected) {
    const Fixture x = small_ball_with_ii_normals();
    for (const RegularizationWeights& w :
         {RegularizationWeights{0, 1, 1e-2, {}, {}}, RegularizationWeights{-1e-3, 1, 1e-2, {}, {}},
          RegularizationWeights{1e-3, -1, 1e-2, {}, {}}, RegularizationWeights{1e-3, 1, std::nan(""), {}, {}},
          RegularizationWeights{1e-3, 1, 1e-2, Eigen::VectorXd::Ones(3), {}}})
        EXPECT_THROW(regularize(x.surface, x.normals, w, SolverOptions{}), Error);
    EXPECT_THROW(parse_solver_kind("magic"), Error);
}

}  // namespace
}  // namespace dsreg
