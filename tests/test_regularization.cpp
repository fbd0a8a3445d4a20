#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <omp.h>

#include <algorithm>
#include <cmath>
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

/// R assembled term by term from eq. (1) with triplets, independently of the block assembly:
/// α α_i w0_i I3 on (i,i); γ γ_i w0_i F_iᵀF_i ⊗ I3 for each row F_i of I − B; β β_f w2_f u uᵀ with
/// signs on (a,a), (b,b), (a,b), (b,a) for every edge (a,b) of every face f.
Eigen::SparseMatrix<double> reference_matrix(const DigitalSurface& s, const VertexLinks& links, const PointMatrix& u,
                                             const RegularizationWeights& w) {
    const auto one_or = [](const Eigen::VectorXd& v, Eigen::Index i) { return v.size() ? v[i] : 1.0; };
    std::vector<Eigen::Triplet<double>> t;
    const auto add_scalar = [&](Eigen::Index a, Eigen::Index b, double v) {
        for (int d = 0; d < 3; ++d) t.emplace_back(3 * a + d, 3 * b + d, v);
    };
    const auto add_block = [&](Eigen::Index a, Eigen::Index b, const Eigen::Matrix3d& m) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) t.emplace_back(3 * a + r, 3 * b + c, m(r, c));
    };
    for (Eigen::Index i = 0; i < s.vertex_count(); ++i) {
        add_scalar(i, i, w.alpha * one_or(w.vertex_alpha, i) * one_or(w.vertex_weights, i));
        if (links.size(i) == 0) continue;
        std::vector<std::pair<Eigen::Index, double>> row{{i, 1.0}};
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            row.emplace_back(links.neighbors[std::size_t(q)], -1.0 / double(links.size(i)));
        const double g = w.gamma * one_or(w.vertex_gamma, i) * one_or(w.vertex_weights, i);
        for (const auto& [a, fa] : row)
            for (const auto& [b, fb] : row) add_scalar(a, b, g * fa * fb);
    }
    for (Eigen::Index f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d n = u.row(f).transpose();
        const Eigen::Matrix3d m = w.beta * one_or(w.face_beta, f) * one_or(w.face_weights, f) * n * n.transpose();
        for (Eigen::Index e = 0; e < s.quads.cols(); ++e) {
            const Eigen::Index a = s.quads(f, e), b = s.quads(f, (e + 1) % s.quads.cols());
            add_block(a, a, m);
            add_block(b, b, m);
            add_block(a, b, -m);
            add_block(b, a, -m);
        }
    }
    Eigen::SparseMatrix<double> r(3 * s.vertex_count(), 3 * s.vertex_count());
    r.setFromTriplets(t.begin(), t.end());
    return r;
}

TEST(Regularization, BlockAssemblyEqualsTermByTermAssemblyAndIsExactlySymmetric) {
    const Fixture x = small_ball_with_ii_normals();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> positive(0.2, 3.0);
    std::bernoulli_distribution zero(0.2);
    const auto random_vector = [&](Eigen::Index size, bool zeros) {
        return Eigen::VectorXd::NullaryExpr(size, [&] { return zeros && zero(rng) ? 0.0 : positive(rng); }).eval();
    };
    RegularizationWeights local{0.3, 1.7, 0.6, {}, {}};
    local.vertex_weights = random_vector(x.surface.vertex_count(), false);
    local.face_weights = random_vector(x.surface.face_count(), false);
    local.vertex_alpha = random_vector(x.surface.vertex_count(), false);
    local.face_beta = random_vector(x.surface.face_count(), true);     // some faces without alignment
    local.vertex_gamma = random_vector(x.surface.vertex_count(), true);  // some vertices without fairness
    for (const RegularizationWeights& w :
         {RegularizationWeights{}, RegularizationWeights{1e-5, 1, 0, {}, {}}, RegularizationWeights{1e-3, 0, 1e-2, {}, {}}, local}) {
        const RegularizationSystem s = assemble_regularization_system(x.surface.vertices, x.surface.quads, x.links, x.normals, w);
        const Eigen::SparseMatrix<double> reference = reference_matrix(x.surface, x.links, x.normals, w);
        EXPECT_LE((s.matrix - reference).norm(), 1e-14 * reference.norm());
        const Eigen::SparseMatrix<double> transposed = s.matrix.transpose();
        EXPECT_EQ((s.matrix - transposed).norm(), 0.0) << "R must be exactly symmetric (the solvers read its CSC as CSR)";
        EXPECT_TRUE(s.matrix.isCompressed());
        // No entry is stored twice and columns are sorted in each column of the CSC arrays.
        for (Eigen::Index c = 0; c < s.matrix.outerSize(); ++c)
            for (int q = s.matrix.outerIndexPtr()[c] + 1; q < s.matrix.outerIndexPtr()[c + 1]; ++q)
                ASSERT_LT(s.matrix.innerIndexPtr()[q - 1], s.matrix.innerIndexPtr()[q]);
    }
}

