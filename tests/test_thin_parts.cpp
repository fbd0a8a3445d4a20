// Thin parts with the default pipeline (no option): a torus whose tube is 1.5 voxels in radius and
// an ellipsoidal shell 2 voxels thick keep their volume (within 3 % of the true solid's) and their
// voxels (99 % of the voxel centres next to the surface, inside and outside, on the right side).
// Also the two corrections behind it: the thin-part data weights and the shrink correction.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "dsreg/adaptive_normals.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/local_weights.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/local_reach.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/shrink_correction.hpp"
#include "dsreg/thin_part_shape.hpp"
#include "../src/pipeline/pipeline_stages.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

/// A polynomial shape (F ≤ 0 inside) of the box [−box, box]³, digitized at h = 0.25.
VolumeSource shape_at_quarter_step(const char* polynomial, double box) {
    VolumeSource source;
    source.shape = polynomial;
    source.box = box;
    source.h = 0.25;
    return source;
}

/// The regularized mesh of a pipeline run.
PolygonMesh solved_mesh(const PipelineResult& result) {
    return PolygonMesh{result.regularization.positions, result.surface.quads, {}, {}};
}

/// The narrow average alone (no wide one), with an optional local share.
ShrinkAveraging narrow_average(int steps, const Eigen::VectorXd& local_share = {}, int local_steps = 0) {
    ShrinkAveraging a;
    a.steps = steps;
    a.wide_steps = 0;
    a.local_share = local_share;
    a.local_steps = local_steps;
    return a;
}

struct ThinCase {
    const char* polynomial;
    double box;
    bool tube;
};

TEST(ThinParts, TubeAndShellKeepTheirVolumeAndVoxelsWithTheDefaults) {
    const ThinCase cases[] = {
        {"(x^2+y^2+z^2+9-0.140625)^2-36*(x^2+y^2)", 3.6, true},  // tube radius 0.375 = 1.5 voxels
        {"(0.1111111*x^2+0.25*y^2+0.4444444*z^2-1)*(0.0816327*x^2+0.16*y^2+0.25*z^2-1)", 4, false},  // 2 voxels thick
    };
    for (const ThinCase& c : cases) {
        const VolumeSource source = shape_at_quarter_step(c.polynomial, c.box);
        const PipelineResult result = run_pipeline(source, PipelineOptions{});
        const ImplicitShape shape = make_shape(c.polynomial, c.box);
        const PolygonMesh mesh = solved_mesh(result);
        const double truth = shape_volume(shape, 16);
        const double volume = enclosed_volume(mesh.vertices, mesh_triangles(mesh.vertices, mesh.faces));
        EXPECT_NEAR(volume / truth, 1.0, 0.03) << c.polynomial;
        const VoxelClassification voxels = classify_voxel_centres(mesh, digitize(shape, 0.25));
        EXPECT_GE(voxels.boundary_share(), 0.99) << c.polynomial;
        EXPECT_GE(voxels.share(), 0.99) << c.polynomial;
        // Without the thin-part weights and the shrink correction the solve loses more than 9 % of
        // the tube's volume (a shell, with a surface on each side, much less). Measured as solved:
        // the validity repair would pull the collapsed tube back to its voxels.
        if (!c.tube) continue;
        PipelineOptions paper;
        paper.extensions.alpha_reach = 0.0;
        paper.extensions.shrink_correction = 0;
        paper.validity = ValidityMode::Off;
        const PipelineResult plain = run_pipeline(source, paper);
        const double plain_volume = enclosed_volume(
            plain.regularization.positions, mesh_triangles(plain.regularization.positions, plain.surface.quads));
        EXPECT_LT(plain_volume / truth, 0.91);
    }
}

