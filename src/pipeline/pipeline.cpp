// dsreg pipeline — run_pipeline and its outputs (include/dsreg/pipeline.hpp).
#include "dsreg/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "dsreg/atomic_file.hpp"
#include "dsreg/block_pipeline.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/grid_placement.hpp"
#include "dsreg/local_reach.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/text.hpp"
#include "dsreg/thin_part_shape.hpp"
#include "dsreg/world_space.hpp"
#include "dsreg/output_paths.hpp"
#include "pipeline_stages.hpp"
#include "stage_clock.hpp"

namespace dsreg {

namespace {

RegularizationWeights global_weights(const PipelineOptions& o) { return {o.alpha, o.beta, o.gamma, {}, {}}; }

/// The weights checked with the flags' names, as typed (the library's validate_weights names the
/// weight instead).
void check_weight_flags(const PipelineOptions& o) {
    const auto check = [](const char* flag, double value, bool zero_allowed) {
        if ((zero_allowed ? value >= 0 : value > 0) && std::isfinite(value)) return;
        throw Error(std::string(flag) + " " + format("%g", value) + ": must be " +
                    (zero_allowed ? "zero or positive" : "positive (the data term keeps the system positive definite)") +
                    " and finite");
    };
    check("--alpha", o.alpha, false);
    check("--beta", o.beta, true);
    check("--gamma", o.gamma, true);
    validate_weights(global_weights(o), 0, 0);
}

/// The faces' reach and sheetness for the thin-part data weights (empty when --alpha-reach 0),
/// measured along the field used, whatever made it: so a field read back from --export-normals
/// gives the same weights, and so the same mesh (the adaptive field's own reach follows its
/// first field). The sheetness is measured at each face's own reach, the weights use the largest
/// reach within a few rings (max_over_rings: one voxel of noise is not a thin part). The
/// adaptive field's distance maps serve when they have the same cap (the defaults).
ThinParts thin_parts(const RegularizationExtensions& o, const VoxelLabels& volume, const DigitalSurface& surface,
                     const NormalField& field) {
    const double reference = alpha_reach(o, volume.grid());
    if (reference <= 0) return {};
    const double cap = thin_part_reach_cap(o, volume.grid());
    const ReachMaps* kept = field.adaptive ? field.adaptive->reach_maps.get() : nullptr;
    const SurfelReach reach = kept && kept->cap == cap ? surfel_reach(volume, surface, field.normals, *kept)
                                                       : surfel_reach(volume, surface, field.normals, cap);
    ThinParts parts;
    parts.reach = max_over_rings(surface, reach.smallest(), AdaptiveNormalOptions{}.reach_rings);
    parts.wide_reach = max_over_rings(surface, reach.smallest(), kNoisyReachRings);
    if (sheet_alpha_reach(o, volume.grid()) != reference)
        parts.sheetness = thin_part_sheetness(volume, surface, field.normals, reach, reference);
    return parts;
}

std::string component_text(std::int64_t count) {
    return std::to_string(count) + (count == 1 ? " component" : " components");
}

std::string validity_counts(const MeshValidity& v) {
    std::string text = std::to_string(v.intersecting_pairs) + " intersecting triangle pairs, " +
                       std::to_string(v.folded_faces) + " folded faces";
    if (v.degenerate_triangles > 0) text += ", " + std::to_string(v.degenerate_triangles) + " degenerate triangles";
    return text;
}

/// What the check and repair did, for the stage line and the summary line.
std::string validity_text(const ValidityRepairReport& r, const RegularizationWeights& w) {
    std::string voxels;  // when put back (VoxelKeeping); counted only: in the report
    if (r.voxels_put_back)
        voxels = ", " + std::to_string(r.wrong_voxels_before - r.wrong_voxels_after) + " of " +
                 std::to_string(r.wrong_voxels_before) + " voxel centres put back on their side";
    if (r.rounds == 0) return (r.before.valid() ? "valid solid" : validity_counts(r.before) + " (not repaired)") + voxels;
    std::string text = (r.before.valid() ? "valid solid" : "repaired " + validity_counts(r.before)) + voxels + " in " +
                       std::to_string(r.rounds) + (r.rounds == 1 ? " round (" : " rounds (") + std::to_string(r.region_vertices) +
                       " vertices, energy -> " + format("%.4g", r.energy_after.total(w)) + ")";
    if (!r.after.valid()) text += ", left " + validity_counts(r.after);
    return text;
}

nlohmann::json validity_counts_json(const MeshValidity& v) {
    return {{"intersecting_pairs", v.intersecting_pairs},
            {"degenerate_triangles", v.degenerate_triangles},
            {"folded_faces", v.folded_faces},
            {"valid", v.valid()}};
}

nlohmann::json validity_json(const ValidityRepairReport& r, const RegularizationWeights& w, ValidityMode mode) {
    return {{"repair", mode == ValidityMode::Repair},
            {"before", validity_counts_json(r.before)},
            {"after", validity_counts_json(r.after)},
            {"rounds", r.rounds},
            {"region_vertices", r.region_vertices},
            {"strengthened_vertices", r.strengthened_vertices},
            {"smoothed_vertices", r.smoothed_vertices},
            {"held_vertices", r.held_vertices},
            {"field_corrections", r.field_corrections},
            {"parts_solved", r.parts_solved},
            {"exact", r.exact},
            {"converged", r.converged},
            {"kkt_residual", r.max_kkt_residual},
            {"max_displacement_voxels", r.max_displacement_voxels},
            {"energy_before", energy_json(r.energy_before, w)},
            {"energy_after", energy_json(r.energy_after, w)},
            {"wrong_voxels_before", r.wrong_voxels_before},
            {"wrong_voxels_after", r.wrong_voxels_after},
            {"noisy_wrong_voxels", r.noisy_wrong_voxels},
            {"outside_object_voxels_before", r.outside_object_voxels_before},
            {"voxels_put_back", r.voxels_put_back},
            {"bounded_vertices", r.bounded_vertices},
            {"seconds", {{"check", r.check_seconds}, {"solve", r.solve_seconds}}}};
}

/// Stage "validity": checks the solved mesh and, unless ValidityMode::Check, repairs it; with
/// `voxels` and --keep-voxels, also puts their centres back on their side.
void check_and_repair(const PipelineOptions& o, PipelineResult& result, StageClock& clock, const BinaryVolume* voxels) {
    clock.start("validity");
    ValidityRepairOptions options;
    if (o.keep_voxels != VoxelKeeping::Never && voxels) {
        options.voxels = voxels;
        options.noisy_voxels = noisy_voxel_vertices(result.surface, result.field);
        options.put_back_from_share = o.keep_voxels == VoxelKeeping::Auto ? kVoxelPutBackShare : 0.0;
    }
    if (o.validity == ValidityMode::Check) options.max_rounds = 0;
    // Where the voxels are noisy, a fold is first smoothed (docs/accuracy.md, "Noisy voxels").
    const Eigen::VectorXd noisy = noise_multipliers(o.extensions, result.surface, result.field);
    options.smooth_first.assign(std::size_t(noisy.size()), 0);
    for (Eigen::Index v = 0; v < noisy.size(); ++v) options.smooth_first[std::size_t(v)] = noisy[v] > 1;
    if (o.extensions.clamp) {  // stay in the clamp boxes, and keep the split copies' targets inside them
        options.clamp_half_width = o.extensions.clamp_half_width;
        options.split_offset = std::min(options.split_offset, 0.5 * o.extensions.clamp_half_width);
        options.qp.tolerance = o.extensions.clamp_tolerance;
    }
    ValidityRepairResult repaired = repair_validity(result.surface, result.field.normals, result.weights,
                                                    result.regularization.positions, options, clock.progress());
    result.regularization.positions = std::move(repaired.positions);
    result.field.normals = std::move(repaired.normals);
    result.validity = repaired.report;
    clock.finish(validity_text(*result.validity, result.weights));
}

std::int64_t labelled_voxels(const LabelVolume& labels) {
    return static_cast<std::int64_t>(std::count_if(labels.labels.begin(), labels.labels.end(), [](std::uint32_t l) { return l != 0; }));
}

/// Each label's closed surface and its measures, at the regularized positions (stage "labels").
void measure_labels(const LabelVolume& labels, PipelineResult& result) {
    result.label_meshes = label_meshes(result.surface);
    const std::vector<std::int64_t> voxels = labels.voxel_counts();
    for (const LabelMesh& mesh : result.label_meshes)
        result.label_measures.push_back(
            measure_label(result.surface, mesh, result.regularization.positions, voxels[mesh.label]));
    result.junctions = find_junctions(result.surface, complex_edges(result.surface));
}

std::string label_text(std::size_t count) { return std::to_string(count) + (count == 1 ? " label" : " labels"); }

/// Stages 2–4 on a loaded volume; `clock` may already hold the read stage.
PipelineResult run_stages(const LoadedVolume& loaded, const PipelineOptions& o, StageClock& clock) {
    PipelineResult result;
    result.input = loaded.description;
    result.grid = loaded.volume.grid;
    result.file = loaded.file;
    result.warnings = loaded.warnings;
    result.object_voxels = loaded.labels ? labelled_voxels(*loaded.labels) : loaded.volume.object_voxel_count();
    if (result.object_voxels == 0) throw Error(loaded.description + ": the object is empty");

    clock.start("surface");
    result.surface = loaded.labels ? extract_digital_surface(*loaded.labels, o.connectivity)
                                   : extract_digital_surface(loaded.volume, o.connectivity);
    clock.finish(std::to_string(result.surface.face_count()) + " surfels, " +
                 std::to_string(result.surface.vertex_count()) + " vertices, " +
                 component_text(result.surface.component_count));

    result.field = compute_normal_field(o.normals, loaded, result.surface, clock);

    clock.start("regularize");
    result.weights = global_weights(o);
    const ThinParts thin = thin_parts(o.extensions, loaded.voxel_labels(), result.surface, result.field);
    if (result.field.adaptive) result.field.adaptive->reach_maps.reset();  // used: freed before the solve
    result.sheet_faces = (thin.sheetness.array() >= 0.5).count();
    const Eigen::VectorXd local_shrink =
        apply_regularization_extensions(o.extensions, result.surface, result.field, thin, result.weights);
    SolverOptions solver;
    solver.kind = o.solver;
    solver.max_error_voxels = o.max_error_voxels;  // iterative solvers: within this of the exact answer
    solver.progress = clock.progress();             // each iteration, as stage "solve" (and "clamp")
    result.regularization = run_regularization(o.extensions, loaded.volume, result.surface, result.field.normals,
                                               result.weights, local_shrink, solver, result.extension_report);
    clock.finish(result.regularization.solve.solver + ", relative residual " +
                 format("%.2e", result.regularization.solve.relative_residual));
    // On a label map, the complex: its junction edges are shared by three faces or more, which
    // meet there by index (mesh_validity.hpp); each label's surface is a subset of its faces.
    // The repair spreads from a junction into the sheets that meet there (docs/multi-label.md).
    if (o.validity != ValidityMode::Off) check_and_repair(o, result, clock, loaded.labels ? nullptr : &loaded.volume);
    result.faces_against_field =
        count_faces_against_field(result.regularization.positions, result.surface.quads, result.field.normals);
    if (loaded.labels) {
        clock.start("labels");
        measure_labels(*loaded.labels, result);
        clock.finish(label_text(result.label_meshes.size()) + ", " + std::to_string(result.junctions.vertex_count) +
                     " junction vertices");
    }
    result.stage_seconds = clock.stage_seconds();
    return result;
}

void check_label_values_fit(const DigitalSurface& surface) {
    for (const std::int64_t value : surface.label_values)
        if (value < INT32_MIN || value > INT32_MAX)
            throw Error("label " + std::to_string(value) + " does not fit the 32-bit face properties of the output");
}

/// The complex with the labels on either side of each face (values, not indices).
void add_face_labels(const DigitalSurface& surface, PolygonMesh& mesh) {
    const std::int64_t m = surface.face_count();
    Eigen::VectorXi inner(m), outer(m);
    for (std::int64_t f = 0; f < m; ++f) {
        inner[f] = static_cast<int>(surface.label_values[surface.face_labels[std::size_t(f)].inner]);
        outer[f] = static_cast<int>(surface.label_values[surface.face_labels[std::size_t(f)].outer]);
    }
    mesh.face_integers.emplace_back("inner_label", std::move(inner));
    mesh.face_integers.emplace_back("outer_label", std::move(outer));
}

/// A mesh of the grid frame in --space, tagged with its coordinate system when the input file
/// has a world geometry.
PolygonMesh mesh_for_output(PolygonMesh mesh, const PipelineResult& result, const PipelineOutputs& outputs) {
    mesh = mesh_in_space(std::move(mesh), result.grid, outputs.space);
    if (!result.file.world_geometry) mesh.coordinate_system.clear();  // shapes, DGtal files: no world frame to name
    return mesh;
}

/// Every label's surface, next to -o.
void write_label_meshes(const PipelineResult& result, const PipelineOutputs& outputs, const ProgressCallback& progress) {
    const std::size_t count = result.label_meshes.size();
    for (std::size_t i = 0; i < count; ++i) {
        write_mesh(label_output_path(outputs.mesh, result.surface.label_values[result.label_meshes[i].label]),
                   output_label_mesh(result, outputs, i));
        report_progress(progress, "write", double(i + 1) / double(count));
    }
}

/// The outputs of a run and their flags, label meshes included, for the distinctness check.
std::vector<std::pair<std::string, std::string>> all_outputs(const PipelineResult& result, const PipelineOutputs& o) {
    std::vector<std::pair<std::string, std::string>> outputs = {{"-o", o.mesh},
                                                                {"--input-mesh", o.input_mesh},
                                                                {"--report", o.report},
                                                                {"--export-normals", o.normals},
                                                                {"--features", o.features},
                                                                {"--html", o.html}};
    for (const LabelMesh& mesh : result.label_meshes) {
        const std::int64_t value = result.surface.label_values[mesh.label];
        outputs.emplace_back("the surface of label " + std::to_string(value), label_output_path(o.mesh, value));
    }
    return outputs;
}

nlohmann::json label_json(const LabelMeasures& m, const std::string& path) {
    return {{"label", m.value},
            {"faces", m.faces},
            {"vertices", m.vertices},
            {"area", m.area},
            {"volume", m.volume},
            {"voxel_volume", m.voxel_volume},
            {"volume_ratio", m.voxel_volume > 0 ? m.volume / m.voxel_volume : 0.0},
            {"components", m.components},
            {"genus", m.genus},
            {"euler_characteristics", m.euler_characteristics},
            {"pinch_vertices", m.pinch_vertices},
            {"mesh", path}};
}

nlohmann::json optional_json(const std::optional<double>& value) {
    return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

nlohmann::json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

/// The rows of a 3×3 or 4×4 matrix.
template <int N>
nlohmann::json matrix_json(const Eigen::Matrix<double, N, N>& m) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < N; ++r) {
        nlohmann::json row = nlohmann::json::array();
        for (int c = 0; c < N; ++c) row.push_back(m(r, c));
        rows.push_back(row);
    }
    return rows;
}

/// The output space of the report: its name and the affine maps into it from the grid frame
/// and from voxel indices (index → grid frame: origin + spacing ⊙ index).
nlohmann::json space_json(const VoxelGrid& grid, const PipelineOutputs& outputs, bool world_geometry) {
    const AffineMap to_space = grid_to_space(grid, outputs.space);
    return {{"name", output_space_name(outputs.space)},
            {"recorded_in_files", world_geometry ? slicer_coordinate_system(outputs.space) : ""},
            {"grid_to_output", matrix_json(homogeneous_matrix(to_space))},
            {"index_to_output", matrix_json(grid_affine(grid, outputs.space))},
            {"faces_reversed", to_space.reverses_orientation()}};
}

}  // namespace

