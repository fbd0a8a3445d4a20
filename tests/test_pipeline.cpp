// The library's one pipeline (include/dsreg/pipeline.hpp): the same answer as the stages called
// by hand, its progress events, interruption, option checks and outputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "dsreg/adaptive_normals.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/local_weights.hpp"
#include "dsreg/shrink_correction.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/pipeline.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

LoadedVolume loaded_ball() {
    LoadedVolume loaded;
    loaded.volume = test::make_ball(14, 5.2, 6.5);
    loaded.description = "ball";
    return loaded;
}

std::filesystem::path fresh_folder(const std::string& name) {
    const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("dsreg_pipeline_" + name);
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    return folder;
}

TEST(Pipeline, EqualsTheStagesCalledByHand) {
    const LoadedVolume loaded = loaded_ball();
    PipelineOptions options;
    options.solver = SolverKind::Cholmod;
    const PipelineResult result = run_pipeline(loaded, options);

    // The defaults by hand: the adaptive integral invariants lifted into the surfels' half-spaces
    // (margin 0.05), the thin-part data weights from their reach (reference 12 voxels), the
    // solve, the shrink correction (40 steps).
    const DigitalSurface surface = extract_digital_surface(loaded.volume, Connectivity::TwentySix);
    const AdaptiveNormalOptions adaptive = default_adaptive_options(options.normals, loaded);
    EXPECT_DOUBLE_EQ(adaptive.max_radius, 14.0);  // voxels of a file
    const AdaptiveNormalField field = adaptive_integral_invariant_normals(loaded.volume, surface, adaptive);
    PointMatrix normals = field.normals;
    ASSERT_TRUE(options.normals.lift_margin.has_value());
    EXPECT_EQ(*options.normals.lift_margin, 0.05);
    const std::vector<std::int32_t> against = faces_against_their_surfels(surface, normals);  // before the lift
    EXPECT_EQ(result.field.faces_against_surfels, against);
    EXPECT_EQ(lift_into_surfel_half_spaces(surface, normals, *options.normals.lift_margin), result.field.lifted_faces);
    RegularizationWeights weights;
    weights.alpha = options.alpha;  // the pipeline's defaults (docs/accuracy.md), not the paper's
    weights.gamma = options.gamma;
    if (!against.empty()) weights.vertex_gamma = noise_fairness_gamma(surface, against, 12, 0.02, 3);
    weights.vertex_alpha = thin_part_alpha(surface, field.reach.smallest(), 12.0);
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    const RegularizationResult solved = regularize(surface, normals, weights, solver);
    const ShrinkCorrection expected = correct_shrink(surface, solved.positions, normals, ShrinkAveraging{});

    ASSERT_EQ(result.surface.face_count(), surface.face_count());
    EXPECT_EQ((result.surface.quads - surface.quads).cwiseAbs().maxCoeff(), 0);
    EXPECT_LT((result.field.normals - normals).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((result.weights.vertex_alpha - weights.vertex_alpha).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_EQ(result.weights.vertex_gamma, weights.vertex_gamma);
    EXPECT_LT((result.regularization.positions - expected.positions).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(result.object_voxels, loaded.volume.object_voxel_count());
    EXPECT_EQ(result.faces_against_field, 0);
}

TEST(Pipeline, RoundOffOfTheSpacingMovesTheMeshByRoundOffOnly) {
    // The spacing (1, 0.8, 1.2) of one float32 NIfTI affine as ITK reads it and as the column
    // norms of nibabel's affine give it: the defaults take no discrete decision from the
    // round-off (radius levels, reach steps, which reach the thin-part weights use: with these
    // two, 13·s ≥ 12·s + s holds for one and not the other), so the meshes agree to ~1e-9 (they
    // differed by 3e-3 voxel).
    LoadedVolume exact = loaded_ball();
    exact.volume.grid.spacing = Eigen::Vector3d(1.0, 0.800000011920929, 1.2000000476837158);
    LoadedVolume rounded = exact;
    rounded.volume.grid.spacing = Eigen::Vector3d(0.9999999938786497, 0.8000000104982703, 1.2000000410192275);
    const PipelineResult a = run_pipeline(exact, PipelineOptions{});
    const PipelineResult b = run_pipeline(rounded, PipelineOptions{});
    ASSERT_EQ(a.surface.quads, b.surface.quads);
    const double extent = a.regularization.positions.cwiseAbs().maxCoeff();
    EXPECT_LT((a.regularization.positions - b.regularization.positions).cwiseAbs().maxCoeff(), 1e-6 * extent);
}

TEST(Pipeline, FixedRadiusAndNoCorrectionsIsThePapersPipeline) {
    // --radius 5 --alpha-reach 0 --shrink-correction 0 --alpha 1e-3 --gamma 1e-2: integral
    // invariants of one radius and the paper's energy with its weights, nothing else.
    const LoadedVolume loaded = loaded_ball();
    PipelineOptions options;
    options.solver = SolverKind::Cholmod;
    options.alpha = RegularizationWeights{}.alpha;
    options.gamma = RegularizationWeights{}.gamma;
    options.normals.radius = 5.0;
    options.extensions.alpha_reach = 0.0;
    options.extensions.shrink_correction = 0;
    const PipelineResult result = run_pipeline(loaded, options);
    const DigitalSurface surface = extract_digital_surface(loaded.volume, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(loaded.volume, surface, 5.0);
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    const RegularizationResult expected = regularize(surface, u, RegularizationWeights{}, solver);
    EXPECT_LT((result.field.normals - u).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_EQ(result.weights.vertex_alpha.size(), 0);
    EXPECT_LT((result.regularization.positions - expected.positions).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Pipeline, ReportsEveryStageOnceStartedThenFinishedInOrder) {
    std::vector<ProgressEvent> events;
    PipelineOptions options;
    run_pipeline(loaded_ball(), options, [&](const ProgressEvent& e) { events.push_back(e); });
    std::vector<std::string> finished;
    std::map<std::string, int> open;
    for (const ProgressEvent& e : events) {
        if (e.finished) {
            EXPECT_EQ(open[e.stage], 1) << e.stage << " finished without starting";
            open[e.stage] = 0;
            finished.push_back(e.stage);
            EXPECT_GE(e.seconds, 0.0);
            EXPECT_EQ(e.fraction, 1.0);
        } else if (e.fraction == 0.0 && open[e.stage] == 0) {
            open[e.stage] = 1;
        }
    }
    EXPECT_EQ(finished, (std::vector<std::string>{"surface", "normals", "regularize", "validity"}));
}

TEST(Pipeline, AnInterruptFromTheProgressCallbackStopsTheRun) {
    VolumeSource source;
    source.shape = "sphere9";
    source.h = 1.0;
    PipelineOptions options;
    const auto interrupt_at_normals = [](const ProgressEvent& e) {
        if (e.stage == "normals") throw Interrupted();
    };
    EXPECT_THROW(run_pipeline(source, options, interrupt_at_normals), Interrupted);
}

TEST(Pipeline, FromAShapeWritesTheMeshAndAReportThatDescribesIt) {
    const std::filesystem::path folder = fresh_folder("outputs");
    VolumeSource source;
    source.shape = "sphere9";
    source.h = 1.0;
    PipelineOptions options;
    PipelineOutputs outputs;
    outputs.mesh = (folder / "sphere.ply").string();
    outputs.input_mesh = (folder / "digital.obj").string();
    outputs.report = (folder / "report.json").string();
    check_pipeline_outputs(outputs);
    PipelineResult result = run_pipeline(source, options);
    write_pipeline_outputs(result, options, outputs, source);

    const PolygonMesh mesh = read_mesh(outputs.mesh);
    EXPECT_EQ(mesh.faces.rows(), result.surface.face_count());
    EXPECT_LT((mesh.vertices - result.regularization.positions).cwiseAbs().maxCoeff(), 1e-6);  // PLY stores floats
    const PolygonMesh digital = read_mesh(outputs.input_mesh);
    EXPECT_LT((digital.vertices - result.surface.vertices).cwiseAbs().maxCoeff(), 1e-9);

    std::ifstream in(outputs.report);
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report["counts"]["surfels"], result.surface.face_count());
    EXPECT_EQ(report["input"], "sphere9 at h=1");
    EXPECT_TRUE(report["seconds"].contains("digitize"));
    EXPECT_TRUE(report["seconds"].contains("write"));
    EXPECT_DOUBLE_EQ(report["energy_after"]["total"].get<double>(),
                     result.regularization.energy_after.total(result.weights));
    EXPECT_LT(result.regularization.energy_after.total(result.weights),
              result.regularization.energy_before.total(result.weights));
    EXPECT_NE(summary_line(result, options).find(std::to_string(result.surface.face_count()) + " surfels"),
              std::string::npos);
}

TEST(Pipeline, ThePageShowsTheResultWithItsDigitalSurfaceAndSummary) {
    const LoadedVolume loaded = loaded_ball();
    PipelineOptions options;
    const PipelineResult result = run_pipeline(loaded, options);
    const ViewPage page = result_page(result, options);
    ASSERT_EQ(page.layers.size(), 1u);
    const ViewLayer& layer = page.layers[0];
    EXPECT_EQ((layer.mesh.vertices - result.regularization.positions).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((layer.mesh.faces - result.surface.quads).cwiseAbs().maxCoeff(), 0);
    EXPECT_EQ((layer.mesh.face_normals - result.field.normals).cwiseAbs().maxCoeff(), 0.0);
    ASSERT_TRUE(layer.digital.has_value());
    EXPECT_EQ((layer.digital->vertices - result.surface.vertices).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(page.length_unit, "voxels");
    std::map<std::string, std::string> summary;
    for (const SummaryLine& line : page.summary) summary[line.name] = line.value;
    EXPECT_EQ(summary["input"], "ball");
    EXPECT_EQ(summary["surfels"], std::to_string(result.surface.face_count()));
    EXPECT_EQ(summary["normal field"], result.field.description);
    for (const auto& [stage, seconds] : result.stage_seconds) EXPECT_EQ(summary.count(stage), 1u) << stage;
    EXPECT_EQ(summary.count("total"), 1u);

    const std::filesystem::path folder = fresh_folder("page");
    PipelineOutputs outputs;
    outputs.mesh = (folder / "ball.obj").string();
    outputs.html = (folder / "ball.obj.html").string();
    PipelineResult written = result;
    write_pipeline_outputs(written, options, outputs, VolumeSource{});
    EXPECT_GT(std::filesystem::file_size(outputs.html), 800000u);  // with three.js
    outputs.html = (folder / "ball.png").string();
    EXPECT_THROW(check_pipeline_outputs(outputs), Error);
    outputs.html = outputs.mesh;
    EXPECT_THROW(check_pipeline_outputs(outputs), Error);
}

TEST(Pipeline, OptionsAreCheckedWithTheFlagsNames) {
    const auto message = [](const PipelineOptions& options) {
        try {
            run_pipeline(loaded_ball(), options);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    PipelineOptions options;
    options.alpha = 0;
    EXPECT_NE(message(options).find("--alpha 0: must be positive"), std::string::npos);
    options = {};
    options.normals.radius = -1;
    EXPECT_NE(message(options).find("--radius"), std::string::npos);
    options = {};
    options.normals.kind = "exact";
    EXPECT_NE(message(options).find("needs an implicit --shape"), std::string::npos);
    options = {};
    options.normals.kind = "wavy";
    EXPECT_NE(message(options).find("--normals wavy"), std::string::npos);
    options = {};
    options.normals.at_input = "trivial";
    EXPECT_NE(message(options).find("--at-input only applies"), std::string::npos);
}

TEST(Pipeline, EmptyMaskIsRejectedWithItsDescription) {
    LoadedVolume loaded;
    loaded.volume = test::make_voxels({4, 4, 4}, {});
    loaded.description = "an empty array";
    try {
        run_pipeline(loaded, PipelineOptions{});
        FAIL() << "an empty object was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("an empty array: the object is empty"), std::string::npos);
    }
}

TEST(Pipeline, TwoOutputsOnOneFileAreRejectedBeforeAnyWork) {
    const std::filesystem::path folder = fresh_folder("same");
    PipelineOutputs outputs;
    outputs.mesh = (folder / "a.obj").string();
    outputs.report = (folder / "." / "a.obj").string();
    EXPECT_THROW(check_pipeline_outputs(outputs), Error);
    outputs.report.clear();
    outputs.mesh = (folder / "a.xyz").string();
    EXPECT_THROW(check_pipeline_outputs(outputs), Error);
}

TEST(Pipeline, WithoutAMeshPathOnlyTheOtherOutputsAreWritten) {
    // The Python module returns the mesh and writes only the files asked (--report here).
    const std::filesystem::path folder = fresh_folder("no_mesh");
    PipelineOutputs outputs;
    EXPECT_FALSE(outputs.any());
    outputs.report = (folder / "r.json").string();
    ASSERT_TRUE(outputs.any());
    check_pipeline_outputs(outputs);
    PipelineResult result = run_pipeline(loaded_ball(), PipelineOptions{});
    write_pipeline_outputs(result, PipelineOptions{}, outputs, VolumeSource{});
    std::vector<std::filesystem::path> written;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) written.push_back(entry.path().filename());
    EXPECT_EQ(written, std::vector<std::filesystem::path>{"r.json"});
    EXPECT_EQ(result.stage_seconds.back().first, "write");
}

/// A ball of radius 9 voxels whose voxels next to the surface are flipped with probability 0.2:
/// noise that turns many estimated normals into or along their faces.
LoadedVolume loaded_noisy_ball() {
    LoadedVolume loaded = loaded_ball();
    loaded.volume = test::flip_voxels_next_to_surface(test::make_ball(24, 9.0, 12.0), 0.2, 11);
    return loaded;
}

TEST(Pipeline, EstimatedFieldsAreLiftedIntoTheSurfelsHalfSpacesAndOnlyThere) {
    const LoadedVolume loaded = loaded_noisy_ball();
    PipelineOptions options;
    options.validity = ValidityMode::Off;  // the field is the subject: the lift, not what the repair does after
    const PipelineResult lifted = run_pipeline(loaded, options);
    options.normals.lift_margin.reset();
    const PipelineResult raw = run_pipeline(loaded, options);
    ASSERT_EQ(lifted.surface.face_count(), raw.surface.face_count());
    EXPECT_EQ(raw.field.lifted_faces, 0);
    std::int64_t below = 0;
    for (std::int64_t f = 0; f < raw.surface.face_count(); ++f) {
        const Eigen::Vector3d n = raw.surface.surfels[std::size_t(f)].trivial_normal();
        const Eigen::RowVector3d u = raw.field.normals.row(f), w = lifted.field.normals.row(f);
        EXPECT_GE(w.dot(n.transpose()), 0.05 - 1e-12) << "face " << f;
        if (u.dot(n.transpose()) < 0.05) ++below;
        else EXPECT_EQ(w, u) << "face " << f;  // the others bit for bit
    }
    EXPECT_GT(below, 0);  // the noise made some
    EXPECT_EQ(lifted.field.lifted_faces, below);
}

/// Mean angle (degrees) between the faces' normals and the sphere's (centre c) at their centroids.
double mean_normal_error_deg(const PipelineResult& r, const Eigen::RowVector3d& c) {
    const PointMatrix normals = face_normals(r.regularization.positions, r.surface.quads);
    double sum = 0;
    for (std::int64_t f = 0; f < r.surface.face_count(); ++f) {
        Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
        for (int k = 0; k < 4; ++k) centroid += r.regularization.positions.row(r.surface.quads(f, k)) / 4;
        const double cosine = std::clamp(normals.row(f).dot((centroid - c).normalized()), -1.0, 1.0);
        sum += std::acos(cosine) * 180 / M_PI;
    }
    return sum / double(r.surface.face_count());
}

TEST(Pipeline, NoiseFairnessStraightensTheNoisyBallAndLeavesTheCleanOneAlone) {
    PipelineOptions options;
    options.solver = SolverKind::Cholmod;
    const LoadedVolume noisy = loaded_noisy_ball();
    const PipelineResult with = run_pipeline(noisy, options);
    options.extensions.noise_fairness = 0.0;
    const PipelineResult without = run_pipeline(noisy, options);
    ASSERT_GT(with.field.faces_against_surfels.size(), std::size_t(with.surface.face_count() / 20));
    EXPECT_EQ(with.field.faces_against_surfels, without.field.faces_against_surfels);
    EXPECT_EQ(without.weights.vertex_gamma.size(), 0);
    ASSERT_EQ(with.weights.vertex_gamma.size(), with.surface.vertex_count());
    EXPECT_LE(with.weights.vertex_gamma.maxCoeff(), 13.0);
    const Eigen::RowVector3d centre(12, 12, 12);
    const double error_with = mean_normal_error_deg(with, centre), error_without = mean_normal_error_deg(without, centre);
    EXPECT_LT(error_with, 0.8 * error_without) << error_with << "° against " << error_without << "°";
    EXPECT_EQ(with.faces_against_field, 0);
    ASSERT_TRUE(with.validity.has_value());
    EXPECT_TRUE(with.validity->after.valid());

    // A clean digitization has no face against its surfel: the same mesh, bit for bit.
    const PipelineResult clean_without = run_pipeline(loaded_ball(), options);
    options.extensions.noise_fairness.reset();
    const PipelineResult clean_with = run_pipeline(loaded_ball(), options);
    EXPECT_TRUE(clean_with.field.faces_against_surfels.empty());
    EXPECT_EQ(clean_with.regularization.positions, clean_without.regularization.positions);
}

}  // namespace
}  // namespace dsreg