TEST(ThinParts, NoiseIsNoThinPart) {
    // A ball of radius 18 voxels with 20 % of the voxels next to its surface flipped: the flipped
    // voxels make every reach short, and the thin-part data weight pinned the mesh to them (12.4°
    // from the sphere's normals as solved, against 8.5° without the weight). Where the noise share
    // ρ reaches 0.2 the weight takes the reach over 8 rings, beyond the noise: as good as without it.
    const ImplicitShape sphere = make_shape("x^2+y^2+z^2-81", 10);
    const BinaryVolume clean = digitize(sphere, 0.5);
    std::vector<std::uint8_t> values(clean.mask.begin(), clean.mask.end());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> draw(0, 1);
    const Index3& d = clean.grid.dims;
    for (std::int64_t k = 1; k + 1 < d[2]; ++k)
        for (std::int64_t j = 1; j + 1 < d[1]; ++j)
            for (std::int64_t i = 1; i + 1 < d[0]; ++i) {
                const std::int64_t v = clean.grid.linear_index(i, j, k);
                bool next_to_surface = false;  // a 6-neighbour on the other side
                for (int a = 0; a < 3; ++a)
                    for (const int s : {-1, 1}) {
                        std::array<std::int64_t, 3> n{i, j, k};
                        n[std::size_t(a)] += s;
                        next_to_surface = next_to_surface || clean.mask[std::size_t(clean.grid.linear_index(n[0], n[1], n[2]))] != clean.mask[std::size_t(v)];
                    }
                if (next_to_surface && draw(rng) < 0.2) values[std::size_t(v)] ^= 1;
            }
    VolumeSource source;
    source.array = VoxelArray{values.data(), d, {1, d[0], d[0] * d[1]}};
    source.origin = clean.grid.origin;
    source.spacing = clean.grid.spacing;
    const auto error = [&](const PipelineOptions& options) {
        const PipelineResult result = run_pipeline(source, options);
        const PointMatrix truth = exact_normals(sphere, result.surface);
        const PointMatrix& x = result.regularization.positions;
        double sum = 0;
        for (std::int64_t f = 0; f < result.surface.face_count(); ++f) {
            const auto q = result.surface.quads.row(f);
            const Eigen::Vector3d diagonal = (x.row(q(2)) - x.row(q(0))).transpose(), other = (x.row(q(3)) - x.row(q(1))).transpose();
            const Eigen::Vector3d n = diagonal.cross(other);
            sum += std::acos(std::clamp(n.normalized().dot(truth.row(f).transpose()), -1.0, 1.0)) * 180 / M_PI;
        }
        return sum / double(result.surface.face_count());
    };
    PipelineOptions defaults, without;
    defaults.validity = without.validity = ValidityMode::Off;  // the solve itself
    without.extensions.alpha_reach = 0.0;
    const double with_weights = error(defaults), no_weights = error(without);
    EXPECT_LT(with_weights, no_weights + 0.5);
    EXPECT_LT(with_weights, 10.0);
}

TEST(ThinParts, TheAdaptiveFieldsDistanceMapsGiveTheReachesOfMapsMadeAfresh) {
    // With the defaults the thin-part weights measure the reach up to the cap of the adaptive
    // field's maps, and take those maps instead of computing them again: along the final field,
    // the kept maps must give every surfel the reaches that maps made for the thin parts alone
    // give, and the pipeline must release them before its solve.
    const VolumeSource source = shape_at_quarter_step("(x^2+y^2+z^2+9-0.140625)^2-36*(x^2+y^2)", 3.6);
    const LoadedVolume loaded = load_volume(source);
    const DigitalSurface surface = extract_digital_surface(loaded.volume, Connectivity::TwentySix);
    const AdaptiveNormalOptions options = default_adaptive_options(NormalFieldOptions{}, loaded);
    ASSERT_TRUE(options.keep_reach_maps);
    const AdaptiveNormalField field = adaptive_integral_invariant_normals(loaded.voxel_labels(), surface, options);
    ASSERT_TRUE(field.reach_maps);
    const double cap = thin_part_reach_cap(RegularizationExtensions{}, loaded.volume.grid);
    ASSERT_EQ(field.reach_maps->cap, cap) << "the defaults must share the maps";
    const SurfelReach kept = surfel_reach(loaded.voxel_labels(), surface, field.normals, *field.reach_maps);
    const SurfelReach fresh = surfel_reach(loaded.voxel_labels(), surface, field.normals, cap);
    EXPECT_TRUE(kept.inner == fresh.inner);
    EXPECT_TRUE(kept.outer == fresh.outer);
    EXPECT_LT(kept.smallest().minCoeff(), alpha_reach(RegularizationExtensions{}, loaded.volume.grid))
        << "the tube must be a thin part";

    PipelineOptions defaults;
    defaults.validity = ValidityMode::Off;
    const PipelineResult result = run_pipeline(loaded, defaults);
    ASSERT_TRUE(result.field.adaptive.has_value());
    EXPECT_FALSE(result.field.adaptive->reach_maps) << "kept past the thin parts";
}