void check_and_repair_welded(const PipelineOptions& options, PipelineResult& result, const ProgressCallback& progress) {
    if (options.validity == ValidityMode::Off) return;
    StageClock clock(progress);
    check_and_repair(options, result, clock, nullptr);
    result.faces_against_field =
        count_faces_against_field(result.regularization.positions, result.surface.quads, result.field.normals);
    for (const auto& stage : clock.stage_seconds()) result.stage_seconds.push_back(stage);
}

double total_seconds(const PipelineResult& result) {
    return std::accumulate(result.stage_seconds.begin(), result.stage_seconds.end(), 0.0,
                           [](double sum, const auto& stage) { return sum + stage.second; });
}

void check_pipeline_options(const PipelineOptions& o, bool input_is_shape) {
    check_normal_field_options(o.normals, input_is_shape);
    check_weight_flags(o);
    if (!(o.max_error_voxels > 0) || !std::isfinite(o.max_error_voxels))
        throw Error("--max-error " + format("%g", o.max_error_voxels) + ": must be positive and finite (voxels)");
    check_regularization_extensions(o.extensions);
}

namespace {

/// The checks of check_multi_label_options that only need the options.
void check_label_map_options(const PipelineOptions& o) {
    const std::string kind = o.normals.kind.empty() ? "ii" : o.normals.kind;
    if (kind != "ii" && kind != "trivial")
        throw Error("--normals " + kind + " does not apply to --multi-label (use ii, trivial or --normals-file)");
    if (o.extensions.clamp) throw Error("--clamp does not apply to --multi-label");
}

}  // namespace

