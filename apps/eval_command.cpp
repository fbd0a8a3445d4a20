#include "eval_command.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "dsreg/text.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation_report.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/pipeline.hpp"

namespace dsreg::cli {

namespace {

struct EvalOptions {
    std::string mesh;
    EvaluationRequest request;
    bool json = false;
};

void print_stats_row(std::ostream& out, const std::string& name, const ErrorStats& s, const char* pattern,
                     const std::string& unit) {
    out << "  " << name;
    for (std::size_t pad = name.size(); pad < 24; ++pad) out << ' ';
    for (double v : {s.mean, s.l2, s.linf, s.p95}) out << format(pattern, v) << "  ";
    out << unit << '\n';
}

void print_classification(std::ostream& out, const VoxelClassification& c, const std::string& source) {
    out << "  voxel centres correct   " << c.correct << " / " << c.total << " = " << format("%.4f", 100.0 * c.share())
        << " %  (" << source << ")\n";
    out << "    object voxels         " << c.object_correct << " / " << c.object_total << " = "
        << format("%.4f", 100.0 * c.object_share()) << " %\n";
    out << "    next to the surface   " << c.boundary_correct << " / " << c.boundary_total << " = "
        << format("%.4f", 100.0 * c.boundary_share()) << " %\n";
}

void print_validity(std::ostream& out, const EvaluationRun& run) {
    const MeshValidity& v = run.validity;
    out << "  self-intersections      " << v.intersecting_pairs << " pairs of triangles, " << v.degenerate_triangles
        << " degenerate triangles";
    if (run.has_face_field) out << ", " << v.folded_faces << " faces folded against the mesh's field";
    out << "\n";
}

void print_volume_table(std::ostream& out, const std::string& mesh, const EvaluationRun& run) {
    out << "dsreg eval " << mesh << " against the voxels of " << run.volume << "\n\n";
    print_classification(out, run.evaluation.voxels, run.volume);
    print_validity(out, run);
}

void print_table(std::ostream& out, const std::string& mesh, const EvaluationRun& run) {
    if (!run.volume.empty()) return print_volume_table(out, mesh, run);
    const MeshEvaluation& e = run.evaluation;
    const double h = run.h;
    out << "dsreg eval " << mesh << " against " << run.shape.name << "\n";
    out << "  " << e.vertices_evaluated << " vertices and " << e.faces_evaluated << " faces evaluated";
    if (e.vertices_outside_region + e.faces_outside_region > 0)
        out << " (" << e.vertices_outside_region << " vertices and " << e.faces_outside_region
            << " faces within " << format("%g", run.wall_margin) << " of a clipped box face left out)";
    if (e.faces_degenerate > 0) out << "; " << e.faces_degenerate << " faces without a normal";
    out << "\n\n";
    out << "  quantity                      mean          L2        Linf         p95\n";
    print_stats_row(out, "vertex distance", e.vertex_distance, "%10.4g", "(physical units)");
    if (run.h_given) print_stats_row(out, "vertex distance / h", e.vertex_distance.scaled(1.0 / h), "%10.4f", "(units of h)");
    print_stats_row(out, "normal angle", e.normal_angle_deg, "%10.3f", "(degrees)");
    out << "\n  relative volume error   " << format("%+.3e", e.relative_volume_error) << "  (mesh "
        << format("%.6g", e.mesh_volume) << ", shape " << format("%.6g", e.shape_volume) << ")\n";
    print_classification(out, e.voxels, "digitization at h = " + format("%g", h));
    out << "  triangle min angle      min " << format("%.2f", e.triangle_min_angle_min_deg) << ", mean "
        << format("%.2f", e.triangle_min_angle_mean_deg) << " degrees over " << e.triangles << " triangles\n";
    print_validity(out, run);
}

void run(const EvalOptions& o) {
    check_evaluation_request(o.request);  // bad flags first, then the file
    const PolygonMesh mesh = read_mesh(o.mesh);
    const EvaluationRun run = run_evaluation(mesh, o.mesh, o.request);
    if (o.json) std::cout << evaluation_report(run, o.mesh).dump(2) << '\n';
    else print_table(std::cout, o.mesh, run);
}

}  // namespace

CLI::Option* add_truth_shape_options(CLI::App& command, TruthShapeOptions& o) {
    CLI::Option* shape = command.add_option("--shape", o.shape,
                       "Ground truth: a named shape (sphere1 sphere9 ellipsoid cylinder torus rcube goursat goursat-hole "
                       "distel leopold diabolo heart crixxi), a polynomial in x, y, z (F <= 0 inside), or 'plane' "
                       "(the tilted half-space n.p <= d in [-B,B]^3)");
    command.add_option("--box", o.box, "Half-size B of the box of a polynomial shape (default 10, as for regularize) or "
                                       "of 'plane' (default 1)");
    command.add_option("--plane-normal", o.plane_normal, "Normal n of 'plane' (normalized)")
        ->expected(3)
        ->delimiter(',')
        ->capture_default_str();
    command.add_option("--plane-offset", o.plane_offset, "Signed distance d of 'plane' from the origin")->capture_default_str();
    return shape;
}

void add_evaluation_flags(CLI::App& command, EvaluationRequest& request) {
    add_truth_shape_options(command, request.truth);
    command.add_option("--volume", request.volume,
                       "Ground truth as voxels instead of --shape: a volume file (any format regularize reads); only "
                       "the voxel classification and the validity are measured, in the grid of the file as read");
    command.add_option("--min", request.min_value, "--volume: object = voxels with value >= MIN (default: value > 0)");
    command.add_option("--max", request.max_value, "--volume: object = voxels with value <= MAX");
    command.add_flag("--voxel-coordinates", request.voxel_coordinates,
                     "--shape: the mesh is in the voxel coordinates of the digitization at --h (a mesh made from the "
                     ".vol of 'dsreg digitize', spacing 1, origin 0): it is mapped to the shape's coordinates first");
    command.add_option("--face-errors", request.face_errors,
                       "--shape: write the normal error of every face to this CSV file (centroid x, y, z in the "
                       "shape's coordinates, angle in degrees; nan where not evaluated), for analyses by region");
    command.add_option("--h", request.h,
                       "Grid step: distances are also given in units of h, and the voxel classification uses "
                       "digitize(shape, h) (default: 1/64 of the shape's extent, as for regularize)");
    command.add_option("--wall-margin", request.wall_margin,
                       "Leave out vertices and faces closer than this to a clipped box face (physical units; "
                       "default 3h for shapes clipped by their box, else 0)");
    command.add_option("--volume-cells", request.volume_cells,
                       "Initial cells per axis of the quadrature of the shape's volume (features thinner than 1/N of "
                       "the box may be missed)")
        ->capture_default_str();
}

void add_eval_command(CLI::App& app) {
    auto options = std::make_shared<EvalOptions>();
    CLI::App* cmd = app.add_subcommand(
        "eval", "Measure a mesh (OBJ/OFF/PLY/STL/VTK/VTP, from dsreg or any tool) against an implicit shape (vertex distance, "
                "normal error, volume, voxel classification, triangle angles, validity) or the voxels of a volume file");
    cmd->add_option("mesh", options->mesh, "Mesh file: .obj .off .ply .stl .vtk .vtp (triangles and/or quads)")->required();
    add_evaluation_flags(*cmd, options->request);
    cmd->add_flag("--json", options->json, "Print one JSON object instead of the table");
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
