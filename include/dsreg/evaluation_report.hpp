// dsreg — the `dsreg eval` job in one call: the ground truth (an implicit shape, or the voxels of
// a volume file), the defaults of the flags, evaluate_mesh or classify_voxel_centres
// (evaluation.hpp), the mesh's validity (mesh_validity.hpp), the per-face CSV and the JSON report. The command line and the Python module's
// dsreg.evaluate are thin shells over it, so that they report the same numbers in the same words.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/evaluation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/mesh_validity.hpp"

namespace dsreg {

/// The ground-truth shape of `eval` and `convergence`: a named shape, a polynomial, or "plane"
/// (the tilted half-space n·p ≤ d clipped by the box [-B, B]³, make_plane_shape).
struct TruthShapeOptions {
    std::string shape;          ///< --shape
    std::optional<double> box;  ///< --box; polynomial: default 10 (as `regularize --box`); plane: default 1
    std::vector<double> plane_normal{1.0, 1.4142135623730951, 1.7320508075688772};  ///< --plane-normal (1, √2, √3)
    double plane_offset = 0.01;                                                     ///< --plane-offset
};

/// Builds the shape. Throws dsreg::Error for an unknown shape or bad plane parameters.
ImplicitShape make_truth_shape(const TruthShapeOptions& options);

/// What `dsreg eval` is asked, flag by flag.
struct EvaluationRequest {
    TruthShapeOptions truth;  ///< truth.shape empty: the truth is `volume`
    /// --volume: the truth as the voxels of this file instead of a shape (only the voxel
    /// classification is measured, in the grid read_volume gives); excludes --shape, --h,
    /// --wall-margin, --voxel-coordinates, --face-errors.
    std::string volume;
    std::optional<double> min_value, max_value;  ///< --min, --max: the object voxels of `volume` (default value > 0)
    /// --voxel-coordinates: the mesh is in the voxel frame of digitize(shape, h) (spacing 1,
    /// origin 0: a mesh made from the .vol of `dsreg digitize`); mapped to the shape's frame first.
    bool voxel_coordinates = false;
    std::string face_errors;  ///< --face-errors: CSV path of every face's centroid and normal error
    std::optional<double> h;            ///< --h: default 1/64 of the shape's extent (default_grid_step)
    std::optional<double> wall_margin;  ///< --wall-margin: default 3h for shapes clipped by their box, else 0
    int volume_cells = 64;              ///< --volume-cells
};

/// Checks the values of the request (naming the flags) and builds its shape (none for --volume):
/// what can fail before the mesh is read. Throws dsreg::Error.
std::optional<ImplicitShape> check_evaluation_request(const EvaluationRequest& request);

struct EvaluationRun {
    std::string volume;      ///< the --volume file (then only evaluation.voxels is filled, shape is unused)
    ImplicitShape shape;
    double h = 0;            ///< grid step used
    bool h_given = false;    ///< --h was given: distances are also reported in units of h
    double wall_margin = 0;  ///< used
    MeshEvaluation evaluation;
    MeshValidity validity;        ///< self-intersections, degenerate triangles, faces folded against the mesh's face_normals
    bool has_face_field = false;  ///< the mesh carried face_normals (a PLY written by dsreg: the field u)
};

/// Checks the request (naming the flags), builds the shape (or reads the volume), fills the
/// defaults, evaluates `mesh` and checks its validity; writes the --face-errors CSV (atomically)
/// when asked. Errors of the evaluation itself are prefixed with `mesh_name` ("g.obj: ...").
/// Throws dsreg::Error.
EvaluationRun run_evaluation(const PolygonMesh& mesh, const std::string& mesh_name, const EvaluationRequest& request);

/// The `dsreg eval --json` object: mesh (`mesh_name`, null if empty), shape, h, counts, vertex
/// distance (also in units of h when h was given), normal angle, volumes, voxel classification
/// (all, object and boundary voxels), triangle angles, validity (folded_faces null without a
/// field). For --volume: mesh, volume, voxel classification and validity only.
nlohmann::json evaluation_report(const EvaluationRun& run, const std::string& mesh_name);

}  // namespace dsreg
