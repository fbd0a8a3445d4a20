// Area metrics (W0, W2 of §3.4), local multipliers α_i, β_f, γ_i, their sources, and the
// regularization of anisotropic grids in physical coordinates.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/local_weights.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/regularization_metrics.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Area metric

TEST(AreaMetric, SphereAreaFromTheNormalFieldNotFromTheSurfelCount) {
    const double h = 0.25;
    const ImplicitShape sphere = make_shape("sphere9");
    const BinaryVolume volume = digitize(sphere, h);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const AreaMetric metric = estimate_area_metric(surface, exact_normals(sphere, surface));
    const double truth = 4 * kPi * 81;
    const double estimated = metric.face_areas.sum();
    const double surfels = double(surface.face_count()) * h * h;
    EXPECT_LT(std::abs(estimated - truth) / truth, 0.01);
    EXPECT_GT(std::abs(surfels - truth) / truth, 0.4);  // the mean of |n_x|+|n_y|+|n_z| over a sphere is 1.5
    EXPECT_NEAR(metric.vertex_areas.sum(), estimated, 1e-10 * estimated);
}

TEST(AreaMetric, TiltedPlaneAreaFromTheNormalFieldIsExact) {
    // Plane x + 2y + 3z ≤ h/2 in [-1, 1]³, digitized at h. Its digitization is invariant under the
    // lattice translations (3, 0, −1) and (0, 3, −2), which move surfel centres by (3h, 0) and
    // (0, 3h) in the x-y projection; over a window of whole periods the surfels of axes x, y, z
    // come in the ratio 1 : 2 : 3, so Σ |n · n_f| h² equals the plane's area there exactly,
    // while the surfels alone count |n_x| + |n_y| + |n_z| = 6/√14 ≈ 1.6 times that area.
    const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
    const double h = 0.02;
    // Offset ½ in units of i + 2j + 3k: no voxel centre lies on the plane, so rounding cannot
    // break the periodicity.
    const ImplicitShape plane = make_plane_shape(n, 0.5 * h / std::sqrt(14.0), 1.0);
    const int half_window = 24;  // 48 = 16 periods of 3 voxels
    const BinaryVolume volume = digitize(plane, h);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix u = solid_exact_normals(plane, surface);
    const AreaMetric metric = estimate_area_metric(surface, u);
    const PointMatrix centres = surfel_centers(surface);
    const auto in_window = [&](double coordinate) {
        const double index = coordinate / h;  // integer or half-integer
        return index >= -half_window - 0.25 && index < half_window - 0.25;
    };
    double estimated = 0, surfels = 0;
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const bool on_plane = u.row(f).dot(n) > 0.999;  // not a face of the clipping box
        if (!on_plane || !in_window(centres(f, 0)) || !in_window(centres(f, 1))) continue;
        estimated += metric.face_areas[f];
        surfels += h * h;
    }
    const double truth = std::pow(2 * half_window * h, 2) / n.z();
    EXPECT_NEAR(estimated, truth, 1e-9 * truth);
    EXPECT_NEAR(surfels, (1 + 2 + 3) / std::sqrt(14.0) * truth, 1e-9 * truth);
}

TEST(AreaMetric, DefinitionFloorAndAnisotropicFaces) {
    const BinaryVolume one_voxel = test::make_voxels({3, 3, 3}, {{1, 1, 1}});
    DigitalSurface surface = extract_digital_surface(one_voxel, Connectivity::Six);
    surface.grid.spacing = Eigen::Vector3d(1.0, 2.0, 3.0);
    PointMatrix u = trivial_normals(surface);
    u.row(0) = Eigen::RowVector3d(0.6, 0.8, 0.0);  // any unit vector; only |u · n_f| matters
    AreaMetricOptions options;
    options.min_cosine = 0.1;
    const AreaMetric metric = estimate_area_metric(surface, u, options);
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const int a = surface.surfels[std::size_t(f)].axis;
        const double face_area = surface.grid.spacing.prod() / surface.grid.spacing[a];
        const double cosine = std::max(std::abs(u(f, a)), options.min_cosine);
        EXPECT_DOUBLE_EQ(metric.face_areas[f], cosine * face_area) << "face " << f;
    }
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v) {
        double quarter_sum = 0;
        for (std::int64_t f = 0; f < surface.face_count(); ++f)
            for (int c = 0; c < 4; ++c)
                if (surface.quads(f, c) == v) quarter_sum += metric.face_areas[f] / 4;
        EXPECT_DOUBLE_EQ(metric.vertex_areas[v], quarter_sum);
        EXPECT_GT(metric.vertex_areas[v], 0);
    }
    EXPECT_THROW(estimate_area_metric(surface, u, AreaMetricOptions{0.0}), Error);
    EXPECT_THROW(estimate_area_metric(surface, PointMatrix(2, 3)), Error);
    EXPECT_EQ(parse_metric_kind("area"), MetricKind::Area);
    EXPECT_THROW(parse_metric_kind("areas"), Error);
}

