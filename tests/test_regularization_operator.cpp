// The matrix-free regularization operator (src/regularization/regularization_operator.hpp) against
// the assembled matrix R of eq. (22–23), and the solve by connected components (mesh_parts.hpp)
// against the solve of the whole system.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "../src/regularization/block_sparse.hpp"
#include "../src/regularization/mesh_parts.hpp"
#include "../src/regularization/regularization_operator.hpp"
#include "../src/regularization/smoothed_aggregation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/regularization_metrics.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

struct Case {
    std::string name;
    DigitalSurface surface;
    PointMatrix normals;
    RegularizationWeights weights;
};

/// Two balls, a few small blobs and scattered single voxels: 2 large components and many small
/// ones (of 8 to a few dozen vertices), like the CT noise around real scans.
BinaryVolume many_components() {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> coordinate(1, 38);
    BinaryVolume v = test::make_volume({40, 40, 40}, [](double x, double y, double z) {
        const auto in_ball = [&](double cx, double cy, double cz, double r) {
            return (x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz) <= r * r;
        };
        return in_ball(12, 12, 12, 9) || in_ball(29, 28, 27, 7) || (x >= 30 && x <= 32 && y >= 4 && y <= 5 && z >= 4 && z <= 8);
    });
    for (int k = 0; k < 150; ++k) {
        const int i = coordinate(rng), j = coordinate(rng), l = coordinate(rng);
        const bool near_ball = (i - 12) * (i - 12) + (j - 12) * (j - 12) + (l - 12) * (l - 12) <= 12 * 12 ||
                               (i - 29) * (i - 29) + (j - 28) * (j - 28) + (l - 27) * (l - 27) <= 10 * 10;
        if (!near_ball) v.mask[std::size_t(v.grid.linear_index(i, j, l))] = 1;
    }
    return v;
}

Case make_case(const std::string& name, const BinaryVolume& volume, double radius) {
    Case c;
    c.name = name;
    c.surface = extract_digital_surface(volume, Connectivity::TwentySix);
    c.normals = integral_invariant_normals(volume, c.surface, radius);
    return c;
}

/// The cases: default weights; area metrics with local multipliers (some β_f = 0, some γ_i = 0);
/// no fairness term.
const std::vector<Case>& cases() {
    static const std::vector<Case> all = [] {
    std::vector<Case> all;
    all.push_back(make_case("goursat h=0.5", digitize(make_shape("goursat"), 0.5), 3 * std::cbrt(0.5)));
    Case local = make_case("many components, area metric, local weights", many_components(), 3.0);
    apply_metric(MetricKind::Area, local.surface, local.normals, local.weights);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> factor(0.2, 3.0);
    local.weights.vertex_alpha = Eigen::VectorXd::NullaryExpr(local.surface.vertex_count(), [&] { return factor(rng); });
    local.weights.face_beta = Eigen::VectorXd::NullaryExpr(local.surface.face_count(), [&] { return factor(rng); });
    local.weights.vertex_gamma = Eigen::VectorXd::NullaryExpr(local.surface.vertex_count(), [&] { return factor(rng); });
    for (Eigen::Index f = 0; f < local.weights.face_beta.size(); f += 7) local.weights.face_beta[f] = 0;
    for (Eigen::Index i = 0; i < local.weights.vertex_gamma.size(); i += 5) local.weights.vertex_gamma[i] = 0;
    all.push_back(std::move(local));
    Case no_fairness = make_case("ball, gamma = 0", test::make_ball(20, 7.0, 9.5), 3.0);
    no_fairness.weights.gamma = 0;
    all.push_back(std::move(no_fairness));
    return all;
    }();
    return all;
}

TEST(RegularizationOperator, ProductEqualsTheAssembledMatrix) {
    std::mt19937 rng(5);
    std::normal_distribution<double> normal;
    for (const Case& c : cases()) {
        const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
        const RegularizationSystem system = assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, c.weights);
        const detail::RegularizationOperator R(c.surface.quads, links, c.normals, c.weights, c.surface.vertex_count());
        for (int trial = 0; trial < 3; ++trial) {
            const Eigen::VectorXd x = Eigen::VectorXd::NullaryExpr(system.rhs.size(), [&] { return normal(rng); });
            Eigen::VectorXd y;
            R.multiply(x, y);
            const Eigen::VectorXd expected = system.matrix * x;
            EXPECT_LE((y - expected).norm(), 1e-13 * expected.norm()) << c.name;
        }
        // Translations: R t = α W0_α t (the alignment and fairness terms annihilate them).
        const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(system.rhs.size(), 0, double(system.rhs.size() - 1))
                                      .unaryExpr([](double q) { return std::fmod(q, 3.0) == 1.0 ? 1.0 : 0.0; });
        Eigen::VectorXd y;
        R.multiply(t, y);
        for (Eigen::Index i = 0; i < c.surface.vertex_count(); ++i)
            EXPECT_NEAR(y[3 * i + 1], c.weights.alpha * detail::data_weight(c.weights, i), 1e-12) << c.name;
    }
}

