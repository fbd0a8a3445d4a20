// dsreg — the `dsreg eval` job (include/dsreg/evaluation_report.hpp).
#include "dsreg/evaluation_report.hpp"

#include <cmath>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/text.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg {

namespace {

void check_positive(const char* option, const std::optional<double>& value, bool allow_zero = false) {
    if (value && (!std::isfinite(*value) || *value < 0 || (!allow_zero && *value == 0)))
        throw Error(std::string(option) + " must be " + (allow_zero ? "non-negative" : "positive") + " (got " +
                    format("%g", *value) + ")");
}

bool has_clipped_axis(const ImplicitShape& shape) {
    return shape.clipped[0] || shape.clipped[1] || shape.clipped[2];
}

nlohmann::json stats_json(const ErrorStats& s, bool with_p95) {
    nlohmann::json j = {{"mean", s.mean}, {"l2", s.l2}, {"linf", s.linf}};
    if (with_p95) j["p95"] = s.p95;
    return j;
}

nlohmann::json classification_json(const VoxelClassification& c) {
    return {{"correct", c.correct},
            {"total", c.total},
            {"share", c.share()},
            {"object_correct", c.object_correct},
            {"object_total", c.object_total},
            {"object_share", c.object_share()},
            {"boundary_correct", c.boundary_correct},
            {"boundary_total", c.boundary_total},
            {"boundary_share", c.boundary_share()}};
}

nlohmann::json validity_json(const EvaluationRun& run) {
    const MeshValidity& v = run.validity;
    return {{"intersecting_pairs", v.intersecting_pairs},
            {"degenerate_triangles", v.degenerate_triangles},
            {"folded_faces", run.has_face_field ? nlohmann::json(v.folded_faces) : nlohmann::json(nullptr)},
            {"triangles", v.triangles}};
}

/// The mesh in the shape's frame: mapped from the voxel frame of digitize(shape, h) with
/// --voxel-coordinates (voxel (0,0,0) at the grid's first centre, steps of the grid's spacing).
PolygonMesh mesh_in_shape_frame(const PolygonMesh& mesh, const ImplicitShape& shape, double h) {
    PolygonMesh mapped = mesh;
    const VoxelGrid grid = digitize(shape, h).grid;
    for (Eigen::Index i = 0; i < mapped.vertices.rows(); ++i)
        mapped.vertices.row(i) =
            grid.voxel_center(0, 0, 0).transpose() + mapped.vertices.row(i).cwiseProduct(grid.spacing.transpose());
    return mapped;
}

/// --face-errors: one line per face, its centroid (the shape's frame) and normal error (nan
/// where not evaluated).
void write_face_errors(const std::string& path, const PolygonMesh& mesh, const MeshEvaluation& e) {
    const PointMatrix centroids = face_centroids(mesh.vertices, mesh.faces);
    write_file_atomically(path, [&](std::ostream& out) {
        out << "x,y,z,normal_angle_deg\n";
        for (Eigen::Index f = 0; f < centroids.rows(); ++f)
            out << format("%.9g", centroids(f, 0)) << ',' << format("%.9g", centroids(f, 1)) << ','
                << format("%.9g", centroids(f, 2)) << ',' << format("%.9g", e.face_angle_deg[std::size_t(f)]) << '\n';
    });
}

/// --volume: the voxel classification against the file's voxels.
EvaluationRun run_against_volume(const PolygonMesh& mesh, const std::string& mesh_name, const EvaluationRequest& o) {
    ValueRange range;
    if (o.min_value) range.has_min = true, range.min = *o.min_value;
    if (o.max_value) range.has_max = true, range.max = *o.max_value;
    const BinaryVolume volume = read_volume(o.volume, range);
    EvaluationRun run;
    run.volume = o.volume;
    run.has_face_field = mesh.face_normals.rows() > 0;
    try {
        run.evaluation.has_voxel_classification = true;
        run.evaluation.voxels = classify_voxel_centres(mesh, volume);
        run.validity = check_mesh_validity(mesh.vertices, mesh.faces, mesh.face_normals);
    } catch (const Error& e) {
        throw Error(mesh_name + ": " + e.what());
    }
    return run;
}

}  // namespace