TEST(AreaMetric, RegularizationWithAreaMetricSolvesAndApproachesTheSphere) {
    const double h = 0.5;
    const ImplicitShape sphere = make_shape("sphere9");
    const BinaryVolume volume = digitize(sphere, h);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(volume, surface, 3 * std::cbrt(h));
    RegularizationWeights w;
    apply_metric(MetricKind::Area, surface, u, w);
    ASSERT_EQ(w.vertex_weights.size(), surface.vertex_count());
    ASSERT_EQ(w.face_weights.size(), surface.face_count());
    const RegularizationResult r = regularize(surface, u, w, SolverOptions{});
    EXPECT_LT(r.solve.relative_residual, 1e-10);
    EXPECT_LT(r.energy_after.total(w), r.energy_before.total(w));
    const ErrorStats before = error_stats(distances_to_surface(sphere, surface.vertices));
    const ErrorStats after = error_stats(distances_to_surface(sphere, r.positions));
    EXPECT_LT(after.l2, 0.25 * before.l2);
    apply_metric(MetricKind::Identity, surface, u, w);
    EXPECT_EQ(w.vertex_weights.size() + w.face_weights.size(), 0);
}

// ---------------------------------------------------------------------------------------------
// Local multipliers

struct Ball {
    BinaryVolume volume;
    DigitalSurface surface;
    VertexLinks links;
    PointMatrix normals;
};

Ball small_ball() {
    Ball b;
    b.volume = test::make_ball(12, 4.3, 5.5);
    b.surface = extract_digital_surface(b.volume, Connectivity::TwentySix);
    b.links = vertex_links(b.surface.quads, b.surface.vertex_count());
    b.normals = integral_invariant_normals(b.volume, b.surface, 3.0);
    return b;
}

TEST(LocalWeights, MatrixEnergyEqualsTermByTermEnergy) {
    const Ball b = small_ball();
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> positive(0.1, 5.0);
    const auto random_vector = [&](std::int64_t n) { return Eigen::VectorXd(Eigen::VectorXd::NullaryExpr(n, [&] { return positive(rng); })); };
    RegularizationWeights w{0.2, 1.3, 0.7, {}, {}};
    w.vertex_weights = random_vector(b.surface.vertex_count());
    w.face_weights = random_vector(b.surface.face_count());
    w.vertex_alpha = random_vector(b.surface.vertex_count());
    w.face_beta = random_vector(b.surface.face_count());
    w.vertex_gamma = random_vector(b.surface.vertex_count());
    w.face_beta[0] = 0;  // β_f = 0 and γ_i = 0 are allowed
    w.vertex_gamma[3] = 0;
    w.fairness_targets = PointMatrix::Zero(b.surface.vertex_count(), 3);  // a target at every fifth vertex
    std::uniform_real_distribution<double> offset(-0.4, 0.4);
    for (std::int64_t i = 0; i < b.surface.vertex_count(); i += 5)
        w.fairness_targets.row(i) << offset(rng), offset(rng), offset(rng);
    const RegularizationSystem s = assemble_regularization_system(b.surface.vertices, b.surface.quads, b.links, b.normals, w);
    std::uniform_real_distribution<double> jitter(-0.7, 0.7);
    for (int trial = 0; trial < 3; ++trial) {
        PointMatrix q = b.surface.vertices;
        for (Eigen::Index i = 0; i < q.size(); ++i) q.data()[i] += jitter(rng);
        const Eigen::VectorXd x = flatten_points(q);
        const double by_matrix = x.dot(s.matrix * x) - 2 * s.rhs.dot(x) + s.constant;
        const EnergyTerms terms = regularization_energy(q, b.surface.vertices, b.surface.quads, b.links, b.normals, w);
        // Term by term, written out here with the multipliers, independently of the library.
        double data = 0, alignment = 0, fairness = 0;
        for (std::int64_t i = 0; i < b.surface.vertex_count(); ++i) {
            data += w.vertex_alpha[i] * w.vertex_weights[i] * (q.row(i) - b.surface.vertices.row(i)).squaredNorm();
            Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
            for (std::int64_t k = b.links.offsets[std::size_t(i)]; k < b.links.offsets[std::size_t(i + 1)]; ++k)
                mean += q.row(b.links.neighbors[std::size_t(k)]);
            mean /= double(b.links.size(i));
            fairness += w.vertex_gamma[i] * w.vertex_weights[i] * (q.row(i) - mean - w.fairness_targets.row(i)).squaredNorm();
        }
        for (std::int64_t f = 0; f < b.surface.face_count(); ++f)
            for (int e = 0; e < 4; ++e) {
                const double d = (q.row(b.surface.quads(f, e)) - q.row(b.surface.quads(f, (e + 1) % 4))).dot(b.normals.row(f));
                alignment += w.face_beta[f] * w.face_weights[f] * d * d;
            }
        EXPECT_NEAR(terms.data, data, 1e-10 * data);
        EXPECT_NEAR(terms.alignment, alignment, 1e-10 * alignment);
        EXPECT_NEAR(terms.fairness, fairness, 1e-10 * fairness);
        EXPECT_NEAR(by_matrix, terms.total(w), 1e-9 * terms.total(w));
    }
}

