// dsreg — the `dsreg eval` job (include/dsreg/evaluation_report.hpp).
#include "dsreg/evaluation_report.hpp"

#include <cmath>

#include "dsreg/error.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/text.hpp"

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

ImplicitShape check_evaluation_request(const EvaluationRequest& o) {
    check_positive("--h", o.h);
    check_positive("--wall-margin", o.wall_margin, true);
    if (o.volume_cells < 8) throw Error("--volume-cells must be at least 8");
    return make_truth_shape(o.truth);
}

EvaluationRun run_evaluation(const PolygonMesh& mesh, const std::string& mesh_name, const EvaluationRequest& o) {
    EvaluationRun run;
    run.shape = check_evaluation_request(o);
    run.h = o.h ? *o.h : default_grid_step(run.shape);
    run.h_given = o.h.has_value();
    run.wall_margin = o.wall_margin ? *o.wall_margin : (has_clipped_axis(run.shape) ? 3.0 * run.h : 0.0);

    MeshEvaluationOptions options;
    options.grid_step = run.h;
    options.wall_margin = run.wall_margin;
    options.volume_cells = o.volume_cells;
    try {
        run.evaluation = evaluate_mesh(mesh, run.shape, options);
    } catch (const Error& e) {
        throw Error(mesh_name + ": " + e.what());
    }
    return run;
}

nlohmann::json evaluation_report(const EvaluationRun& run, const std::string& mesh_name) {
    const MeshEvaluation& e = run.evaluation;
    nlohmann::json j;
    j["mesh"] = mesh_name.empty() ? nlohmann::json(nullptr) : nlohmann::json(mesh_name);
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
    j["voxel_classification"] = {{"correct", e.voxels.correct}, {"total", e.voxels.total},
                                 {"share", e.voxels.share()}, {"h", run.h}};
    j["triangle_min_angle_deg"] = {{"min", e.triangle_min_angle_min_deg}, {"mean", e.triangle_min_angle_mean_deg},
                                   {"triangles", e.triangles}};
    return j;
}

}  // namespace dsreg