void check_multi_label_options(const VolumeSource& source, const PipelineOptions& o) {
    if (!source.is_multi_label()) return;
    if (source.min_value || source.max_value || source.label)
        throw Error(std::string(source.label ? "--label" : source.min_value ? "--min" : "--max") +
                    " chooses one object; with --multi-label every non-zero value is a label (choose some with --labels)");
    check_label_map_options(o);
}

PipelineResult run_pipeline(const LoadedVolume& loaded, const PipelineOptions& options, const ProgressCallback& progress) {
    check_pipeline_options(options, loaded.shape.has_value());
    if (loaded.labels) check_label_map_options(options);
    StageClock clock(progress);
    return run_stages(loaded, options, clock);
}

PipelineResult run_pipeline(const VolumeSource& source, const PipelineOptions& options, const ProgressCallback& progress) {
    if (options.blocks.enabled()) return run_streaming_pipeline(source, options, progress);
    if (!source.max_memory.empty()) parse_memory_size("--max-memory", source.max_memory);
    check_pipeline_options(options, !source.shape.empty());
    check_multi_label_options(source, options);
    StageClock clock(progress);
    clock.start(source.shape.empty() ? "read" : "digitize");
    const LoadedVolume loaded = load_volume(source);
    clock.finish(loaded.labels ? std::to_string(labelled_voxels(*loaded.labels)) + " labelled voxels"
                               : std::to_string(loaded.volume.object_voxel_count()) + " object voxels");
    if (!source.max_memory.empty()) {
        // Before anything proportional to the surface is allocated: count its surfels (one pass).
        const bool factorization = options.solver == SolverKind::Cholmod || options.solver == SolverKind::Auto;
        check_run_memory(source, loaded.volume.grid.voxel_count(),
                         loaded.labels ? count_surfels(*loaded.labels) : count_surfels(loaded.volume), factorization);
    }
    PipelineOptions with_maps = options;  // local weight maps are read like the input
    if (source.raw_layout) with_maps.extensions.map_raw_layout = *source.raw_layout;
    with_maps.extensions.max_voxels = source.max_voxels;
    return run_stages(loaded, with_maps, clock);
}

