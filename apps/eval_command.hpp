// dsreg CLI — `dsreg eval`: accuracy of any mesh file against an implicit shape.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/implicit_shape.hpp"

namespace dsreg::cli {

/// The ground-truth shape of `eval` and `convergence`: a named shape, a polynomial, or "plane"
/// (the tilted half-space n·p ≤ d clipped by the box [-B, B]³, make_plane_shape).
struct TruthShapeOptions {
    std::string shape;
    std::optional<double> box;  ///< polynomial: default 10 (as `regularize --box`); plane: default 1
    std::vector<double> plane_normal{1.0, 1.4142135623730951, 1.7320508075688772};  ///< (1, √2, √3)
    double plane_offset = 0.01;
};

/// Registers --shape, --box, --plane-normal, --plane-offset on `command`; returns --shape (for
/// commands that require it).
CLI::Option* add_truth_shape_options(CLI::App& command, TruthShapeOptions& options);

/// Builds the shape. Throws dsreg::Error for an unknown shape or bad plane parameters.
ImplicitShape make_truth_shape(const TruthShapeOptions& options);

/// Registers the `eval` subcommand (truth: --shape, or --volume for a volume file) on `app`.
void add_eval_command(CLI::App& app);

}  // namespace dsreg::cli