TEST(LocalWeights, FairnessTargetsAreMetByEverySolverAlike) {
    // A target t_i moves the minimizer so that the fairness residual p̂_i − mean(links) leans
    // towards t_i; the matrix-free multigrid, CHOLMOD and the assembled system solved densely by
    // Eigen must agree on that minimizer (each solver reads b from the same place, not R).
    const Ball b = small_ball();
    const std::int64_t n = b.surface.vertex_count();
    RegularizationWeights w{3e-3, 1.0, 3e-2, {}, {}};
    w.vertex_gamma = Eigen::VectorXd::Ones(n);
    w.fairness_targets = PointMatrix::Zero(n, 3);
    std::vector<std::int64_t> targeted;
    const Eigen::RowVector3d centre = b.surface.vertices.colwise().mean();
    for (std::int64_t i = 0; i < n; i += 7) {
        w.vertex_gamma[i] = 3;  // as strong as the label pipeline makes the turns of junction curves
        w.fairness_targets.row(i) = 0.2 * (b.surface.vertices.row(i) - centre).normalized();  // outwards
        targeted.push_back(i);
    }
    const RegularizationSystem system = assemble_regularization_system(b.surface.vertices, b.surface.quads, b.links, b.normals, w);
    const Eigen::VectorXd dense = Eigen::MatrixXd(system.matrix).ldlt().solve(system.rhs);
    SolverOptions amg;
    amg.kind = SolverKind::Amg;
    amg.max_error = 1e-9;
    SolverOptions cholmod;
    cholmod.kind = SolverKind::Cholmod;
    for (const SolverOptions& o : {amg, cholmod}) {
        const RegularizationResult r = regularize(b.surface, b.normals, w, o);
        EXPECT_LT((flatten_points(r.positions) - dense).lpNorm<Eigen::Infinity>(), 1e-7) << solver_name(o.kind);
    }
    RegularizationWeights untargeted = w;
    untargeted.fairness_targets.resize(0, 3);
    const PointMatrix with = regularize(b.surface, b.normals, w, cholmod).positions;
    const PointMatrix without = regularize(b.surface, b.normals, untargeted, cholmod).positions;
    // Each solution minimizes its own energy: E_t(with) ≤ E_t(without) and E_0(without) ≤ E_0(with),
    // with E_t = E_0 − 2 γ Σ c_i t_i·r_i + const (r_i the fairness residual); summed, they give
    // Σ c_i t_i·(r_i(with) − r_i(without)) ≥ 0, strictly for R positive definite. The targeted
    // vertices share c_i and |t_i|, so the residuals' gain along t_i sums to a positive number
    // (a wrong sign or factor in b breaks it; the alignment term keeps it small on this ball).
    double towards = 0;
    for (const std::int64_t i : targeted) {
        const auto residual = [&](const PointMatrix& p) {
            Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
            for (std::int64_t k = b.links.offsets[std::size_t(i)]; k < b.links.offsets[std::size_t(i + 1)]; ++k)
                mean += p.row(b.links.neighbors[std::size_t(k)]);
            return Eigen::RowVector3d(p.row(i) - mean / double(b.links.size(i)));
        };
        towards += (residual(with) - residual(without)).dot(w.fairness_targets.row(i).normalized());
    }
    EXPECT_GT(towards, 0.0);
    w.fairness_targets(0, 1) = std::nan("");
    EXPECT_THROW(validate_weights(w, n, b.surface.face_count()), Error);
    w.fairness_targets.resize(n - 1, 3);
    EXPECT_THROW(validate_weights(w, n, b.surface.face_count()), Error);
}