/// The complex of test::sectors_and_small_parts() with the pipeline's label field (integral
/// invariants of each face's inner label, interface normals near the junctions) and γ = 1, where
/// the fairness term weighs.
struct LabelCase {
    DigitalSurface surface;
    VertexLinks links;  ///< fairness_links: junction-aware
    PointMatrix normals;
    RegularizationWeights weights;
};

const LabelCase& label_case() {
    static const LabelCase c = [] {
        LabelCase c;
        const LabelVolume labels = test::sectors_and_small_parts();
        c.surface = extract_digital_surface(labels, Connectivity::TwentySix);
        c.links = fairness_links(c.surface);
        c.normals = integral_invariant_normals(labels, c.surface, 3.0);
        use_interface_normals_near_junctions(labels, c.surface, 3.0, c.normals);
        c.weights.gamma = 1.0;
        return c;
    }();
    return c;
}

TEST(RegularizationOperator, OnALabelComplexProductEqualsTheAssembledMatrixOfTheJunctionLinks) {
    const LabelCase& c = label_case();
    const Junctions junctions = find_junctions(c.surface, complex_edges(c.surface));
    ASSERT_GT(junctions.point_count, 0);
    ASSERT_GT(junctions.vertex_count - junctions.point_count, 0) << "junction curves (two links) needed";
    ASSERT_NE(c.links.neighbors, vertex_links(c.surface.quads, c.surface.vertex_count()).neighbors);
    std::mt19937 rng(17);
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> factor(0.2, 3.0);
    RegularizationWeights local = c.weights;
    local.face_beta = Eigen::VectorXd::NullaryExpr(c.surface.face_count(), [&] { return factor(rng); });
    local.vertex_gamma = Eigen::VectorXd::NullaryExpr(c.surface.vertex_count(), [&] { return factor(rng); });
    for (Eigen::Index i = 0; i < local.vertex_gamma.size(); i += 5) local.vertex_gamma[i] = 0;
    for (const RegularizationWeights& w : {c.weights, RegularizationWeights{}, local}) {
        const RegularizationSystem system = assemble_regularization_system(c.surface.vertices, c.surface.quads, c.links, c.normals, w);
        const detail::RegularizationOperator R(c.surface.quads, c.links, c.normals, w, c.surface.vertex_count());
        for (int trial = 0; trial < 3; ++trial) {
            const Eigen::VectorXd x = Eigen::VectorXd::NullaryExpr(system.rhs.size(), [&] { return normal(rng); });
            Eigen::VectorXd y;
            R.multiply(x, y);
            const Eigen::VectorXd expected = system.matrix * x;
            EXPECT_LE((y - expected).norm(), 1e-13 * expected.norm());
            // and both are the Hessian of eq. (1) summed term by term over the same links:
            // E(p̂) = p̂ᵀR p̂ − 2 bᵀp̂ + c
            const PointMatrix candidate = c.surface.vertices + 0.5 * unflatten_points(x);
            const Eigen::VectorXd q = flatten_points(candidate);
            Eigen::VectorXd Rq;
            R.multiply(q, Rq);
            const double by_terms = regularization_energy(candidate, c.surface.vertices, c.surface.quads, c.links, c.normals, w).total(w);
            EXPECT_NEAR(q.dot(Rq) - 2 * system.rhs.dot(q) + system.constant, by_terms, 1e-9 * by_terms);
        }
    }
}

/// The columns for_each_coupled visits at vertex j, each once.
std::set<std::int32_t> coupled_columns(const detail::RegularizationOperator& R, std::int64_t j) {
    std::set<std::int32_t> columns;
    R.for_each_coupled(j, [&](std::int32_t c) { columns.insert(c); });
    return columns;
}

