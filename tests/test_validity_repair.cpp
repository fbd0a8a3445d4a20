// The repair of the regularized mesh (validity_repair.hpp): its targets are valid, a constructed
// fold comes out valid, the result is the exact minimizer of the repaired energy over the region
// and nothing else moves, the repair stops as soon as the mesh is valid; noisy random blobs, the
// reversible mode and the real volumes of ../shared/data come out valid; the mesh is the same bits
// whatever the load average and the BLAS's thread count left by earlier code.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <dlfcn.h>
#include <omp.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>

#include "dsreg/clamped_regularization.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_validity.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/validity_repair.hpp"
#include "test_support.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

namespace {
/// The 1-minute load average that dsreg reads in this test binary while it is set (≥ 0): see
/// ValidityRepair.TheMeshIsTheSameWhateverTheLoadAndTheBlasThreads.
double simulated_load = -1;
}  // namespace

/// getloadavg for this test binary: the simulated load while one is set, the system's otherwise.
/// (dsreg once chose CHOLMOD's BLAS threads from the load average, so a run on a busy machine
/// gave another mesh than on an idle one; it must not read it again.)
extern "C" int getloadavg(double loadavg[], int nelem) noexcept {
    if (simulated_load >= 0) {
        for (int k = 0; k < nelem; ++k) loadavg[k] = simulated_load;
        return nelem;
    }
    using Real = int (*)(double[], int);
    static const Real real = reinterpret_cast<Real>(dlsym(RTLD_NEXT, "getloadavg"));
    return real ? real(loadavg, nelem) : -1;
}

namespace dsreg {
namespace {

constexpr double kPi = 3.14159265358979323846;

SolverOptions cholmod() {
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    return solver;
}

/// A digital ball of radius 9 (centre z = 10.5) whose field is tilted by 60° on the cap z > 17 (a
/// wrong field, as on a part thinner than the integral-invariant ball): the solve folds the cap.
struct TiltedCap {
    BinaryVolume volume = test::make_ball(22, 9, 10.5);
    DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    PointMatrix field;
    RegularizationResult solved;

    TiltedCap() {
        field = integral_invariant_normals(volume, surface, 3.0);
        const PointMatrix centres = surfel_centers(surface);
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            if (centres(f, 2) <= 17) continue;
            const Eigen::Vector3d n = field.row(f).transpose();
            const Eigen::Vector3d axis = n.cross(Eigen::Vector3d::UnitX()).normalized();
            field.row(f) = (Eigen::AngleAxisd(kPi / 3, axis) * n).transpose();
        }
        solved = regularize(surface, field, RegularizationWeights{}, cholmod());
    }
};

const TiltedCap& tilted_cap() {
    static const TiltedCap c;
    return c;
}

const ValidityRepairResult& tilted_cap_repair() {
    static const ValidityRepairResult r =
        repair_validity(tilted_cap().surface, tilted_cap().field, RegularizationWeights{}, tilted_cap().solved.positions);
    return r;
}

/// A blob: the union of a few random balls in a size³ grid, each surface voxel flipped with
/// probability 0.15 (noise).
BinaryVolume noisy_blob(unsigned seed, std::int64_t size = 24) {
    std::mt19937 rng(seed);
    const double scale = double(size) / 24;
    std::uniform_real_distribution<double> centre(7 * scale, 16 * scale), radius(3 * scale, 6 * scale);
    std::vector<Eigen::Vector4d> balls;
    for (int b = 0; b < 4; ++b) balls.emplace_back(centre(rng), centre(rng), centre(rng), radius(rng));
    const auto inside = [&](double x, double y, double z) {
        for (const Eigen::Vector4d& ball : balls)
            if (Eigen::Vector3d(x - ball[0], y - ball[1], z - ball[2]).norm() <= ball[3]) return true;
        return false;
    };
    BinaryVolume volume = test::make_volume({size, size, size}, inside);
    std::bernoulli_distribution flip(0.15);
    BinaryVolume noisy = volume;
    for (std::int64_t k = 1; k + 1 < size; ++k)
        for (std::int64_t j = 1; j + 1 < size; ++j)
            for (std::int64_t i = 1; i + 1 < size; ++i) {
                bool boundary = false;
                for (int d = 0; d < 3; ++d)
                    for (int s : {-1, 1}) {
                        std::int64_t n[3] = {i, j, k};
                        n[d] += s;
                        boundary = boundary || volume.inside(n[0], n[1], n[2]) != volume.inside(i, j, k);
                    }
                if (boundary && flip(rng)) {
                    auto& voxel = noisy.mask[std::size_t(noisy.grid.linear_index(i, j, k))];
                    voxel = voxel ? 0 : 1;
                }
            }
    return noisy;
}

TEST(ValidityRepair, TargetsAreAValidMeshOnRandomVolumes) {
    // The digital surface itself touches itself at every split pointel; the targets pull the copies
    // apart and are valid, for both connectivities.
    int with_split_pointels = 0;
    for (unsigned seed = 0; seed < 24; ++seed) {
        std::mt19937 rng(seed);
        std::bernoulli_distribution coin(0.3 + 0.02 * seed);
        const BinaryVolume volume = test::make_volume({8, 8, 7}, [&](double, double, double) { return coin(rng); });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
            const DigitalSurface s = extract_digital_surface(volume, c);
            SCOPED_TRACE("seed " + std::to_string(seed) + ", connectivity " + std::to_string(int(c)));
            if (s.split_pointel_count > 0) {
                ++with_split_pointels;
                EXPECT_FALSE(check_mesh_validity(s.vertices, s.quads, trivial_normals(s)).valid());
            }
            const MeshValidity v = check_mesh_validity(repair_targets(s, 0.1), s.quads, trivial_normals(s));
            EXPECT_TRUE(v.valid()) << v.intersecting_pairs << " pairs, " << v.folded_faces << " folded";
        }
    }
    EXPECT_GT(with_split_pointels, 20);
}