PolygonMesh result_mesh(const PipelineResult& result, bool triangulate, bool digital) {
    PolygonMesh mesh;
    mesh.vertices = digital ? result.surface.vertices : result.regularization.positions;
    mesh.faces = result.surface.quads;
    mesh.face_normals = result.field.normals;
    if (result.field.at) mesh.vertex_scalars.emplace_back("v", result.field.at->features);
    if (!result.label_meshes.empty()) add_face_labels(result.surface, mesh);
    return triangulate ? triangulate_shorter_diagonal(mesh) : mesh;
}

std::string label_output_path(const std::string& mesh_path, std::int64_t value) {
    const std::filesystem::path path(mesh_path);
    std::filesystem::path out = path.parent_path() / (path.stem().string() + "-" + std::to_string(value));
    out += path.extension();
    return out.string();
}

PolygonMesh output_mesh(const PipelineResult& result, const PipelineOutputs& outputs, bool digital) {
    return mesh_for_output(result_mesh(result, outputs.triangulate, digital), result, outputs);
}

PolygonMesh output_label_mesh(const PipelineResult& result, const PipelineOutputs& outputs, std::size_t index) {
    const PolygonMesh polygons =
        label_polygon_mesh(result.label_meshes.at(index), result.regularization.positions, result.field.normals);
    return mesh_for_output(outputs.triangulate ? triangulate_shorter_diagonal(polygons) : polygons, result, outputs);
}

