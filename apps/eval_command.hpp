// dsreg CLI — `dsreg eval`: accuracy of any mesh file against an implicit shape.
#pragma once

#include <CLI/CLI.hpp>

#include "dsreg/evaluation_report.hpp"

namespace dsreg::cli {

/// Registers --shape, --box, --plane-normal, --plane-offset on `command`; returns --shape (for
/// the commands that require it: eval takes --volume instead).
CLI::Option* add_truth_shape_options(CLI::App& command, TruthShapeOptions& options);

/// Registers the flags of the evaluation on `command`: the truth shape's, --volume, --min, --max,
/// --voxel-coordinates, --face-errors, --h, --wall-margin, --volume-cells (not the mesh file, not
/// --json). The one definition of these flags: `dsreg eval` and the Python module's
/// dsreg.evaluate keywords both parse them.
void add_evaluation_flags(CLI::App& command, EvaluationRequest& request);

/// Registers the `eval` subcommand on `app`.
void add_eval_command(CLI::App& app);

}  // namespace dsreg::cli