TEST(ThinPartAlpha, InverseSquareOfTheSmallestReachAroundEachVertexBelowTheReference) {
    // Two faces of a 2×1 strip of surfels: vertex reach = the smaller of its faces' reaches.
    const BinaryVolume volume = test::make_voxels({2, 1, 1}, {{0, 0, 0}, {1, 0, 0}});
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    Eigen::VectorXd reach = Eigen::VectorXd::Constant(surface.face_count(), 20.0);
    reach[0] = 3.0;
    const Eigen::VectorXd alpha = thin_part_alpha(surface, reach, 12.0);
    ASSERT_EQ(alpha.size(), surface.vertex_count());
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v) {
        bool on_face_0 = false;
        for (int k = 0; k < 4; ++k) on_face_0 |= surface.quads(0, k) == v;
        EXPECT_DOUBLE_EQ(alpha[v], on_face_0 ? 16.0 : 1.0);  // (12/3)², or 1 above the reference
    }
    EXPECT_THROW(thin_part_alpha(surface, reach, 0.0), Error);
    EXPECT_THROW(thin_part_alpha(surface, Eigen::VectorXd::Ones(3), 12.0), Error);

    // A sheet's reference replaces the tube's as its sheetness rises: R_f = 12 − s·(12 − 6).
    for (const double sheetness : {1.0, 0.5}) {
        Eigen::VectorXd s = Eigen::VectorXd::Zero(surface.face_count());
        s[0] = sheetness;
        const Eigen::VectorXd sheet_alpha = thin_part_alpha(surface, reach, 12.0, s, 6.0);
        const double ratio = (12.0 - sheetness * 6.0) / 3.0;
        for (std::int64_t v = 0; v < surface.vertex_count(); ++v) {
            bool on_face_0 = false;
            for (int k = 0; k < 4; ++k) on_face_0 |= surface.quads(0, k) == v;
            EXPECT_DOUBLE_EQ(sheet_alpha[v], on_face_0 ? ratio * ratio : 1.0);
        }
    }
    EXPECT_THROW(thin_part_alpha(surface, reach, 12.0, Eigen::VectorXd::Zero(3), 2.0), Error);
    EXPECT_THROW(thin_part_alpha(surface, reach, 12.0, Eigen::VectorXd::Zero(surface.face_count()), -1.0), Error);
}

/// The mean sheetness of the faces whose smaller reach (along `field`) is below 12 voxels, and
/// how many there are; only those whose thinner side is the background if `background_side`.
std::pair<double, std::int64_t> mean_sheetness(const BinaryVolume& volume, const PointMatrix& field,
                                               bool background_side = false) {
    const double voxel = volume.grid.spacing.maxCoeff();
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const SurfelReach reach = surfel_reach(volume, surface, field, 13.0 * voxel);
    const Eigen::VectorXd s = thin_part_sheetness(volume, surface, field, reach, 12.0 * voxel);
    double sum = 0;
    std::int64_t thin = 0;
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        EXPECT_TRUE(s[f] >= 0 && s[f] <= 1);
        if (std::min(reach.inner[f], reach.outer[f]) >= 12.0 * voxel) {
            EXPECT_EQ(s[f], 0.0);  // not thin: not measured
            continue;
        }
        if (background_side && reach.outer[f] >= reach.inner[f]) continue;
        sum += s[f];
        ++thin;
    }
    return {thin > 0 ? sum / double(thin) : 0.0, thin};
}

/// The shape's outward unit normals at the surfel centres of its digitization (grid units).
PointMatrix exact_field(const ImplicitShape& shape, const BinaryVolume& volume) {
    return solid_exact_normals(shape, extract_digital_surface(volume, Connectivity::TwentySix));
}