void check_pipeline_outputs(const PipelineOutputs& o) {
    if (!o.mesh.empty()) check_mesh_output_path("-o", o.mesh);
    if (!o.input_mesh.empty()) check_mesh_output_path("--input-mesh", o.input_mesh);
    if (!o.report.empty()) check_output_folder("--report", o.report);
    if (!o.html.empty()) check_page_output_path("--html", o.html);
    if (!o.normals.empty()) check_output_folder("--export-normals", o.normals);
    if (!o.features.empty()) {
        if (file_extension(o.features) != "obj")
            throw Error("--features " + o.features + ": the feature lines are written as OBJ polylines (use .obj)");
        check_output_folder("--features", o.features);
    }
    if (!o.fragments.empty() && std::filesystem::exists(o.fragments) && !std::filesystem::is_directory(o.fragments))
        throw Error("--fragments " + o.fragments + ": exists and is not a folder");
    check_distinct_outputs({{"-o", o.mesh},
                            {"--input-mesh", o.input_mesh},
                            {"--report", o.report},
                            {"--export-normals", o.normals},
                            {"--features", o.features},
                            {"--html", o.html}});
}

void write_pipeline_outputs(PipelineResult& result, const PipelineOptions& options, const PipelineOutputs& outputs,
                            const VolumeSource& source, const ProgressCallback& progress) {
    StageClock clock(progress);
    clock.start("write");
    if (!result.label_meshes.empty()) {
        check_label_values_fit(result.surface);
        check_distinct_outputs(all_outputs(result, outputs));  // before anything is written
    }
    if (!outputs.mesh.empty()) {
        write_mesh(outputs.mesh, output_mesh(result, outputs));
        write_label_meshes(result, outputs, progress);  // next to -o
    }
    if (!outputs.input_mesh.empty()) write_mesh(outputs.input_mesh, output_mesh(result, outputs, true));
    if (!outputs.normals.empty())
        write_normals_file(outputs.normals, result.surface, result.field.normals, result.field.description);
    if (!outputs.features.empty())
        write_feature_lines(outputs.features, options.normals, result.field, result.surface,
                            map_points(grid_to_space(result.grid, outputs.space), result.regularization.positions));
    if (!outputs.fragments.empty()) {
        if (!result.block_layout) throw Error("--fragments needs a block-wise run (--block-size, or dsreg-mpi)");
        write_block_fragments(outputs.fragments, result, *result.block_layout);
    }
    std::string written = outputs.mesh;
    if (!result.label_meshes.empty() && !outputs.mesh.empty())
        written += " and " + label_text(result.label_meshes.size()) + " (" +
                   label_output_path(outputs.mesh, result.surface.label_values[result.label_meshes.front().label]) +
                   (result.label_meshes.size() > 1 ? ", ...)" : ")");
    if (!outputs.html.empty()) write_html_view(outputs.html, result_page(result, options));
    clock.finish(written);
    result.stage_seconds.push_back(clock.stage_seconds().back());
    if (outputs.report.empty()) return;
    const std::string text = pipeline_report(result, options, outputs, source).dump(2) + "\n";
    write_file_atomically(outputs.report, [&](std::ostream& out) { out << text; });
}