/// The vertex coupling that splits the repair's regions into independent parts: the columns
/// visited are those of the block row, and they hold every non-zero of the rows of R as eq.
/// (22–23) assembles it term by term (assemble_regularization_system, not the operator's rows;
/// on the binary cases and on the label complex, whose junction vertices are linked along their
/// curves only).
void expect_coupling_covers_the_matrix(const DigitalSurface& surface, const VertexLinks& links, const PointMatrix& normals,
                                       const RegularizationWeights& weights) {
    const std::int64_t vertex_count = surface.vertex_count();
    const detail::RegularizationOperator R(surface.quads, links, normals, weights, vertex_count);
    const Eigen::SparseMatrix<double> matrix =  // symmetric: column 3j + a holds row 3j + a
        assemble_regularization_system(surface.vertices, surface.quads, links, normals, weights).matrix;
    detail::RegularizationOperator::Row row(vertex_count);
    for (std::int64_t j = 0; j < vertex_count; ++j) {
        const std::set<std::int32_t> coupled = coupled_columns(R, j);
        for (int a = 0; a < 3; ++a)
            for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, 3 * j + a); it; ++it)
                if (it.value() != 0) ASSERT_TRUE(coupled.count(std::int32_t(it.row() / 3))) << "vertex " << j;
        R.row(j, row, false);
        ASSERT_EQ(coupled, std::set<std::int32_t>(row.columns.begin(), row.columns.end())) << "vertex " << j;
    }
}

TEST(RegularizationOperator, CoupledColumnsAreTheRowsColumnsAndHoldEveryNonZero) {
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        expect_coupling_covers_the_matrix(c.surface, vertex_links(c.surface.quads, c.surface.vertex_count()), c.normals,
                                          c.weights);
    }
    const LabelCase& c = label_case();
    expect_coupling_covers_the_matrix(c.surface, c.links, c.normals, c.weights);
}

TEST(RegularizationOperator, SummaryAndFineLevelEqualThoseOfTheAssembledMatrix) {
    for (const Case& c : cases()) {
        const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
        const RegularizationSystem system = assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, c.weights);
        const detail::RegularizationOperator R(c.surface.quads, links, c.normals, c.weights, c.surface.vertex_count());
        const detail::RegularizationOperator::Summary summary = R.summary();
        const detail::ScalarRows rows = detail::row_view(system.matrix);
        const std::vector<Eigen::Matrix3d> diagonal = detail::diagonal_blocks(rows);
        ASSERT_EQ(summary.diagonal.size(), diagonal.size());
        for (std::size_t i = 0; i < diagonal.size(); ++i) EXPECT_EQ(summary.diagonal[i], diagonal[i]) << c.name << ", vertex " << i;
        EXPECT_EQ(summary.scalar_nonzeros, double(system.matrix.nonZeros())) << c.name;
        double largest = 0;
        for (Eigen::Index r = 0; r < rows.rows(); ++r) largest = std::max(largest, rows.row(r).cwiseAbs().sum());
        EXPECT_NEAR(summary.infinity_norm, largest, 1e-14 * largest) << c.name;

        // The multigrid fine level: R without its weak blocks, built from either form.
        const double theta = detail::AmgSettings{}.strength_threshold;
        const Eigen::SparseMatrix<double> from_operator = detail::filtered_fine_level<double>(R, summary.diagonal, theta).to_scalar();
        Eigen::SparseMatrix<double> from_matrix = detail::filtered_blocks(rows, [&] {
            // the strong graph of R as solve_spd's hierarchy builds it: block norms against the threshold
            detail::StrengthGraph g;
            std::vector<double> scratch(std::size_t(rows.rows() / 3), 0.0);
            detail::BlockRowNorms norms;
            for (Eigen::Index i = 0; i < rows.rows() / 3; ++i) {
                detail::block_row_norms(rows, i, scratch, norms);
                for (std::size_t q = 0; q < norms.neighbor.size(); ++q) {
                    const std::int32_t j = norms.neighbor[q];
                    if (norms.norm[q] >= theta * std::sqrt(diagonal[std::size_t(i)].norm() * diagonal[std::size_t(j)].norm()))
                        g.neighbour.push_back(j);
                }
                g.start.push_back(std::int64_t(g.neighbour.size()));
            }
            return g;
        }()).to_scalar();
        EXPECT_LE((from_operator - from_matrix).norm(), 1e-14 * from_matrix.norm()) << c.name;
    }
}