ImplicitShape make_truth_shape(const TruthShapeOptions& o) {
    if (o.box && (!(*o.box > 0) || !std::isfinite(*o.box))) throw Error("--box must be positive (got " + format("%g", *o.box) + ")");
    if (o.shape == "plane") {
        if (o.plane_normal.size() != 3) throw Error("--plane-normal needs three values X,Y,Z");
        return make_plane_shape(Eigen::Vector3d(o.plane_normal[0], o.plane_normal[1], o.plane_normal[2]), o.plane_offset,
                                o.box ? *o.box : 1.0);
    }
    return make_shape(o.shape, o.box ? *o.box : 10.0);
}

std::optional<ImplicitShape> check_evaluation_request(const EvaluationRequest& o) {
    if (!o.volume.empty()) {
        if (o.h || o.wall_margin || !o.truth.shape.empty() || o.voxel_coordinates || !o.face_errors.empty())
            throw Error("--volume gives the truth as voxels: --shape, --h, --wall-margin, --voxel-coordinates and "
                        "--face-errors do not apply");
        return std::nullopt;
    }
    if (o.truth.shape.empty()) throw Error("eval needs the truth: --shape (an implicit shape) or --volume (a volume file)");
    if (o.min_value || o.max_value) throw Error("--min and --max only apply to --volume");
    check_positive("--h", o.h);
    check_positive("--wall-margin", o.wall_margin, true);
    if (o.volume_cells < 8) throw Error("--volume-cells must be at least 8");
    return make_truth_shape(o.truth);
}

EvaluationRun run_evaluation(const PolygonMesh& input, const std::string& mesh_name, const EvaluationRequest& o) {
    std::optional<ImplicitShape> shape = check_evaluation_request(o);
    if (!shape) return run_against_volume(input, mesh_name, o);
    EvaluationRun run;
    run.shape = std::move(*shape);
    run.h = o.h ? *o.h : default_grid_step(run.shape);
    run.h_given = o.h.has_value();
    run.wall_margin = o.wall_margin ? *o.wall_margin : (has_clipped_axis(run.shape) ? 3.0 * run.h : 0.0);

    const PolygonMesh mesh = o.voxel_coordinates ? mesh_in_shape_frame(input, run.shape, run.h) : input;
    run.has_face_field = mesh.face_normals.rows() > 0;

    MeshEvaluationOptions options;
    options.grid_step = run.h;
    options.wall_margin = run.wall_margin;
    options.volume_cells = o.volume_cells;
    try {
        run.evaluation = evaluate_mesh(mesh, run.shape, options);
        run.validity = check_mesh_validity(mesh.vertices, mesh.faces, mesh.face_normals);
    } catch (const Error& e) {
        throw Error(mesh_name + ": " + e.what());
    }
    if (!o.face_errors.empty()) write_face_errors(o.face_errors, mesh, run.evaluation);
    return run;
}

nlohmann::json evaluation_report(const EvaluationRun& run, const std::string& mesh_name) {
    const MeshEvaluation& e = run.evaluation;
    nlohmann::json j;
    j["mesh"] = mesh_name.empty() ? nlohmann::json(nullptr) : nlohmann::json(mesh_name);
    if (!run.volume.empty()) {
        j["volume"] = run.volume;
        j["voxel_classification"] = classification_json(e.voxels);
        j["validity"] = validity_json(run);
        return j;
    }
    j["shape"] = run.shape.name;
    j["h"] = run.h;
    j["wall_margin"] = run.wall_margin;
    j["vertices"] = {{"evaluated", e.vertices_evaluated}, {"outside_region", e.vertices_outside_region}};
    j["faces"] = {{"evaluated", e.faces_evaluated}, {"outside_region", e.faces_outside_region},
                  {"degenerate", e.faces_degenerate}};
    j["vertex_distance"] = stats_json(e.vertex_distance, true);
    if (run.h_given) j["vertex_distance_h"] = stats_json(e.vertex_distance.scaled(1.0 / run.h), true);
    j["normal_angle_deg"] = stats_json(e.normal_angle_deg, true);
    j["mesh_volume"] = e.mesh_volume;
    j["shape_volume"] = e.shape_volume;
    j["relative_volume_error"] = e.relative_volume_error;
    j["voxel_classification"] = classification_json(e.voxels);
    j["voxel_classification"]["h"] = run.h;
    j["triangle_min_angle_deg"] = {{"min", e.triangle_min_angle_min_deg}, {"mean", e.triangle_min_angle_mean_deg},
                                   {"triangles", e.triangles}};
    j["validity"] = validity_json(run);
    return j;
}

}  // namespace dsreg