TEST(LocalWeights, HugeAlphaPinsARegion) {
    const Ball b = small_ball();
    RegularizationWeights w;
    w.vertex_alpha = Eigen::VectorXd::Ones(b.surface.vertex_count());
    std::vector<bool> pinned(std::size_t(b.surface.vertex_count()));
    for (std::int64_t i = 0; i < b.surface.vertex_count(); ++i) {
        pinned[std::size_t(i)] = b.surface.vertices(i, 0) > 5.5;  // the half x > centre
        if (pinned[std::size_t(i)]) w.vertex_alpha[i] = 1e9;
    }
    const RegularizationResult r = regularize(b.surface, b.normals, w, SolverOptions{});
    double pinned_move = 0, free_move = 0;
    for (std::int64_t i = 0; i < b.surface.vertex_count(); ++i) {
        const double move = (r.positions.row(i) - b.surface.vertices.row(i)).norm();
        double& largest = pinned[std::size_t(i)] ? pinned_move : free_move;
        largest = std::max(largest, move);
    }
    EXPECT_LT(pinned_move, 1e-5);
    EXPECT_GT(free_move, 0.2);
}

TEST(LocalWeights, ValidationOfTheMultipliers) {
    const Ball b = small_ball();
    const std::int64_t n = b.surface.vertex_count(), m = b.surface.face_count();
    RegularizationWeights w;
    w.vertex_alpha = Eigen::VectorXd::Ones(n);
    w.face_beta = Eigen::VectorXd::Zero(m);
    w.vertex_gamma = Eigen::VectorXd::Zero(n);
    EXPECT_NO_THROW(validate_weights(w, n, m));
    w.vertex_alpha[4] = 0;  // α_i must be > 0: the data term keeps R definite
    EXPECT_THROW(validate_weights(w, n, m), Error);
    w.vertex_alpha[4] = 1;
    w.vertex_gamma[2] = -1e-3;
    EXPECT_THROW(validate_weights(w, n, m), Error);
    w.vertex_gamma[2] = 0;
    w.face_beta.resize(m - 1);
    EXPECT_THROW(validate_weights(w, n, m), Error);
    w.face_beta = Eigen::VectorXd::Constant(m, std::nan(""));
    EXPECT_THROW(validate_weights(w, n, m), Error);
}