TEST(ThinPartShape, PlatesShellsAndGapsAreSheetsTubesTunnelsAndLumpsAreNot) {
    // Object sides: a turned plate 2 voxels thick and an ellipsoidal shell 2 voxels thick (sheets),
    // a torus of tube radius 1.5 voxels and a ball of radius 2 voxels (a lump), digitized at
    // h = 0.25 and measured along their exact normals.
    struct Case {
        const char* polynomial;
        double box;
        bool sheet;
    };
    const Case shapes[] = {
        {"((0.2*x+0.15*y)^2+(-0.12*x+0.16*y+0.15*z)^2)^4+(1.44*x-1.92*y+3.2*z)^8-1", 4.5, true},
        {"(0.1111111*x^2+0.25*y^2+0.4444444*z^2-1)*(0.0816327*x^2+0.16*y^2+0.25*z^2-1)", 4, true},
        {"(x^2+y^2+z^2+9-0.140625)^2-36*(x^2+y^2)", 3.6, false},
        {"x^2+y^2+z^2-0.5625", 1.2, false},  // radius 3 voxels
    };
    for (const Case& c : shapes) {
        const ImplicitShape shape = make_shape(c.polynomial, c.box);
        const BinaryVolume volume = digitize(shape, 0.25);
        const PointMatrix field = exact_field(shape, volume);
        const auto [mean, thin] = mean_sheetness(volume, field);
        EXPECT_GT(thin, 100) << c.polynomial;
        if (c.sheet)  // less than 1: the rim of the plate is a half tube
            EXPECT_GT(mean, 0.7) << c.polynomial;
        else
            EXPECT_LT(mean, 0.1) << c.polynomial;
    }
    // Background sides, in a 40×40×40 block: a flat gap 3 voxels wide (a sheet of background) and
    // a straight tunnel of radius 1.5 voxels (a tube of background); the field: the axis normals.
    // The faces of the gap's and the tunnel's walls only (the block's outer faces, whose object
    // side is thinner than 12 voxels near the grid's border, are other parts).
    const BinaryVolume gap = test::make_volume({40, 40, 40}, [](double x, double, double) { return std::abs(x - 20) > 1.1; });
    const BinaryVolume tunnel = test::make_volume({40, 40, 40}, [](double x, double y, double) {
        return (x - 20) * (x - 20) + (y - 20) * (y - 20) > 1.5 * 1.5;
    });
    for (const BinaryVolume* volume : {&gap, &tunnel}) {
        const DigitalSurface surface = extract_digital_surface(*volume, Connectivity::TwentySix);
        PointMatrix axis(surface.face_count(), 3);
        for (std::int64_t f = 0; f < surface.face_count(); ++f) axis.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
        const auto [mean, thin] = mean_sheetness(*volume, axis, true);
        EXPECT_GT(thin, 100);
        if (volume == &gap)
            EXPECT_GT(mean, 0.8);
        else
            EXPECT_LT(mean, 0.1);
    }
}

TEST(ThinPartShape, SheetWeightsStraightenAThinPlateAndKeepItsVoxels) {
    // A turned plate 1.5 voxels thick, defaults against sheets weighted as tubes
    // (--alpha-reach-sheet at the --alpha-reach value): the tube weight (12/ρ)² pins the plate to
    // its staircase; the sheet weight (2/ρ)² lets its faces follow the field and still keeps 99 %
    // of its voxels (docs/accuracy.md, "Sheets and tubes": 6.8° against 11.1°).
    const char* plate = "((0.2*x+0.15*y)^2+(-0.12*x+0.16*y+0.15*z)^2)^4+(1.92*x-2.56*y+4.266667*z)^8-1";
    const VolumeSource source = shape_at_quarter_step(plate, 4.5);
    const ImplicitShape shape = make_shape(plate, 4.5);
    MeshEvaluationOptions evaluation;
    evaluation.grid_step = 0.25;
    const auto evaluate = [&](const PipelineOptions& options, std::int64_t& sheet_faces) {
        const PipelineResult result = run_pipeline(source, options);
        EXPECT_TRUE(result.validity && result.validity->after.valid());
        sheet_faces = result.sheet_faces;
        return evaluate_mesh(solved_mesh(result), shape, evaluation);
    };
    std::int64_t sheets = 0, sheets_as_tubes = 0;
    const MeshEvaluation defaults = evaluate(PipelineOptions{}, sheets);
    PipelineOptions tubes;
    tubes.extensions.alpha_reach_sheet = 12 * 0.25;
    const MeshEvaluation as_tubes = evaluate(tubes, sheets_as_tubes);
    EXPECT_GT(sheets, 1000);  // of 2 730 faces
    EXPECT_EQ(sheets_as_tubes, 0);  // not measured
    EXPECT_LT(defaults.normal_angle_deg.mean, 0.75 * as_tubes.normal_angle_deg.mean);
    EXPECT_LT(defaults.vertex_distance.mean, as_tubes.vertex_distance.mean);
    EXPECT_GE(defaults.voxels.object_share(), 0.99);
}