nlohmann::json pipeline_report(const PipelineResult& r, const PipelineOptions& o, const PipelineOutputs& outputs,
                               const VolumeSource& source) {
    const DigitalSurface& surface = r.surface;
    const NormalField& field = r.field;
    const SolveReport& solve = r.regularization.solve;
    nlohmann::json report;
    report["input"] = r.input;
    report["input_file"] = {{"format", r.file.format}, {"value_type", r.file.value_type}, {"notes", r.file.notes},
                            {"world_geometry", r.file.world_geometry}};
    report["warnings"] = r.warnings;
    report["grid"] = {{"dims", r.grid.dims},
                      {"spacing", vector_json(r.grid.spacing)},
                      {"origin", vector_json(r.grid.origin)},
                      {"direction", matrix_json(r.grid.direction)}};
    report["space"] = space_json(r.grid, outputs, r.file.world_geometry);
    report["counts"] = {{"voxels", r.grid.voxel_count()},
                        {"object_voxels", r.object_voxels},
                        {"surfels", surface.face_count()},
                        {"vertices", surface.vertex_count()},
                        {"components", surface.component_count},
                        {"split_pointels", surface.split_pointel_count},
                        {"euler_characteristics", component_euler_characteristics(surface)},
                        {"faces_against_field", r.faces_against_field}};
    report["parameters"] = {{"alpha", o.alpha}, {"beta", o.beta}, {"gamma", o.gamma},
                            {"min", optional_json(source.min_value)}, {"max", optional_json(source.max_value)},
                            {"label", optional_json(source.label)},
                            {"connectivity", static_cast<int>(o.connectivity)},
                            {"normals", o.normals.kind.empty() ? (o.normals.file.empty() ? "ii" : "file") : o.normals.kind},
                            {"normals_input", field.input},
                            {"radius", optional_json(field.radius)},
                            {"ii_kernel", field.ii_kernel ? nlohmann::json(*field.ii_kernel) : nlohmann::json(nullptr)},
                            {"ii_extrapolated", field.ii_extrapolated},
                            {"field_lift_margin", optional_json(o.normals.lift_margin)},
                            {"lifted_faces", field.lifted_faces},
                            {"faces_against_surfels", std::int64_t(field.faces_against_surfels.size())},
                            {"noise_fairness", noise_fairness(o.extensions)},
                            {"solver", solve.solver}, {"max_error_voxels", o.max_error_voxels},
                            {"triangulate", outputs.triangulate}};
    if (field.adaptive) {
        const AdaptiveNormalField& a = *field.adaptive;
        report["adaptive_ii"] = {{"radius_min", a.radius.minCoeff()},
                                 {"radius_mean", a.radius.mean()},
                                 {"radius_max", a.radius.maxCoeff()},
                                 {"extrapolated_share", a.extrapolated.mean()},
                                 {"reach_min", a.reach.smallest().minCoeff()},
                                 {"reach_cap", a.reach_cap},
                                 {"noisy_smoothed_faces", a.noisy_smoothed_faces}};
    }
    if (r.weights.vertex_alpha.size() > 0)
        report["thin_part_alpha"] = {{"reference_reach", alpha_reach(o.extensions, r.grid)},
                                     {"sheet_reference_reach", sheet_alpha_reach(o.extensions, r.grid)},
                                     {"sheet_faces", r.sheet_faces},
                                     {"multiplier_max", r.weights.vertex_alpha.maxCoeff()},
                                     {"vertices_above_one", (r.weights.vertex_alpha.array() > 1.0).count()}};
    if (r.weights.vertex_gamma.size() > 0 && noise_fairness(o.extensions) > 0 && !field.faces_against_surfels.empty())
        report["noise_fairness"] = {{"multiplier_max", r.weights.vertex_gamma.maxCoeff()},
                                    {"vertices_above_one", (r.weights.vertex_gamma.array() > 1.0).count()}};
    if (field.at) report["at"] = at_report(o.normals, field, surface);
    report["solve"] = {{"relative_residual", solve.relative_residual},
                       {"error_bound", solve.error_bound},
                       {"solver", solve.solver},
                       {"note", solve.note},
                       {"multigrid_levels", solve.multigrid_levels},
                       {"operator_complexity", solve.operator_complexity},
                       {"iterations", solve.iterations},
                       {"factor_nonzeros", std::int64_t(solve.factor_nonzeros)},
                       {"unknowns", 3 * surface.vertex_count()}};
    report["energy_before"] = energy_json(r.regularization.energy_before, r.weights);
    report["energy_after"] = energy_json(r.regularization.energy_after, r.weights);
    report["validity"] = r.validity ? validity_json(*r.validity, r.weights, o.validity) : nlohmann::json(nullptr);
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [name, seconds] : r.stage_seconds) stages[name] = seconds;
    stages["assembly"] = r.regularization.assembly_seconds;
    stages["solve"] = r.regularization.solve_seconds;
    report["seconds"] = stages;
    report["total_seconds"] = total_seconds(r);
    report["peak_memory_bytes"] = peak_memory_bytes();
    report["outputs"] = {{"mesh", outputs.mesh}, {"input_mesh", outputs.input_mesh},
                         {"normals", outputs.normals}, {"features", outputs.features}, {"html", outputs.html},
                         {"fragments", outputs.fragments}};
    if (!r.label_meshes.empty()) {
        nlohmann::json labels = nlohmann::json::array();
        for (const LabelMeasures& m : r.label_measures) labels.push_back(label_json(m, outputs.mesh.empty() ? "" : label_output_path(outputs.mesh, m.value)));
        report["labels"] = labels;
        std::int64_t pinches = 0;
        for (const LabelMeasures& m : r.label_measures) pinches += m.pinch_vertices;
        report["label_complex"] = {{"labels", r.label_meshes.size()},
                                   {"junction_vertices", r.junctions.vertex_count},
                                   {"junction_points", r.junctions.point_count},
                                   {"junction_edges", r.junctions.edge_count},
                                   {"interface_normal_faces", field.interface_normal_faces},
                                   {"pinch_vertices", pinches}};
        report["parameters"]["multi_label"] = true;
    }
    report.update(r.extension_report);
    return report;
}