TEST(Regularization, MatrixEnergyEqualsTermByTermEnergyOnAVolumeFromTheShapes) {
    // A larger surface (assembled in parallel) with split pointels and every local weight.
    const auto volume = test::make_volume({30, 28, 26}, [](double x, double y, double z) {
        return std::sin(0.7 * x) + std::cos(0.5 * y) + 0.3 * std::sin(0.9 * z) > 0.2;
    });
    Fixture x;
    x.surface = extract_digital_surface(volume, Connectivity::TwentySix);
    x.links = vertex_links(x.surface.quads, x.surface.vertex_count());
    x.normals = integral_invariant_normals(volume, x.surface, 2.5);
    ASSERT_GT(x.surface.vertex_count(), 4096) << "large enough for the parallel assembly";
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> positive(0.2, 3.0);
    RegularizationWeights w{2e-3, 1.3, 0.2, {}, {}};
    w.vertex_weights = Eigen::VectorXd::NullaryExpr(x.surface.vertex_count(), [&] { return positive(rng); });
    w.face_beta = Eigen::VectorXd::NullaryExpr(x.surface.face_count(), [&] { return positive(rng); });
    w.vertex_gamma = Eigen::VectorXd::NullaryExpr(x.surface.vertex_count(), [&] { return positive(rng); });
    const RegularizationSystem s = assemble_regularization_system(x.surface.vertices, x.surface.quads, x.links, x.normals, w);
    EXPECT_LE((s.matrix - reference_matrix(x.surface, x.links, x.normals, w)).norm(), 1e-14 * s.matrix.norm());
    for (unsigned seed = 0; seed < 3; ++seed) {
        const PointMatrix q = jitter(x.surface.vertices, 0.8, seed);
        const double by_terms = regularization_energy(q, x.surface.vertices, x.surface.quads, x.links, x.normals, w).total(w);
        EXPECT_NEAR(matrix_energy(s, q), by_terms, 1e-9 * by_terms);
    }
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
        options.max_error_voxels = kDefaultMaxErrorVoxels;  // as the dsreg command does
        const RegularizationResult r = regularize(x.surface, x.normals, w, options);
        const Eigen::VectorXd gradient = 2 * (s.matrix * flatten_points(r.positions) - s.rhs);
        EXPECT_LT(gradient.norm(), 1e-6 * s.rhs.norm()) << name;
        EXPECT_LE(r.solve.error_bound, kDefaultMaxErrorVoxels * x.surface.grid.spacing.minCoeff()) << name;
        // A minimum: any perturbation raises the energy.
        const double e_star = r.energy_after.total(w);
        for (unsigned seed = 0; seed < 3; ++seed)
            EXPECT_GT(regularization_energy(jitter(r.positions, 1e-3, seed), x.surface.vertices, x.surface.quads, x.links,
                                            x.normals, w)
                          .total(w),
                      e_star);
        if (reference.size() == 0) reference = r.positions;
        EXPECT_LT((r.positions - reference).rowwise().norm().maxCoeff(), 1e-4) << name << " disagrees with cholmod (1e-4 voxel)";
    }
}

TEST(Regularization, EnergyAndRightHandSideAreTheSameBitsAtEveryThreadCount) {
    // A ball of some 20 000 vertices and faces (the sums run in blocks of 4 096 terms, in parallel):
    // the energy terms and the constant of E are summed in an order fixed by the mesh, so 1 to 4
    // threads give the same bits (an OpenMP reduction adds the threads' partial sums in the order
    // they finish, over ranges that depend on the thread count).
    const auto ball = test::make_ball(84, 40, 41.5);
    const DigitalSurface s = extract_digital_surface(ball, Connectivity::Six);
    ASSERT_GT(s.vertex_count(), 4 * 4096);
    const VertexLinks links = vertex_links(s.quads, s.vertex_count());
    const PointMatrix u = trivial_normals(s), q = jitter(s.vertices, 0.3, 7);
    RegularizationWeights w;
    w.vertex_alpha = Eigen::VectorXd::LinSpaced(s.vertex_count(), 0.5, 3.0);
    const int threads = omp_get_max_threads();
    std::vector<EnergyTerms> energies;
    std::vector<double> constants;
    for (int t = 1; t <= 4; ++t) {
        omp_set_num_threads(t);
        energies.push_back(regularization_energy(q, s.vertices, s.quads, links, u, w));
        constants.push_back(regularization_right_hand_side(q, links, w).constant);
    }
    omp_set_num_threads(threads);
    for (std::size_t k = 1; k < energies.size(); ++k) {
        SCOPED_TRACE(std::to_string(k + 1) + " threads");
        EXPECT_EQ(energies[k].data, energies[0].data);
        EXPECT_EQ(energies[k].fairness, energies[0].fairness);
        EXPECT_EQ(energies[k].alignment, energies[0].alignment);
        EXPECT_EQ(constants[k], constants[0]);
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
