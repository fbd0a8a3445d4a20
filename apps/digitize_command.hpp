// dsreg CLI — `dsreg digitize`: an implicit shape's Gauss digitization written as a volume file,
// so that other tools (bench/slicer_pipeline.py) can read the very voxels dsreg regularizes.
#pragma once

#include <CLI/CLI.hpp>

namespace dsreg::cli {

/// Registers the `digitize` subcommand on `app`.
void add_digitize_command(CLI::App& app);

}  // namespace dsreg::cli