TEST(MeshParts, EveryVertexAndFaceIsInOnePartAndNoFaceCrossesParts) {
    const Case c = make_case("many components", many_components(), 3.0);
    const std::int64_t small = 400;
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    const std::vector<detail::MeshPart> parts = detail::mesh_parts(c.surface.quads, links, c.surface.vertex_count(), small, 500);
    ASSERT_GT(parts.size(), 3u);
    std::vector<int> part_of_vertex(std::size_t(c.surface.vertex_count()), -1), faces_seen(std::size_t(c.surface.face_count()), 0);
    std::int32_t components = 0;
    for (std::size_t p = 0; p < parts.size(); ++p) {
        components += parts[p].components;
        EXPECT_FALSE(parts[p].whole);
        if (!parts[p].small) EXPECT_EQ(parts[p].components, 1);
        if (parts[p].small) EXPECT_LE(std::int64_t(parts[p].vertices.size()), 500 + small);
        if (p > 0 && !parts[p].small) EXPECT_LE(parts[p].vertices.size(), parts[p - 1].vertices.size());
        for (std::int32_t v : parts[p].vertices) {
            EXPECT_EQ(part_of_vertex[std::size_t(v)], -1);
            part_of_vertex[std::size_t(v)] = int(p);
        }
        for (std::int32_t f : parts[p].faces) ++faces_seen[std::size_t(f)];
    }
    EXPECT_EQ(components, c.surface.component_count);
    for (int v : part_of_vertex) EXPECT_GE(v, 0);
    for (std::size_t p = 0; p < parts.size(); ++p)
        for (std::int32_t f : parts[p].faces) {
            EXPECT_EQ(faces_seen[std::size_t(f)], 1);
            for (Eigen::Index e = 0; e < 4; ++e) EXPECT_EQ(part_of_vertex[std::size_t(c.surface.quads(f, e))], int(p));
        }
    // A one-component mesh is one whole part.
    const Case ball = make_case("ball", test::make_ball(16, 5.0, 7.5), 3.0);
    const std::vector<detail::MeshPart> one = detail::mesh_parts(
        ball.surface.quads, vertex_links(ball.surface.quads, ball.surface.vertex_count()), ball.surface.vertex_count(), small, 500);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_TRUE(one.front().whole);
}

TEST(MeshParts, ALinkJoinsTwoComponentsAndPartsKeepTheirLinks) {
    // R couples the two ends of a link (the fairness term), so they must be solved together,
    // whether or not a face joins them.
    const Case c = make_case("many components", many_components(), 3.0);
    const std::int64_t n = c.surface.vertex_count();
    const VertexLinks links = vertex_links(c.surface.quads, n);
    const std::vector<detail::MeshPart> separate = detail::mesh_parts(c.surface.quads, links, n, 0, 0);
    ASSERT_GT(separate.size(), 2u);
    const std::int32_t a = separate[0].vertices.front(), b = separate[1].vertices.front();
    VertexLinks joined;  // b added to the link of a
    joined.offsets = links.offsets;
    joined.neighbors = links.neighbors;
    joined.neighbors.insert(joined.neighbors.begin() + links.offsets[std::size_t(a) + 1], b);
    for (std::int64_t i = a + 1; i <= n; ++i) ++joined.offsets[std::size_t(i)];
    const std::vector<detail::MeshPart> parts = detail::mesh_parts(c.surface.quads, joined, n, 0, 0);
    ASSERT_EQ(parts.size(), separate.size() - 1);
    const auto part_of = [&](std::int32_t v) {
        for (std::size_t p = 0; p < parts.size(); ++p)
            if (std::binary_search(parts[p].vertices.begin(), parts[p].vertices.end(), v)) return p;
        return parts.size();
    };
    ASSERT_EQ(part_of(a), part_of(b));
    // Each part's links, in local indices, are the global links in the same order.
    for (const detail::MeshPart& part : parts) {
        const detail::PartMesh mesh = extract_part(part, c.surface.vertices, c.surface.quads, joined, c.normals, c.weights);
        ASSERT_EQ(mesh.links.offsets.size(), part.vertices.size() + 1);
        for (std::size_t i = 0; i < part.vertices.size(); ++i) {
            const std::int32_t g = part.vertices[i];
            ASSERT_EQ(mesh.links.size(std::int64_t(i)), joined.size(g));
            for (std::int64_t q = 0; q < joined.size(g); ++q)
                EXPECT_EQ(part.vertices[std::size_t(mesh.links.neighbors[std::size_t(mesh.links.offsets[i] + q)])],
                          joined.neighbors[std::size_t(joined.offsets[std::size_t(g)] + q)]);
        }
    }
}

/// Largest vertex distance between two n×3 point sets.
double max_distance(const PointMatrix& a, const PointMatrix& b) { return (a - b).rowwise().norm().maxCoeff(); }