TEST(ValidityRepair, LiftIntoHalfSpace) {
    const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d good(0.6, 0, 0.8);
    EXPECT_EQ(lift_into_half_space(good, n, 0.2), good);
    const Eigen::Vector3d lifted = lift_into_half_space(Eigen::Vector3d(0.6, 0, -0.8), n, 0.2);
    EXPECT_NEAR(lifted.norm(), 1.0, 1e-15);
    EXPECT_NEAR(lifted.dot(n), 0.2, 1e-15);
    EXPECT_NEAR(lifted.y(), 0.0, 1e-15);  // same tangential direction (+x)
    EXPECT_GT(lifted.x(), 0.0);
    EXPECT_EQ(lift_into_half_space(-n, n, 0.2), n);
}

TEST(ValidityRepair, AConstructedFoldComesOutValid) {
    const TiltedCap& c = tilted_cap();
    const ValidityRepairResult& r = tilted_cap_repair();
    ASSERT_EQ(c.surface.split_pointel_count, 0);  // targets = digital positions below
    EXPECT_GT(r.report.before.intersecting_pairs, 0);
    EXPECT_GT(r.report.before.folded_faces, 0);
    EXPECT_TRUE(r.report.after.valid());
    EXPECT_TRUE(check_mesh_validity(r.positions, c.surface.quads, r.normals).valid());
    EXPECT_GT(r.report.rounds, 0);
    // Local: the lower third of the ball (z < 8; the cap is z > 17) is not touched.
    EXPECT_LT(r.report.region_vertices, c.surface.vertex_count());
    for (std::int64_t v = 0; v < c.surface.vertex_count(); ++v)
        if (c.surface.vertices(v, 2) < 8) EXPECT_EQ(r.positions.row(v), c.solved.positions.row(v)) << "vertex " << v;
}

TEST(ValidityRepair, AReflexCornerStrengthensItsApexOnly) {
    // A valid solved ball; then one vertex of one quad is pushed beyond the diagonal between its
    // two neighbours (the quad turns reflex there: one corner triangle against u). The repair
    // pulls that vertex, not the whole quad: its three other corners get only the graded factor.
    const BinaryVolume volume = test::make_ball(22, 9, 10.5);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix field = integral_invariant_normals(volume, surface, 3.0);
    PointMatrix positions = regularize(surface, field, RegularizationWeights{}, cholmod()).positions;
    ASSERT_TRUE(check_mesh_validity(positions, surface.quads, field).valid());
    const std::int64_t f = surface.face_count() / 2;
    const std::int32_t apex = surface.quads(f, 2);
    const Eigen::Vector3d middle = (positions.row(surface.quads(f, 1)) + positions.row(surface.quads(f, 3))).transpose() / 2;
    const Eigen::Vector3d apex_position = positions.row(apex).transpose();
    positions.row(apex) = (middle + 0.3 * (middle - apex_position)).transpose();
    const MeshValidity broken = check_mesh_validity(positions, surface.quads, field);
    ASSERT_EQ(broken.folded, (std::vector<std::int32_t>{std::int32_t(f)}));
    ASSERT_EQ(broken.intersecting_pairs, 0);
    const ValidityRepairOptions options;
    const ValidityRepairResult r = repair_validity(surface, field, RegularizationWeights{}, positions, options);
    EXPECT_TRUE(r.report.after.valid());
    const double apex_factor = r.alpha_factors[apex];
    EXPECT_GE(apex_factor, options.alpha_start);
    for (const int k : {0, 1, 3})
        EXPECT_LE(r.alpha_factors[surface.quads(f, k)], apex_factor / options.alpha_grade) << "corner " << k;
}