TEST(LocalWeights, NoiseFairnessRisesAroundFacesAgainstTheirSurfelsOnly) {
    const auto s = extract_digital_surface(test::make_ball(16, 6.5, 8), Connectivity::Six);
    const Eigen::VectorXd clean = noise_fairness_gamma(s, {}, 10, 0.02, 3);
    EXPECT_EQ(clean, Eigen::VectorXd::Ones(s.vertex_count()));
    const std::int32_t noisy_face = 0;
    const Eigen::VectorXd one = noise_fairness_gamma(s, {noisy_face}, 10, 0.02, 3);
    ASSERT_EQ(one.size(), s.vertex_count());
    // Vertex distance (in edges) from the noisy face's corners.
    std::vector<int> hops(std::size_t(s.vertex_count()), -1);
    std::vector<std::int32_t> front;
    for (int k = 0; k < 4; ++k) {
        hops[std::size_t(s.quads(noisy_face, k))] = 0;
        front.push_back(s.quads(noisy_face, k));
    }
    for (int step = 1; !front.empty(); ++step) {
        std::vector<std::int32_t> next;
        for (std::int64_t f = 0; f < s.face_count(); ++f)
            for (int k = 0; k < 4; ++k) {
                const std::int32_t a = s.quads(f, k), b = s.quads(f, (k + 1) % 4);
                for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}})
                    if (hops[std::size_t(from)] == step - 1 && hops[std::size_t(to)] < 0) {
                        hops[std::size_t(to)] = step;
                        next.push_back(to);
                    }
            }
        front = next;
    }
    std::int64_t raised = 0;
    for (std::int64_t v = 0; v < s.vertex_count(); ++v) {
        raised += one[v] > 1.0;
        EXPECT_GE(one[v], 1.0);
        EXPECT_LE(one[v], 11.0);
        if (hops[std::size_t(v)] == 0) EXPECT_DOUBLE_EQ(one[v], 11.0) << "a corner of the face: a share above 0.02";
        // Each of the 3 passes reaches the faces around the vertices reached: 2 edges further at most.
        if (hops[std::size_t(v)] > 6) EXPECT_EQ(one[v], 1.0) << "vertex " << v << ", " << hops[std::size_t(v)] << " edges away";
    }
    EXPECT_GT(raised, 20);
    EXPECT_LT(raised, s.vertex_count() / 2);
    // The gain scales the rise; 0 turns it off.
    const Eigen::VectorXd doubled = noise_fairness_gamma(s, {noisy_face}, 20, 0.02, 3);
    EXPECT_LT(((doubled.array() - 1) - 2 * (one.array() - 1)).abs().maxCoeff(), 1e-12);
    EXPECT_EQ(noise_fairness_gamma(s, {noisy_face}, 0, 0.02, 3), Eigen::VectorXd::Ones(s.vertex_count()));
    EXPECT_THROW(noise_fairness_gamma(s, {noisy_face}, -1, 0.02, 3), Error);
    EXPECT_THROW(noise_fairness_gamma(s, {noisy_face}, 10, 0, 3), Error);
    EXPECT_THROW(noise_fairness_gamma(s, {noisy_face}, 10, 0.02, -1), Error);
    EXPECT_THROW(noise_fairness_gamma(s, {std::int32_t(s.face_count())}, 10, 0.02, 3), Error);
}

TEST(LocalWeights, VolumeSampledAroundEachPointel) {
    const Ball b = small_ball();
    ScalarVolume map;
    map.grid = b.volume.grid;
    map.values.resize(std::size_t(map.grid.voxel_count()));
    const auto linear = [](double i, double j, double k) { return 1 + i + 10 * j + 100 * k; };
    for (std::int64_t k = 0; k < map.grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < map.grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < map.grid.dims[0]; ++i)
                map.values[std::size_t(map.grid.linear_index(i, j, k))] = float(linear(i, j, k));
    const Eigen::VectorXd at_vertices = sample_at_vertices(map, b.surface);
    for (std::int64_t v = 0; v < b.surface.vertex_count(); ++v) {
        // A linear field's mean over the 8 voxels around pointel (a,b,c) is its value at the
        // pointel's position (a−½, b−½, c−½) (the ball does not touch the grid's border).
        const auto p = b.surface.vertex_pointels.row(v);
        EXPECT_NEAR(at_vertices[v], linear(p[0] - 0.5, p[1] - 0.5, p[2] - 0.5), 1e-9) << "vertex " << v;
    }
    const Eigen::VectorXd at_faces = face_means(b.surface.quads, at_vertices);
    for (std::int64_t f = 0; f < b.surface.face_count(); ++f) {
        double sum = 0;
        for (int c = 0; c < 4; ++c) sum += at_vertices[b.surface.quads(f, c)];
        EXPECT_NEAR(at_faces[f], sum / 4, 1e-9);
    }
    ScalarVolume wrong_grid = map;
    wrong_grid.grid.dims[0] += 1;
    EXPECT_THROW(sample_at_vertices(wrong_grid, b.surface), Error);
}

TEST(LocalWeights, VoxelsOutsideTheGridAreLeftOut) {
    // One voxel filling a 1x1x1 grid: every pointel has only that voxel in the grid.
    const BinaryVolume volume = test::make_voxels({1, 1, 1}, {{0, 0, 0}});
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::Six);
    ScalarVolume map;
    map.grid = volume.grid;
    map.values = {7.5f};
    const Eigen::VectorXd at_vertices = sample_at_vertices(map, surface);
    ASSERT_EQ(at_vertices.size(), 8);
    for (Eigen::Index v = 0; v < at_vertices.size(); ++v) EXPECT_EQ(at_vertices[v], 7.5);
}

