// dsreg — the `dsreg eval` job in one call: the ground-truth shape, the defaults of the flags,
// evaluate_mesh (evaluation.hpp) and the JSON report. The command line and the Python module's
// dsreg.evaluate are thin shells over it, so that they report the same numbers in the same words.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/evaluation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh.hpp"

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
    TruthShapeOptions truth;
    std::optional<double> h;            ///< --h: default 1/64 of the shape's extent (default_grid_step)
    std::optional<double> wall_margin;  ///< --wall-margin: default 3h for shapes clipped by their box, else 0
    int volume_cells = 64;              ///< --volume-cells
};

/// Checks the values of the request (naming the flags) and builds its shape: what can fail before
/// the mesh is read. Throws dsreg::Error.
ImplicitShape check_evaluation_request(const EvaluationRequest& request);

struct EvaluationRun {
    ImplicitShape shape;
    double h = 0;            ///< grid step used
    bool h_given = false;    ///< --h was given: distances are also reported in units of h
    double wall_margin = 0;  ///< used
    MeshEvaluation evaluation;
};

/// Checks the request (naming the flags), builds the shape, fills the defaults and evaluates
/// `mesh`. Errors of the evaluation itself are prefixed with `mesh_name` ("g.obj: ...").
/// Throws dsreg::Error.
EvaluationRun run_evaluation(const PolygonMesh& mesh, const std::string& mesh_name, const EvaluationRequest& request);

/// The `dsreg eval --json` object: mesh (`mesh_name`, null if empty), shape, h, counts, vertex
/// distance (also in units of h when h was given), normal angle, volumes, voxel classification,
/// triangle angles.
nlohmann::json evaluation_report(const EvaluationRun& run, const std::string& mesh_name);

}  // namespace dsreg