TEST(ValidityRepair, TheResultMinimizesTheRepairedEnergyOverTheRegionAndNothingElseMoves) {
    const TiltedCap& c = tilted_cap();
    const ValidityRepairResult& r = tilted_cap_repair();
    ASSERT_TRUE(r.report.exact);
    // E' = E with α_i × m_i and the corrected field (targets = p here): its gradient vanishes on
    // every free vertex of the region (the KKT conditions of min E' over the region, the rest held).
    RegularizationWeights repaired;
    repaired.vertex_alpha = r.alpha_factors;
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    const RegularizationSystem system =
        assemble_regularization_system(c.surface.vertices, c.surface.quads, links, r.normals, repaired);
    const Eigen::VectorXd gradient = system.matrix * flatten_points(r.positions) - system.rhs;
    std::vector<char> in_region(std::size_t(c.surface.vertex_count()), 0), held(in_region.size(), 0);
    for (const std::int32_t v : r.region) in_region[std::size_t(v)] = 1;
    for (const std::int32_t v : r.held) held[std::size_t(v)] = 1;
    double worst = 0;
    for (std::int64_t v = 0; v < c.surface.vertex_count(); ++v) {
        if (in_region[std::size_t(v)] && !held[std::size_t(v)])
            worst = std::max(worst, gradient.segment<3>(3 * v).norm());
        if (!in_region[std::size_t(v)]) EXPECT_EQ(r.positions.row(v), c.solved.positions.row(v)) << "vertex " << v;
        if (held[std::size_t(v)]) EXPECT_EQ(r.positions.row(v), r.targets.row(v));
    }
    EXPECT_LT(worst, 1e-9 * system.rhs.norm());
    EXPECT_LT(r.report.max_kkt_residual, 1e-9);
    // The field changes only on faces it corrected, each to u·n_s = field_margin.
    for (std::int64_t f = 0; f < c.surface.face_count(); ++f) {
        if (r.normals.row(f) == c.field.row(f)) continue;
        EXPECT_NEAR(r.normals.row(f).dot(c.surface.surfels[std::size_t(f)].trivial_normal().transpose()), 0.2, 1e-12);
    }
}

TEST(ValidityRepair, SmoothingFirstEndsValidAtTheMinimizerOfItsEnergy) {
    // Every vertex marked: the cap's folds first raise the fairness of their vertices (twice),
    // then, where still folded, the data term; the result minimizes E' with both factors.
    const TiltedCap& c = tilted_cap();
    ValidityRepairOptions options;
    options.smooth_first.assign(std::size_t(c.surface.vertex_count()), 1);
    const ValidityRepairResult r = repair_validity(c.surface, c.field, RegularizationWeights{}, c.solved.positions, options);
    EXPECT_TRUE(r.report.after.valid());
    EXPECT_TRUE(check_mesh_validity(r.positions, c.surface.quads, r.normals).valid());
    ASSERT_TRUE(r.report.exact);
    EXPECT_GT(r.report.smoothed_vertices, 0);
    EXPECT_LE(r.fairness_factors.maxCoeff(), options.fairness_start * options.fairness_step);
    EXPECT_GE(r.fairness_factors.minCoeff(), 1.0);
    RegularizationWeights repaired;
    repaired.vertex_alpha = r.alpha_factors;
    repaired.vertex_gamma = r.fairness_factors;
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    const RegularizationSystem system =
        assemble_regularization_system(c.surface.vertices, c.surface.quads, links, r.normals, repaired);
    const Eigen::VectorXd gradient = system.matrix * flatten_points(r.positions) - system.rhs;
    std::vector<char> free_in_region(std::size_t(c.surface.vertex_count()), 0);
    for (const std::int32_t v : r.region) free_in_region[std::size_t(v)] = 1;
    for (const std::int32_t v : r.held) free_in_region[std::size_t(v)] = 0;
    double worst = 0;
    for (std::int64_t v = 0; v < c.surface.vertex_count(); ++v)
        if (free_in_region[std::size_t(v)]) worst = std::max(worst, gradient.segment<3>(3 * v).norm());
    EXPECT_LT(worst, 1e-9 * system.rhs.norm());
    // Smoothing moves the folded cap less far back towards the voxels than the data term does.
    const ValidityRepairResult& data_first = tilted_cap_repair();
    EXPECT_EQ(data_first.report.smoothed_vertices, 0);
    EXPECT_LT(r.report.energy_after.fairness, data_first.report.energy_after.fairness);

    // Without fairness (γ = 0) there is nothing to raise: the data term at once, as without marks.
    RegularizationWeights no_fairness;
    no_fairness.gamma = 0;
    const RegularizationResult solved = regularize(c.surface, c.field, no_fairness, cholmod());
    const ValidityRepairResult plain = repair_validity(c.surface, c.field, no_fairness, solved.positions);
    const ValidityRepairResult marked = repair_validity(c.surface, c.field, no_fairness, solved.positions, options);
    EXPECT_TRUE(marked.report.after.valid());
    EXPECT_EQ(marked.report.smoothed_vertices, 0);
    EXPECT_EQ(marked.positions, plain.positions);
}