class LocalWeightsFiles : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               ("dsreg-weights-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }

    std::filesystem::path dir_;
};

TEST_F(LocalWeightsFiles, ValuesRoundTripExactly) {
    Eigen::VectorXd values(5);
    values << 1.0, 1.0 / 3.0, 2.5e-7, 1e300, 0.0;
    write_values_file(path("w.txt"), values);
    const Eigen::VectorXd back = read_values_file(path("w.txt"), 5, "per-vertex alpha");
    EXPECT_EQ(back, values);
}

TEST_F(LocalWeightsFiles, CommentsAndAnyWhitespace) {
    write("w.txt", "# weights\n1 2\t3\r\n\n  4 # four\n5e-1\n");
    const Eigen::VectorXd v = read_values_file(path("w.txt"), 5, "per-face beta");
    EXPECT_EQ(v, (Eigen::VectorXd(5) << 1, 2, 3, 4, 0.5).finished());
}

TEST_F(LocalWeightsFiles, MalformedFilesAreRejectedWithTheirLine) {
    write("short.txt", "1 2 3\n");
    write("long.txt", "1 2 3\n4 5 6\n");
    write("bad.txt", "1\n2\nthree\n");
    write("inf.txt", "1 inf 3\n");
    const auto message = [&](const std::string& name) {
        try {
            read_values_file(path(name), 4, "per-vertex gamma");
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("short.txt").find("3 per-vertex gamma values, 4 expected"), std::string::npos) << message("short.txt");
    EXPECT_NE(message("long.txt").find("long.txt:2: more than the 4"), std::string::npos) << message("long.txt");
    EXPECT_NE(message("bad.txt").find("bad.txt:3: 'three' is not a finite number"), std::string::npos) << message("bad.txt");
    EXPECT_NE(message("inf.txt").find("inf.txt:1:"), std::string::npos) << message("inf.txt");
    EXPECT_THROW(read_values_file(path("missing.txt"), 1, "x"), Error);
}

// ---------------------------------------------------------------------------------------------
// Anisotropic voxels: everything in physical coordinates

/// A ball of radius r centred at the origin, Gauss-digitized on a grid of the given spacing.
BinaryVolume physical_ball(double r, const Eigen::Vector3d& spacing) {
    BinaryVolume v;
    for (int d = 0; d < 3; ++d) {
        const std::int64_t half = std::int64_t(std::ceil(r / spacing[d])) + 1;
        v.grid.dims[std::size_t(d)] = 2 * half + 1;
        v.grid.origin[d] = -spacing[d] * double(half);
    }
    v.grid.spacing = spacing;
    v.mask.assign(std::size_t(v.grid.voxel_count()), 0);
    for (std::int64_t k = 0; k < v.grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < v.grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < v.grid.dims[0]; ++i)
                v.mask[std::size_t(v.grid.linear_index(i, j, k))] = v.grid.voxel_center(i, j, k).norm() <= r ? 1 : 0;
    return v;
}

/// RMS of | |p| − r | over the rows of p.
double rms_distance_to_sphere(const PointMatrix& p, double r) {
    double sum = 0;
    for (Eigen::Index i = 0; i < p.rows(); ++i) sum += std::pow(p.row(i).norm() - r, 2);
    return std::sqrt(sum / double(p.rows()));
}

TEST(AnisotropicSpacing, DigitizedSphereStaysASphere) {
    const double r = 9.0;
    double isotropic = 0;
    for (const Eigen::Vector3d& spacing : {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1, 1, 2.5)}) {
        const BinaryVolume volume = physical_ball(r, spacing);
        const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
        PointMatrix u = surfel_centers(surface);  // true normals of the sphere at the face centres
        for (Eigen::Index f = 0; f < u.rows(); ++f) u.row(f).normalize();
        const RegularizationResult result = regularize(surface, u, RegularizationWeights{}, SolverOptions{});
        const double before = rms_distance_to_sphere(surface.vertices, r);
        const double after = rms_distance_to_sphere(result.positions, r);
        SCOPED_TRACE("spacing z " + std::to_string(spacing.z()));
        EXPECT_LT(after, 0.15 * before);
        EXPECT_LT(after, 0.1);  // physical units; voxels are 1 wide in x and y
        if (spacing.z() == 1.0)
            isotropic = after;
        else
            EXPECT_LT(after, 2.0 * isotropic);
    }
}

}  // namespace
}  // namespace dsreg