TEST(Regularize, SolvingComponentByComponentGivesTheSolutionOfTheWholeSystem) {
    for (const Case& c : cases()) {
        const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
        const RegularizationSystem system = assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, c.weights);
        Eigen::VectorXd exact = flatten_points(c.surface.vertices);
        SolverOptions direct;
        direct.kind = SolverKind::Cholmod;
        solve_spd(system.matrix, system.rhs, exact, direct);
        for (SolverKind kind : {SolverKind::Cholmod, SolverKind::Auto, SolverKind::Amg, SolverKind::ConjugateGradient}) {
            if (kind == SolverKind::ConjugateGradient && c.weights.gamma > 0) continue;  // hundreds of iterations: one case is enough
            SolverOptions options;
            options.kind = kind;
            options.max_error_voxels = kDefaultMaxErrorVoxels;
            const RegularizationResult r = regularize(c.surface, c.normals, c.weights, options);
            const std::string what = c.name + ", " + solver_name(kind);
            // every vertex within the reported bound, and the bound within the requested accuracy
            const double distance = max_distance(r.positions, unflatten_points(exact));
            EXPECT_LE(distance, std::max(r.solve.error_bound, 1e-12) * (1 + 1e-6)) << what;
            EXPECT_LE(r.solve.error_bound, kDefaultMaxErrorVoxels) << what;
            if (kind == SolverKind::Cholmod) EXPECT_LE(distance, 1e-9) << what;
            // the reported residual is that of the whole system
            const double residual = (system.matrix * flatten_points(r.positions) - system.rhs).norm() / system.rhs.norm();
            EXPECT_NEAR(r.solve.relative_residual, residual, 1e-6 * residual + 1e-12) << what;
        }
    }
}

TEST(Regularize, OnALabelMapEverySolverReachesTheDirectSolveOfTheJunctionAwareSystem) {
    const LabelCase& c = label_case();
    const std::vector<detail::MeshPart> parts = detail::mesh_parts(c.surface.quads, c.links, c.surface.vertex_count(),
                                                                   detail::kSmallComponentVertices, detail::kBatchVertices);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_FALSE(parts[0].small);
    EXPECT_TRUE(parts[1].small);
    EXPECT_EQ(parts[1].components, 2);
    const auto direct_solve = [&](const VertexLinks& links) {
        const RegularizationSystem system = assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, c.weights);
        Eigen::VectorXd x = flatten_points(c.surface.vertices);
        SolverOptions direct;
        direct.kind = SolverKind::Cholmod;
        solve_spd(system.matrix, system.rhs, x, direct);
        return unflatten_points(x);
    };
    const PointMatrix exact = direct_solve(c.links);
    // the junction links matter here: with the quad links the minimizer is another one
    ASSERT_GT(max_distance(exact, direct_solve(vertex_links(c.surface.quads, c.surface.vertex_count()))), 1e-2);
    for (SolverKind kind : {SolverKind::Cholmod, SolverKind::Auto, SolverKind::Amg, SolverKind::ConjugateGradient}) {
        SolverOptions options;
        options.kind = kind;
        options.max_error_voxels = kDefaultMaxErrorVoxels;
        const RegularizationResult r = regularize(c.surface, c.normals, c.weights, options);
        const std::string what = solver_name(kind);
        const double distance = max_distance(r.positions, exact);
        EXPECT_LE(distance, std::max(r.solve.error_bound, 1e-12) * (1 + 1e-6)) << what;
        EXPECT_LE(r.solve.error_bound, kDefaultMaxErrorVoxels) << what;
        if (kind == SolverKind::Cholmod) EXPECT_LE(distance, 1e-9) << what;
        if (kind == SolverKind::Amg) EXPECT_EQ(r.solve.solver, "amg");
        EXPECT_NEAR(r.energy_after.total(c.weights),
                    regularization_energy(exact, c.surface.vertices, c.surface.quads, c.links, c.normals, c.weights).total(c.weights),
                    1e-6 * r.energy_after.total(c.weights))
            << what;
    }
}

TEST(Regularize, SmallComponentsAreSolvedDirectlyAndSaidSo) {
    const Case c = make_case("many components", many_components(), 3.0);
    SolverOptions options;
    options.kind = SolverKind::Amg;
    options.max_error_voxels = kDefaultMaxErrorVoxels;
    const RegularizationResult r = regularize(c.surface, c.normals, c.weights, options);
    EXPECT_EQ(r.solve.solver, "amg");  // the largest component's solver
    EXPECT_GT(r.solve.iterations, 0);
    EXPECT_NE(r.solve.note.find("small components"), std::string::npos) << r.solve.note;
}

}  // namespace
}  // namespace dsreg