TEST(ShrinkCorrection, UndoesAUniformShrinkOfABall) {
    // The digital surface of a ball of radius 10 voxels, moved inward by 0.3 voxel along the
    // radius, with the radial field: the correction brings the mean radius back to the digital
    // surface's (the surfel centres are on average on it), within 0.03 voxel.
    const BinaryVolume volume = test::make_ball(25, 10.0, 12.0);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const Eigen::RowVector3d centre(12, 12, 12);
    PointMatrix shrunk = surface.vertices;
    for (Eigen::Index v = 0; v < shrunk.rows(); ++v)
        shrunk.row(v) -= 0.3 * (shrunk.row(v) - centre).normalized();
    const PointMatrix centres = surfel_centers(surface);
    PointMatrix radial(surface.face_count(), 3);
    for (Eigen::Index f = 0; f < radial.rows(); ++f) radial.row(f) = (centres.row(f) - centre).normalized();
    const auto mean_radius = [&](const PointMatrix& p) {
        double sum = 0;
        for (Eigen::Index v = 0; v < p.rows(); ++v) sum += (p.row(v) - centre).norm();
        return sum / double(p.rows());
    };
    const ShrinkCorrection corrected = correct_shrink(surface, shrunk, radial, ShrinkAveraging{});
    double centre_radius = 0;
    for (Eigen::Index f = 0; f < centres.rows(); ++f) centre_radius += (centres.row(f) - centre).norm();
    centre_radius /= double(centres.rows());
    EXPECT_NEAR(mean_radius(corrected.positions), centre_radius, 0.03);
    EXPECT_NEAR(corrected.mean_shift, 0.3, 0.05);
    // No steps: nothing moves.
    EXPECT_EQ(correct_shrink(surface, shrunk, radial, narrow_average(0)).positions, shrunk);
    EXPECT_THROW(correct_shrink(surface, shrunk, radial, narrow_average(-1)), Error);
    EXPECT_THROW(correct_shrink(surface, shrunk.topRows(3), radial, narrow_average(4)), Error);
    ShrinkAveraging bad;
    bad.wide_steps = -1;
    EXPECT_THROW(correct_shrink(surface, shrunk, radial, bad), Error);
    bad = ShrinkAveraging{};
    bad.wide_tolerance = -0.01;
    EXPECT_THROW(correct_shrink(surface, shrunk, radial, bad), Error);
    bad.wide_tolerance = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(correct_shrink(surface, shrunk, radial, bad), Error);
}

/// The digital surface of a ball of radius 10 voxels with its cap z > 17 (the upper 5 voxels)
/// moved inward by 0.6 voxel and the rest not, and the radial field.
struct CappedBall {
    DigitalSurface surface;
    Eigen::RowVector3d centre{12, 12, 12};
    PointMatrix moved, radial;

    CappedBall() : surface(extract_digital_surface(test::make_ball(25, 10.0, 12.0), Connectivity::TwentySix)) {
        moved = surface.vertices;
        for (Eigen::Index v = 0; v < moved.rows(); ++v)
            if (moved(v, 2) > 17) moved.row(v) -= 0.6 * (moved.row(v) - centre).normalized();
        const PointMatrix centres = surfel_centers(surface);
        radial.resize(surface.face_count(), 3);
        for (Eigen::Index f = 0; f < radial.rows(); ++f) radial.row(f) = (centres.row(f) - centre).normalized();
    }

    /// Corrected, the moved surface should land where the unmoved one does once corrected: the
    /// rms of the difference of their radii.
    double rms_error(const ShrinkAveraging& averaging) const {
        const PointMatrix a = correct_shrink(surface, moved, radial, averaging).positions;
        const PointMatrix b = correct_shrink(surface, surface.vertices, radial, averaging).positions;
        double sum = 0;
        for (Eigen::Index v = 0; v < a.rows(); ++v) {
            const double error = (a.row(v) - centre).norm() - (b.row(v) - centre).norm();
            sum += error * error;
        }
        return std::sqrt(sum / double(a.rows()));
    }
};