TEST(ValidityRepair, TheEnergyRisesOnlyAsMuchAsTheRepairNeeds) {
    const TiltedCap& c = tilted_cap();
    const ValidityRepairResult& r = tilted_cap_repair();
    const RegularizationWeights w;
    // p* is the unconstrained optimum: the repair can only raise E, and it says by how much.
    EXPECT_DOUBLE_EQ(r.report.energy_before.total(w), c.solved.energy_after.total(w));
    EXPECT_GT(r.report.energy_after.total(w), r.report.energy_before.total(w));
    // It stops as soon as it can: with one round less the mesh is not yet valid as the exact
    // minimizer of E' (invalid, or valid only before that last solve undid part of it).
    ValidityRepairOptions fewer;
    fewer.max_rounds = r.report.rounds - 1;
    const ValidityRepairResult short_of_it = repair_validity(c.surface, c.field, w, c.solved.positions, fewer);
    EXPECT_FALSE(short_of_it.report.after.valid() && short_of_it.report.exact);
    // Pulling every vertex as hard as the repair pulled its strongest one costs more.
    RegularizationWeights everywhere;
    everywhere.vertex_alpha = Eigen::VectorXd::Constant(c.surface.vertex_count(), r.alpha_factors.maxCoeff());
    const RegularizationResult blunt = regularize(c.surface, c.field, everywhere, cholmod());
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    const double blunt_energy =
        regularization_energy(blunt.positions, c.surface.vertices, c.surface.quads, links, c.field, w).total(w);
    EXPECT_LT(r.report.energy_after.total(w), blunt_energy);
}

