#include "eval_command.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "dsreg/text.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/pipeline.hpp"

namespace dsreg::cli {

namespace {

struct EvalOptions {
    std::string mesh;
    TruthShapeOptions truth;
    std::optional<double> h;
    std::optional<double> wall_margin;
    int volume_cells = 64;
    bool json = false;
};

nlohmann::json stats_json(const ErrorStats& s, bool with_p95) {
    nlohmann::json j = {{"mean", s.mean}, {"l2", s.l2}, {"linf", s.linf}};
    if (with_p95) j["p95"] = s.p95;
    return j;
}

void check_positive(const char* option, const std::optional<double>& value, bool allow_zero = false) {
    if (value && (!std::isfinite(*value) || *value < 0 || (!allow_zero && *value == 0)))
        throw Error(std::string(option) + " must be " + (allow_zero ? "non-negative" : "positive") + " (got " +
                    format("%g", *value) + ")");
}

bool has_clipped_axis(const ImplicitShape& shape) {
    return shape.clipped[0] || shape.clipped[1] || shape.clipped[2];
}

nlohmann::json report_json(const EvalOptions& o, const ImplicitShape& shape, double h, double wall_margin,
                           const MeshEvaluation& e) {
    nlohmann::json j;
    j["mesh"] = o.mesh;
    j["shape"] = shape.name;
    j["h"] = h;
    j["wall_margin"] = wall_margin;
    j["vertices"] = {{"evaluated", e.vertices_evaluated}, {"outside_region", e.vertices_outside_region}};
    j["faces"] = {{"evaluated", e.faces_evaluated}, {"outside_region", e.faces_outside_region},
                  {"degenerate", e.faces_degenerate}};
    j["vertex_distance"] = stats_json(e.vertex_distance, true);
    if (o.h) j["vertex_distance_h"] = stats_json(e.vertex_distance.scaled(1.0 / h), true);
    j["normal_angle_deg"] = stats_json(e.normal_angle_deg, true);
    j["mesh_volume"] = e.mesh_volume;
    j["shape_volume"] = e.shape_volume;
    j["relative_volume_error"] = e.relative_volume_error;
    j["voxel_classification"] = {{"correct", e.voxels.correct}, {"total", e.voxels.total},
                                 {"share", e.voxels.share()}, {"h", h}};
    j["triangle_min_angle_deg"] = {{"min", e.triangle_min_angle_min_deg}, {"mean", e.triangle_min_angle_mean_deg},
                                   {"triangles", e.triangles}};
    return j;
}

void print_stats_row(std::ostream& out, const std::string& name, const ErrorStats& s, const char* pattern,
                     const std::string& unit) {
    out << "  " << name;
    for (std::size_t pad = name.size(); pad < 24; ++pad) out << ' ';
    for (double v : {s.mean, s.l2, s.linf, s.p95}) out << format(pattern, v) << "  ";
    out << unit << '\n';
}

void print_table(std::ostream& out, const EvalOptions& o, const ImplicitShape& shape, double h, double wall_margin,
                 const MeshEvaluation& e) {
    out << "dsreg eval " << o.mesh << " against " << shape.name << "\n";
    out << "  " << e.vertices_evaluated << " vertices and " << e.faces_evaluated << " faces evaluated";
    if (e.vertices_outside_region + e.faces_outside_region > 0)
        out << " (" << e.vertices_outside_region << " vertices and " << e.faces_outside_region
            << " faces within " << format("%g", wall_margin) << " of a clipped box face left out)";
    if (e.faces_degenerate > 0) out << "; " << e.faces_degenerate << " faces without a normal";
    out << "\n\n";
    out << "  quantity                      mean          L2        Linf         p95\n";
    print_stats_row(out, "vertex distance", e.vertex_distance, "%10.4g", "(physical units)");
    if (o.h) print_stats_row(out, "vertex distance / h", e.vertex_distance.scaled(1.0 / h), "%10.4f", "(units of h)");
    print_stats_row(out, "normal angle", e.normal_angle_deg, "%10.3f", "(degrees)");
    out << "\n  relative volume error   " << format("%+.3e", e.relative_volume_error) << "  (mesh "
        << format("%.6g", e.mesh_volume) << ", shape " << format("%.6g", e.shape_volume) << ")\n";
    out << "  voxel centres correct   " << e.voxels.correct << " / " << e.voxels.total << " = "
        << format("%.4f", 100.0 * e.voxels.share()) << " %  (digitization at h = " << format("%g", h) << ")\n";
    out << "  triangle min angle      min " << format("%.2f", e.triangle_min_angle_min_deg) << ", mean "
        << format("%.2f", e.triangle_min_angle_mean_deg) << " degrees over " << e.triangles << " triangles\n";
}

void run(const EvalOptions& o) {
    check_positive("--h", o.h);
    check_positive("--wall-margin", o.wall_margin, true);
    if (o.volume_cells < 8) throw Error("--volume-cells must be at least 8");
    const ImplicitShape shape = make_truth_shape(o.truth);
    const PolygonMesh mesh = read_mesh(o.mesh);
    const double h = o.h ? *o.h : default_grid_step(shape);
    const double wall_margin = o.wall_margin ? *o.wall_margin : (has_clipped_axis(shape) ? 3.0 * h : 0.0);

    MeshEvaluationOptions options;
    options.grid_step = h;
    options.wall_margin = wall_margin;
    options.volume_cells = o.volume_cells;
    MeshEvaluation evaluation;
    try {
        evaluation = evaluate_mesh(mesh, shape, options);
    } catch (const Error& e) {
        throw Error(o.mesh + ": " + e.what());
    }
    if (o.json) std::cout << report_json(o, shape, h, wall_margin, evaluation).dump(2) << '\n';
    else print_table(std::cout, o, shape, h, wall_margin, evaluation);
}

}  // namespace

void add_truth_shape_options(CLI::App& command, TruthShapeOptions& o) {
    command.add_option("--shape", o.shape,
                       "Ground truth: a named shape (sphere1 sphere9 ellipsoid cylinder torus rcube goursat goursat-hole "
                       "distel leopold diabolo heart crixxi), a polynomial in x, y, z (F <= 0 inside), or 'plane' "
                       "(the tilted half-space n.p <= d in [-B,B]^3)")
        ->required();
    command.add_option("--box", o.box, "Half-size B of the box of a polynomial shape (default 10, as for regularize) or "
                                       "of 'plane' (default 1)");
    command.add_option("--plane-normal", o.plane_normal, "Normal n of 'plane' (normalized)")
        ->expected(3)
        ->delimiter(',')
        ->capture_default_str();
    command.add_option("--plane-offset", o.plane_offset, "Signed distance d of 'plane' from the origin")->capture_default_str();
}

ImplicitShape make_truth_shape(const TruthShapeOptions& o) {
    if (o.box && (!(*o.box > 0) || !std::isfinite(*o.box))) throw Error("--box must be positive (got " + format("%g", *o.box) + ")");
    if (o.shape == "plane") {
        if (o.plane_normal.size() != 3) throw Error("--plane-normal needs three values X,Y,Z");
        return make_plane_shape(Eigen::Vector3d(o.plane_normal[0], o.plane_normal[1], o.plane_normal[2]), o.plane_offset,
                                o.box ? *o.box : 1.0);
    }
    return make_shape(o.shape, o.box ? *o.box : 10.0);
}

void add_eval_command(CLI::App& app) {
    auto options = std::make_shared<EvalOptions>();
    CLI::App* cmd = app.add_subcommand(
        "eval", "Measure a mesh (OBJ/OFF/PLY/STL/VTK/VTP, from dsreg or any tool) against an implicit shape: vertex distance, "
                "normal error, volume, voxel classification, triangle angles");
    cmd->add_option("mesh", options->mesh, "Mesh file: .obj .off .ply .stl .vtk .vtp (triangles and/or quads)")->required();
    add_truth_shape_options(*cmd, options->truth);
    cmd->add_option("--h", options->h,
                    "Grid step: distances are also given in units of h, and the voxel classification uses "
                    "digitize(shape, h) (default: 1/64 of the shape's extent, as for regularize)");
    cmd->add_option("--wall-margin", options->wall_margin,
                    "Leave out vertices and faces closer than this to a clipped box face (physical units; "
                    "default 3h for shapes clipped by their box, else 0)");
    cmd->add_option("--volume-cells", options->volume_cells, "Initial cells per axis of the quadrature of the shape's volume (features thinner than 1/N of the box may be missed)")->capture_default_str();
    cmd->add_flag("--json", options->json, "Print one JSON object instead of the table");
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