TEST(ShrinkCorrection, LocalShareUndoesALocalShrinkThatTheWideAverageSpreads) {
    // The 40-step average spreads the cap's drift over the sphere; the 10-step one, given
    // everywhere as the local share, keeps it where it is.
    const CappedBall ball;
    const std::int64_t faces = ball.surface.face_count();
    const Eigen::VectorXd everywhere = Eigen::VectorXd::Ones(faces);
    const double wide = ball.rms_error(narrow_average(40)), local = ball.rms_error(narrow_average(40, everywhere, 10));
    EXPECT_LT(local, 0.8 * wide) << local << " against " << wide;  // 0.077 against 0.108 voxel
    EXPECT_DOUBLE_EQ(ball.rms_error(narrow_average(40, Eigen::VectorXd::Zero(faces), 10)), wide);  // a zero share: the wide average
    EXPECT_THROW(correct_shrink(ball.surface, ball.moved, ball.radial, narrow_average(40, Eigen::VectorXd::Ones(3), 10)), Error);
    EXPECT_THROW(correct_shrink(ball.surface, ball.moved, ball.radial, narrow_average(40, everywhere, -1)), Error);
}

TEST(ShrinkCorrection, TheWideAverageKeepsADriftThatVaries) {
    // The cap's drift differs from the rest's by far more than τ, so the narrow average is kept
    // there, and the corrected surface lands where the unmoved one does as well as with the
    // narrow average alone; the wide average taken everywhere (τ larger than any difference)
    // spreads the cap's drift over the ball.
    const CappedBall ball;
    ShrinkAveraging everywhere;
    everywhere.wide_tolerance = 10;
    const double narrow = ball.rms_error(narrow_average(40)), thresholded = ball.rms_error(ShrinkAveraging{}),
                 wide = ball.rms_error(everywhere);
    EXPECT_LT(thresholded, 1.1 * narrow) << thresholded << " against " << narrow;
    EXPECT_GT(wide, 1.3 * narrow) << wide << " against " << narrow;
}

/// The sphere of radius 9 at h = 0.25 (36 voxels).
constexpr const char* kSphere9 = "x^2+y^2+z^2-81";

/// A pipeline run's mesh of kSphere9 against the sphere.
MeshEvaluation sphere_evaluation(const PipelineResult& result) {
    return evaluate_mesh(solved_mesh(result), make_shape(kSphere9, 10), MeshEvaluationOptions{});
}

TEST(ShrinkCorrection, TheWideAverageTakesTheStaircaseRippleOffASphere) {
    // A sphere of radius 9 at h = 0.25 (36 voxels): its drift is uniform, and the ripple the
    // narrow average leaves tilts the faces; the wide average removes it (suite: 0.47° → 0.38°,
    // docs/accuracy.md, "A wide shrink average where the drift agrees") and the surface stays as
    // close to the sphere.
    const VolumeSource source = shape_at_quarter_step(kSphere9, 10);
    PipelineOptions narrow;
    narrow.extensions.shrink_wide_steps = 0;
    const PipelineResult defaults = run_pipeline(source, PipelineOptions{});
    const MeshEvaluation without = sphere_evaluation(run_pipeline(source, narrow)), with = sphere_evaluation(defaults);
    const double angle = with.normal_angle_deg.mean, narrow_angle = without.normal_angle_deg.mean;
    const double distance = with.vertex_distance.mean, narrow_distance = without.vertex_distance.mean;
    EXPECT_LT(angle, 0.9 * narrow_angle) << angle << " against " << narrow_angle;
    EXPECT_LT(distance, 1.02 * narrow_distance) << distance << " against " << narrow_distance;
    EXPECT_EQ(defaults.extension_report["shrink_correction"].value("wide_steps", 0), 160);
}