std::string summary_line(const PipelineResult& r, const PipelineOptions& o) {
    const RegularizationResult& reg = r.regularization;
    std::ostringstream line;
    line << r.input << ": " << r.surface.face_count() << " surfels, " << r.surface.vertex_count() << " vertices, "
         << component_text(r.surface.component_count);
    if (!r.label_meshes.empty())
        line << ", " << label_text(r.label_meshes.size()) << ", " << r.junctions.vertex_count << " junction vertices";
    line << "; energy " << format("%.4g", reg.energy_before.total(r.weights))
         << " -> " << format("%.4g", reg.energy_after.total(r.weights)) << "; " << reg.solve.solver << " residual "
         << format("%.1e", reg.solve.relative_residual);
    if (r.validity)
        line << "; " << validity_text(*r.validity, r.weights);
    else if (r.faces_against_field > 0)
        line << "; " << r.faces_against_field << " faces folded against u";
    if (r.field.at)
        line << "; Ambrosio-Tortorelli " << r.field.at->total_rounds() << " rounds, "
             << (r.field.at->features.array() < o.normals.feature_threshold).count() << " feature vertices";
    line << "; " << format("%.2f", total_seconds(r)) << " s, " << human_bytes(double(peak_memory_bytes())) << " peak";
    return line.str();
}

}  // namespace dsreg