TEST(ValidityRepair, AValidMeshIsLeftAlone) {
    const BinaryVolume ball = test::make_ball(16, 6, 7.5);
    const DigitalSurface s = extract_digital_surface(ball, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(ball, s, 3.0);
    const RegularizationResult solved = regularize(s, u, RegularizationWeights{}, cholmod());
    const ValidityRepairResult r = repair_validity(s, u, RegularizationWeights{}, solved.positions);
    ASSERT_TRUE(r.report.before.valid());
    EXPECT_EQ(r.report.rounds, 0);
    EXPECT_EQ(r.positions, solved.positions);
    EXPECT_EQ(r.normals, u);
    EXPECT_DOUBLE_EQ(r.report.energy_after.total(RegularizationWeights{}), solved.energy_after.total(RegularizationWeights{}));
}

TEST(ValidityRepair, NoisyRandomBlobsComeOutValid) {
    int invalid_before = 0;
    for (unsigned seed = 0; seed < 4; ++seed)
        for (Connectivity connectivity : {Connectivity::Six, Connectivity::TwentySix}) {
            LoadedVolume loaded;
            loaded.volume = noisy_blob(seed);
            loaded.description = "blob";
            PipelineOptions options;  // defaults: II normals, paper weights, repair
            options.connectivity = connectivity;
            const PipelineResult result = run_pipeline(loaded, options);
            SCOPED_TRACE("seed " + std::to_string(seed) + ", connectivity " + std::to_string(int(connectivity)));
            ASSERT_TRUE(result.validity.has_value());
            invalid_before += result.validity->before.valid() ? 0 : 1;
            EXPECT_TRUE(result.validity->after.valid());
            const MeshValidity v = check_mesh_validity(result.regularization.positions, result.surface.quads, result.field.normals);
            EXPECT_EQ(v.intersecting_pairs, 0);
            EXPECT_EQ(v.folded_faces, 0);
            EXPECT_EQ(v.degenerate_triangles, 0);
        }
    EXPECT_GT(invalid_before, 0);  // the noise does make the solve fold
}

/// A random volume (45 % of its voxels set) of side^3 voxels with a random unit field: its
/// clamped solve folds.
struct ClampedFold {
    BinaryVolume volume;
    DigitalSurface surface;
    PointMatrix field;
    ClampedRegularizationResult clamped;

    ClampedFold(std::int64_t side, unsigned seed) {
        std::mt19937 rng(seed);
        std::bernoulli_distribution coin(0.45);
        volume = test::make_volume({side, side, side}, [&](double, double, double) { return coin(rng); });
        surface = extract_digital_surface(volume, Connectivity::TwentySix);
        std::normal_distribution<double> normal(0, 1);
        field.resize(surface.face_count(), 3);
        for (std::int64_t f = 0; f < surface.face_count(); ++f)
            field.row(f) = Eigen::RowVector3d(normal(rng), normal(rng), normal(rng)).normalized();
        clamped = regularize_clamped(surface, field, RegularizationWeights{});
    }
};

TEST(ValidityRepair, TheReversibleModeStaysReversible) {
    // A random field makes the clamped solve fold; the repair keeps every vertex in its clamp box,
    // so the mesh still re-digitizes to the input.
    const ClampedFold fold(9, 5);
    const BinaryVolume& volume = fold.volume;
    const DigitalSurface& s = fold.surface;
    const PointMatrix& u = fold.field;
    const ClampedRegularizationResult& clamped = fold.clamped;
    ValidityRepairOptions options;
    options.clamp_half_width = 0.499;
    const ValidityRepairResult r = repair_validity(s, u, RegularizationWeights{}, clamped.positions, options);
    EXPECT_FALSE(r.report.before.valid());
    EXPECT_TRUE(r.report.after.valid());
    EXPECT_TRUE(r.report.converged);
    Eigen::VectorXd lower, upper;
    clamp_bounds(s, 0.499, lower, upper);
    const Eigen::VectorXd x = flatten_points(r.positions);
    EXPECT_TRUE((x.array() >= lower.array()).all() && (x.array() <= upper.array()).all());
    EXPECT_EQ(classify_voxel_centres(volume, r.positions, s.quads).wrong(), 0);
}

TEST(ValidityRepair, TheReversibleModesPartsSideBySideReachWhatOneThreadReaches) {
    // With the clamp boxes every part is a box QP factored by CHOLMOD; at two threads the parts of
    // a round are solved side by side, each with the BLAS at one thread. They share no unknown, so
    // the repair must take the same course as at one thread and end at the same positions (to
    // the rounding of the factorizations).
    const ClampedFold fold(10, 11);
    ValidityRepairOptions options;
    options.clamp_half_width = 0.499;
    const int threads = omp_get_max_threads();
    std::vector<ValidityRepairResult> runs;
    for (const int count : {1, 2}) {
        omp_set_num_threads(count);
        runs.push_back(repair_validity(fold.surface, fold.field, RegularizationWeights{}, fold.clamped.positions, options));
    }
    omp_set_num_threads(threads);
    ASSERT_GT(runs[0].report.parts_solved, 2 * runs[0].report.rounds) << "the test needs rounds of several parts";
    for (const ValidityRepairResult& r : runs) {
        EXPECT_TRUE(r.report.after.valid());
        EXPECT_TRUE(r.report.converged);
    }
    EXPECT_EQ(runs[1].report.rounds, runs[0].report.rounds);
    EXPECT_EQ(runs[1].report.parts_solved, runs[0].report.parts_solved);
    EXPECT_LT((runs[1].positions - runs[0].positions).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ValidityRepair, TheMeshIsTheSameWhateverTheLoadAndTheBlasThreads) {
    // The default pipeline on a volume that folds, three times at two threads: the machine idle
    // (load 0), busy (load 10), idle again, and OpenBLAS left by earlier code at one thread or at
    // two. The mesh (regularized and repaired) and the repair's course must be the same bits: a
    // result may depend on the thread count, never on the load or on the state of the BLAS.
    if (std::getenv("OPENBLAS_NUM_THREADS") || std::getenv("GOTO_NUM_THREADS"))
        GTEST_SKIP() << "the user chose the BLAS's thread count: dsreg keeps it, so the state set here stays";
    using SetThreads = void (*)(int);
    const auto set_blas_threads = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    const int threads = omp_get_max_threads();
    omp_set_num_threads(2);
    LoadedVolume loaded;
    loaded.volume = noisy_blob(0, 48);
    loaded.description = "blob";
    const PipelineOptions options;  // defaults: II normals, paper weights, auto solver, repair
    std::vector<PipelineResult> runs;
    for (const auto& [load, blas] : {std::pair{0.0, 2}, std::pair{10.0, 1}, std::pair{0.0, 1}}) {
        simulated_load = load;
        if (set_blas_threads) set_blas_threads(blas);
        runs.push_back(run_pipeline(loaded, options));
    }
    simulated_load = -1;
    omp_set_num_threads(threads);
    ASSERT_TRUE(runs[0].validity.has_value());
    EXPECT_FALSE(runs[0].validity->before.valid());  // there is a repair to compare
    for (std::size_t k = 1; k < runs.size(); ++k) {
        SCOPED_TRACE("run " + std::to_string(k));
        ASSERT_TRUE(runs[k].validity.has_value());
        EXPECT_EQ(runs[k].validity->rounds, runs[0].validity->rounds);
        EXPECT_EQ(runs[k].validity->parts_solved, runs[0].validity->parts_solved);
        EXPECT_TRUE(runs[k].regularization.positions == runs[0].regularization.positions)
            << "largest difference " << (runs[k].regularization.positions - runs[0].regularization.positions).cwiseAbs().maxCoeff();
        EXPECT_TRUE(runs[k].field.normals == runs[0].field.normals);
    }
}

/// A digital ball of radius 7 with single voxels added on it and taken out of it: the solve
/// smooths them away, so their centres end on the wrong side of the mesh.
BinaryVolume bumpy_ball() {
    BinaryVolume volume = test::make_ball(20, 7, 9.5);
    const auto set = [&](std::int64_t i, std::int64_t j, std::int64_t k, std::uint8_t value) {
        volume.mask[std::size_t(volume.grid.linear_index(i, j, k))] = value;
    };
    // Bumps: the voxel just outside the ball along a few directions.
    set(17, 9, 9, 1), set(2, 9, 9, 1), set(9, 17, 10, 1), set(9, 9, 17, 1), set(13, 14, 9, 1);
    // Dents: surface voxels taken out.
    set(9, 2, 9, 0), set(10, 9, 2, 0), set(14, 5, 9, 0);
    return volume;
}

/// The bumpy ball, its surface, its II normals (r = 3) and its exact solve with the paper's weights.
struct SolvedBumpyBall {
    BinaryVolume volume;
    DigitalSurface surface;
    PointMatrix normals;
    RegularizationResult solved;
};

SolvedBumpyBall solved_bumpy_ball() {
    SolvedBumpyBall ball;
    ball.volume = bumpy_ball();
    ball.surface = extract_digital_surface(ball.volume, Connectivity::TwentySix);
    ball.normals = integral_invariant_normals(ball.volume, ball.surface, 3.0);
    ball.solved = regularize(ball.surface, ball.normals, RegularizationWeights{}, cholmod());
    return ball;
}

TEST(ValidityRepair, PutsEveryVoxelCentreBackOnItsSideAtTheMinimizerWithinTheBounds) {
    const auto [volume, s, u, solved] = solved_bumpy_ball();
    const std::int64_t wrong = classify_voxel_centres(volume, solved.positions, s.quads).wrong();
    ASSERT_GT(wrong, 0) << "the bumps and dents should be smoothed away";
    ValidityRepairOptions options;
    options.voxels = &volume;
    const ValidityRepairResult r = repair_validity(s, u, RegularizationWeights{}, solved.positions, options);
    EXPECT_EQ(r.report.wrong_voxels_before, wrong);
    EXPECT_EQ(r.report.wrong_voxels_after, 0);
    EXPECT_EQ(classify_voxel_centres(volume, r.positions, s.quads).wrong(), 0);
    EXPECT_TRUE(r.report.after.valid());
    ASSERT_TRUE(r.report.exact);
    EXPECT_LT(r.report.max_kkt_residual, 1e-9);
    // Only around the wrong voxels: few vertices bounded, nothing outside the region moved.
    EXPECT_GT(r.report.bounded_vertices, 0);
    EXPECT_LT(r.report.bounded_vertices, s.vertex_count() / 4);
    std::vector<char> in_region(std::size_t(s.vertex_count()), 0);
    for (const std::int32_t v : r.region) in_region[std::size_t(v)] = 1;
    for (std::int64_t v = 0; v < s.vertex_count(); ++v)
        if (!in_region[std::size_t(v)]) EXPECT_EQ(r.positions.row(v), solved.positions.row(v)) << "vertex " << v;
    // KKT conditions of min E' over the region subject to the bounds, whichever coordinates they
    // hold: a coordinate strictly inside the slab |x − p| < ½ s (bounded or not) has a vanishing
    // gradient; one at 0.499 s from p, on a bound, is pushed outwards by the gradient; no bounded
    // coordinate is beyond it, so one beyond 0.499 is free and has a vanishing gradient too.
    RegularizationWeights repaired;
    repaired.vertex_alpha = r.alpha_factors;
    const VertexLinks links = vertex_links(s.quads, s.vertex_count());
    const RegularizationSystem system = assemble_regularization_system(s.vertices, s.quads, links, r.normals, repaired);
    const Eigen::VectorXd gradient = system.matrix * flatten_points(r.positions) - system.rhs;
    const double tolerance = 1e-8 * system.rhs.norm();
    int on_bound = 0;
    for (const std::int32_t v : r.region)
        for (int d = 0; d < 3; ++d) {
            const double offset = r.positions(v, d) - s.vertices(v, d), g = gradient[3 * v + d];
            if (std::abs(std::abs(offset) - 0.499) < 1e-12) {
                ++on_bound;
                EXPECT_LE(offset > 0 ? g : -g, tolerance) << "vertex " << v << " axis " << d;
            } else {
                EXPECT_LE(std::abs(g), tolerance) << "vertex " << v << " axis " << d << " offset " << offset;
            }
        }
    EXPECT_GT(on_bound, 0);
}

TEST(ValidityRepair, LeavesTheWrongVoxelCentresOfNoisyVerticesAsTheyAre) {
    const auto [volume, s, u, solved] = solved_bumpy_ball();
    ValidityRepairOptions options;
    options.voxels = &volume;
    options.noisy_voxels.assign(std::size_t(s.vertex_count()), 1);  // every vertex noisy
    const ValidityRepairResult r = repair_validity(s, u, RegularizationWeights{}, solved.positions, options);
    EXPECT_GT(r.report.wrong_voxels_before, 0);
    EXPECT_EQ(r.report.wrong_voxels_after, r.report.wrong_voxels_before);
    EXPECT_EQ(r.report.noisy_wrong_voxels, r.report.wrong_voxels_before);
    EXPECT_EQ(r.report.bounded_vertices, 0);
    EXPECT_TRUE(r.positions == solved.positions);
}

TEST(ValidityRepair, PutsTheVoxelCentresBackOnlyFromTheShareOfObjectVoxelsOutside) {
    const auto [volume, s, u, solved] = solved_bumpy_ball();
    PolygonMesh mesh;
    mesh.vertices = solved.positions;
    mesh.faces = s.quads;
    const VoxelClassification before = classify_voxel_centres(mesh, volume);
    const std::int64_t outside = before.object_total - before.object_correct;
    ASSERT_GT(outside, 0) << "the bumps should be smoothed away";
    const double share = double(outside) / double(volume.object_voxel_count());
    ValidityRepairOptions options;
    options.voxels = &volume;
    // Just above the share: counted, not put back, the mesh left as solved (it is valid).
    options.put_back_from_share = std::nextafter(share, 1.0);
    const ValidityRepairResult left = repair_validity(s, u, RegularizationWeights{}, solved.positions, options);
    EXPECT_EQ(left.report.outside_object_voxels_before, outside);
    EXPECT_FALSE(left.report.voxels_put_back);
    EXPECT_EQ(left.report.wrong_voxels_before, before.total - before.correct);
    EXPECT_EQ(left.report.wrong_voxels_after, left.report.wrong_voxels_before);
    EXPECT_EQ(left.report.bounded_vertices, 0);
    ASSERT_TRUE(left.report.after.valid());
    EXPECT_TRUE(left.positions == solved.positions);
    // At the share: put back, every one of them.
    options.put_back_from_share = share;
    const ValidityRepairResult back = repair_validity(s, u, RegularizationWeights{}, solved.positions, options);
    EXPECT_TRUE(back.report.voxels_put_back);
    EXPECT_EQ(back.report.wrong_voxels_after, 0);
    EXPECT_EQ(classify_voxel_centres(volume, back.positions, s.quads).wrong(), 0);
}

TEST(ValidityRepair, RejectsInconsistentInput) {
    const TiltedCap& c = tilted_cap();
    EXPECT_THROW(repair_validity(c.surface, PointMatrix(3, 3), RegularizationWeights{}, c.solved.positions), Error);
    ValidityRepairOptions bad;
    bad.alpha_step = 1;
    EXPECT_THROW(repair_validity(c.surface, c.field, RegularizationWeights{}, c.solved.positions, bad), Error);
    ValidityRepairOptions other_grid;
    const BinaryVolume small = test::make_ball(8, 3, 3.5);
    other_grid.voxels = &small;
    EXPECT_THROW(repair_validity(c.surface, c.field, RegularizationWeights{}, c.solved.positions, other_grid), Error);
}

/// The test name of a volume file: its name without ".vol", other than letters and digits as '_'.
std::string volume_test_name(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param.substr(0, info.param.find(".vol"));
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return name;
}

/// The source of a volume of ../shared/data, or nothing when the file is not there.
std::optional<VolumeSource> shared_volume(const std::string& name) {
    const std::string path = std::string(DSREG_SHARED_DATA_DIR) + "/" + name;
    if (!std::filesystem::exists(path)) return std::nullopt;
    VolumeSource source;
    source.input_path = path;
    return source;
}

// The real volumes of ../shared/data with the default pipeline: the mesh users get is valid.
class RealVolume : public ::testing::TestWithParam<std::string> {};

TEST_P(RealVolume, ComesOutValid) {
    const std::optional<VolumeSource> source = shared_volume(GetParam());
    if (!source) GTEST_SKIP() << GetParam() << " not in " << DSREG_SHARED_DATA_DIR;
    const PipelineResult result = run_pipeline(*source, PipelineOptions{});
    ASSERT_TRUE(result.validity.has_value());
    const MeshValidity v = check_mesh_validity(result.regularization.positions, result.surface.quads, result.field.normals);
    EXPECT_EQ(v.intersecting_pairs, 0) << GetParam();
    EXPECT_EQ(v.degenerate_triangles, 0) << GetParam();
    EXPECT_EQ(v.folded_faces, 0) << GetParam();
    // Exact: the minimizer of E' over the whole region, every part of it (lobster.vol's later
    // exact solves leave the parts that did not change as they were).
    if (result.validity->rounds > 0) {
        EXPECT_TRUE(result.validity->exact) << GetParam();
        EXPECT_LT(result.validity->max_kkt_residual, 1e-9) << GetParam();
    }
}

INSTANTIATE_TEST_SUITE_P(SharedData, RealVolume,
                         ::testing::Values("cat10.vol", "bunny-64.vol", "Al.100.vol", "bunny-128.vol", "lobster.vol"),
                         volume_test_name);

// The real volumes whose solved meshes leave more than 1 % of their object voxels outside
// (docs/accuracy.md): the defaults put their centres back; every voxel centre left on the wrong
// side is one left as noise, at least 99 % of the object voxels are inside, and the mesh is valid.
class RealVolumeKeepingVoxels : public ::testing::TestWithParam<std::string> {};

TEST_P(RealVolumeKeepingVoxels, PutsTheirVoxelCentresBackUnlessNoisyAndStaysValid) {
    const std::optional<VolumeSource> source = shared_volume(GetParam());
    if (!source) GTEST_SKIP() << GetParam() << " not in " << DSREG_SHARED_DATA_DIR;
    const LoadedVolume loaded = load_volume(*source);
    const PipelineResult result = run_pipeline(loaded, PipelineOptions{});
    ASSERT_TRUE(result.validity.has_value());
    const ValidityRepairReport& r = *result.validity;
    EXPECT_TRUE(r.voxels_put_back);
    EXPECT_GE(double(r.outside_object_voxels_before), kVoxelPutBackShare * double(loaded.volume.object_voxel_count()));
    EXPECT_GT(r.wrong_voxels_before, r.wrong_voxels_after);
    EXPECT_EQ(r.wrong_voxels_after, r.noisy_wrong_voxels);
    PolygonMesh mesh;
    mesh.vertices = result.regularization.positions;
    mesh.faces = result.surface.quads;
    const VoxelClassification voxels = classify_voxel_centres(mesh, loaded.volume);
    EXPECT_EQ(voxels.total - voxels.correct, r.wrong_voxels_after);
    EXPECT_GE(voxels.object_share(), 0.99);
    const MeshValidity v = check_mesh_validity(result.regularization.positions, result.surface.quads, result.field.normals);
    EXPECT_TRUE(v.valid()) << v.intersecting_pairs << " pairs, " << v.folded_faces << " folded";
    EXPECT_TRUE(r.exact);
    EXPECT_LT(r.max_kkt_residual, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(SharedData, RealVolumeKeepingVoxels, ::testing::Values("bunny-64.vol", "Al.100.vol"),
                         volume_test_name);

}  // namespace
}  // namespace dsreg