TEST(AdaptiveNormals, TheExtrapolationsThresholdKeepsItsNoiseOffASphere) {
    // On a sphere the integral invariants have no bias to extrapolate away (the ball is
    // symmetric about the normal): 2·(n(r/√2) − n(r)) is noise, of which a threshold of 0.5° let
    // through more than the default 0.75° (0.36° against 0.38° here, as in the suite;
    // docs/accuracy.md, "The extrapolation's threshold").
    const VolumeSource source = shape_at_quarter_step(kSphere9, 10);
    PipelineOptions half_degree;
    half_degree.normals.extrapolation_threshold_deg = 0.5;
    const MeshEvaluation loose = sphere_evaluation(run_pipeline(source, half_degree)),
                         defaults = sphere_evaluation(run_pipeline(source, PipelineOptions{}));
    const double angle = defaults.normal_angle_deg.mean, loose_angle = loose.normal_angle_deg.mean;
    const double distance = defaults.vertex_distance.mean, loose_distance = loose.vertex_distance.mean;
    EXPECT_LT(angle, 0.97 * loose_angle) << angle << " against " << loose_angle;
    EXPECT_LT(distance, 1.02 * loose_distance) << distance << " against " << loose_distance;
    PipelineOptions fixed;
    fixed.normals.radius = 1.0;
    fixed.normals.extrapolation_threshold_deg = 1.0;
    EXPECT_THROW(run_pipeline(source, fixed), Error);  // the adaptive field's only
    PipelineOptions negative;
    negative.normals.extrapolation_threshold_deg = -1.0;
    EXPECT_THROW(run_pipeline(source, negative), Error);
}

TEST(ShrinkCorrection, LocalShareOnThinTubesButNotWhereTheVoxelsAreNoisy) {
    // A 3×1 strip of surfels: vertex multipliers above 9 on one vertex of face 0 only; then a
    // raised noise fairness on one vertex of that face.
    const BinaryVolume volume = test::make_voxels({3, 1, 1}, {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}});
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    Eigen::VectorXd thin = Eigen::VectorXd::Ones(surface.vertex_count());
    const std::int32_t apex = surface.quads(0, 0);
    thin[apex] = 16;  // (12/3)²: a tube of reach 3 voxels
    const auto touches = [&](std::int64_t f, std::int32_t v) {
        for (int k = 0; k < 4; ++k)
            if (surface.quads(f, k) == v) return true;
        return false;
    };
    const Eigen::VectorXd share = local_shrink_share(surface, thin, Eigen::VectorXd());
    for (std::int64_t f = 0; f < surface.face_count(); ++f) EXPECT_EQ(share[f], touches(f, apex) ? 1.0 : 0.0);
    thin[apex] = 9;  // (12/4)²: not below a third of the reference
    EXPECT_EQ(local_shrink_share(surface, thin, Eigen::VectorXd()).sum(), 0.0);
    thin[apex] = 16;
    Eigen::VectorXd noise = Eigen::VectorXd::Ones(surface.vertex_count());
    noise[surface.quads(0, 2)] = 3;
    const Eigen::VectorXd noisy = local_shrink_share(surface, thin, noise);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        EXPECT_EQ(noisy[f], touches(f, apex) && !touches(f, surface.quads(0, 2)) ? 1.0 : 0.0);
    EXPECT_EQ(noisy[0], 0.0);
    EXPECT_EQ(local_shrink_share(surface, Eigen::VectorXd(), noise).size(), 0);
}

TEST(ShrinkCorrection, LocalStepsOnThinTubesKeepTheirVoxels) {
    // A torus of tube radius 2.4 voxels with the defaults: its outer equator drifts in further
    // than the rest of the tube, and the 40-step average (which spans the tube's circumference)
    // left 16 voxel centres 0.04–0.08 voxel inside the true surface outside the mesh (98.9 %);
    // the 10-step average on thin tubes keeps them (docs/accuracy.md, "Local shrink on thin tubes").
    const char* torus = "(x^2+y^2+z^2+9-0.36)^2-36*(x^2+y^2)";
    const VolumeSource source = shape_at_quarter_step(torus, 4);
    const BinaryVolume voxels = digitize(make_shape(torus, 4), 0.25);
    const auto object_share = [&](const PipelineOptions& options, std::int64_t& local_faces) {
        const PipelineResult result = run_pipeline(source, options);
        local_faces = result.extension_report["shrink_correction"].value("local_faces", std::int64_t(-1));
        return classify_voxel_centres(solved_mesh(result), voxels).object_share();
    };
    std::int64_t local_faces = 0, none = 0;
    PipelineOptions defaults;  // the solve's voxels: the repair does not put any back
    defaults.keep_voxels = VoxelKeeping::Never;
    PipelineOptions without_local = defaults;
    without_local.extensions.shrink_local_steps = 0;
    EXPECT_GE(object_share(defaults, local_faces), 0.99);
    EXPECT_LT(object_share(without_local, none), 0.99);
    EXPECT_GT(local_faces, 1000);  // of 1 688: the whole tube
    EXPECT_EQ(none, 0);
}

}  // namespace
}  // namespace dsreg
