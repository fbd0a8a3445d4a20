#include "eval_command.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "dsreg/text.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/mesh_validity.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg::cli {

namespace {

struct EvalOptions {
    std::string mesh;
    TruthShapeOptions truth;
    std::string volume;  ///< --volume: classify the voxel centres of this file instead
    bool voxel_coordinates = false;  ///< --voxel-coordinates: the mesh is in the digitization's voxel frame
    std::string face_errors;         ///< --face-errors: CSV of the normal error of every face
    std::optional<double> min_value, max_value;
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

void print_classification(std::ostream& out, const VoxelClassification& c, const std::string& source) {
    out << "  voxel centres correct   " << c.correct << " / " << c.total << " = " << format("%.4f", 100.0 * c.share())
        << " %  (" << source << ")\n";
    out << "    object voxels         " << c.object_correct << " / " << c.object_total << " = "
        << format("%.4f", 100.0 * c.object_share()) << " %\n";
    out << "    next to the surface   " << c.boundary_correct << " / " << c.boundary_total << " = "
        << format("%.4f", 100.0 * c.boundary_share()) << " %\n";
}

/// Self-intersections and degenerate triangles of the mesh (mesh_validity.hpp) and, when it
/// carries one vector per face (a PLY written by dsreg: the field u), the faces folded against it.
MeshValidity mesh_validity(const PolygonMesh& mesh) {
    return check_mesh_validity(mesh.vertices, mesh.faces, mesh.face_normals);
}

nlohmann::json validity_json(const MeshValidity& v, const PolygonMesh& mesh) {
    return {{"intersecting_pairs", v.intersecting_pairs},
            {"degenerate_triangles", v.degenerate_triangles},
            {"folded_faces", mesh.face_normals.rows() > 0 ? nlohmann::json(v.folded_faces) : nlohmann::json(nullptr)},
            {"triangles", v.triangles}};
}

void print_validity(std::ostream& out, const MeshValidity& v, const PolygonMesh& mesh) {
    out << "  self-intersections      " << v.intersecting_pairs << " pairs of triangles, " << v.degenerate_triangles
        << " degenerate triangles";
    if (mesh.face_normals.rows() > 0) out << ", " << v.folded_faces << " faces folded against the mesh's field";
    out << "\n";
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
    j["voxel_classification"] = classification_json(e.voxels);
    j["voxel_classification"]["h"] = h;
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
    print_classification(out, e.voxels, "digitization at h = " + format("%g", h));
    out << "  triangle min angle      min " << format("%.2f", e.triangle_min_angle_min_deg) << ", mean "
        << format("%.2f", e.triangle_min_angle_mean_deg) << " degrees over " << e.triangles << " triangles\n";
}

/// --volume: the mesh against the voxels of a file (its own coordinates: spacing 1, origin 0).
void run_against_volume(const EvalOptions& o) {
    if (o.h || o.wall_margin || !o.truth.shape.empty() || o.voxel_coordinates)
        throw Error("--volume gives the truth as voxels: --shape, --h, --wall-margin and --voxel-coordinates do not apply");
    ValueRange range;
    if (o.min_value) range.has_min = true, range.min = *o.min_value;
    if (o.max_value) range.has_max = true, range.max = *o.max_value;
    const BinaryVolume volume = read_volume(o.volume, range);
    const PolygonMesh mesh = read_mesh(o.mesh);
    VoxelClassification c;
    MeshValidity validity;
    try {
        c = classify_voxel_centres(mesh, volume);
        validity = mesh_validity(mesh);
    } catch (const Error& e) {
        throw Error(o.mesh + ": " + e.what());
    }
    if (o.json) {
        nlohmann::json j = {{"mesh", o.mesh},
                            {"volume", o.volume},
                            {"voxel_classification", classification_json(c)},
                            {"validity", validity_json(validity, mesh)}};
        std::cout << j.dump(2) << '\n';
        return;
    }
    std::cout << "dsreg eval " << o.mesh << " against the voxels of " << o.volume << "\n\n";
    print_classification(std::cout, c, o.volume);
    print_validity(std::cout, validity, mesh);
}

/// --face-errors: one line per face, its centroid (the shape's coordinates) and normal error.
void write_face_errors(const std::string& path, const PolygonMesh& mesh, const MeshEvaluation& e) {
    const PointMatrix centroids = face_centroids(mesh.vertices, mesh.faces);
    write_file_atomically(path, [&](std::ostream& out) {
        out << "x,y,z,normal_angle_deg\n";
        for (Eigen::Index f = 0; f < centroids.rows(); ++f)
            out << format("%.9g", centroids(f, 0)) << ',' << format("%.9g", centroids(f, 1)) << ','
                << format("%.9g", centroids(f, 2)) << ',' << format("%.9g", e.face_angle_deg[std::size_t(f)]) << '\n';
    });
}

/// The mesh read from --mesh, in the shape's coordinates (mapped from the voxel frame of
/// digitize(shape, h) with --voxel-coordinates).
PolygonMesh mesh_in_shape_frame(const EvalOptions& o, const ImplicitShape& shape, double h) {
    PolygonMesh mesh = read_mesh(o.mesh);
    if (!o.voxel_coordinates) return mesh;
    const VoxelGrid grid = digitize(shape, h).grid;
    for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
        mesh.vertices.row(i) = grid.voxel_center(0, 0, 0).transpose() + mesh.vertices.row(i).cwiseProduct(grid.spacing.transpose());
    return mesh;
}

void run(const EvalOptions& o) {
    if (!o.volume.empty()) return run_against_volume(o);
    if (o.truth.shape.empty()) throw Error("eval needs the truth: --shape (an implicit shape) or --volume (a volume file)");
    if (o.min_value || o.max_value) throw Error("--min and --max only apply to --volume");
    check_positive("--h", o.h);
    check_positive("--wall-margin", o.wall_margin, true);
    if (o.volume_cells < 8) throw Error("--volume-cells must be at least 8");
    const ImplicitShape shape = make_truth_shape(o.truth);
    const double h = o.h ? *o.h : default_grid_step(shape);
    const PolygonMesh mesh = mesh_in_shape_frame(o, shape, h);
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
    const MeshValidity validity = mesh_validity(mesh);
    if (!o.face_errors.empty()) write_face_errors(o.face_errors, mesh, evaluation);
    if (o.json) {
        nlohmann::json j = report_json(o, shape, h, wall_margin, evaluation);
        j["validity"] = validity_json(validity, mesh);
        std::cout << j.dump(2) << '\n';
        return;
    }
    print_table(std::cout, o, shape, h, wall_margin, evaluation);
    print_validity(std::cout, validity, mesh);
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
    cmd->add_option("--volume", options->volume,
                    "Ground truth as voxels instead of --shape: a volume file (.vol .longvol .pgm3d); only the voxel "
                    "classification is measured, in the file's coordinates (spacing 1, origin 0, as regularize)");
    cmd->add_flag("--voxel-coordinates", options->voxel_coordinates,
                  "--shape: the mesh is in the voxel coordinates of the digitization at --h (a mesh made from the .vol "
                  "of 'dsreg digitize', spacing 1, origin 0): it is mapped to the shape's coordinates first");
    cmd->add_option("--face-errors", options->face_errors,
                    "--shape: write the normal error of every face to this CSV file (centroid x, y, z in the shape's "
                    "coordinates, angle in degrees; nan where not evaluated), for analyses by region");
    cmd->add_option("--min", options->min_value, "--volume: object = voxels with value >= MIN (default: value > 0)");
    cmd->add_option("--max", options->max_value, "--volume: object = voxels with value <= MAX");
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
