// dsreg CLI — `dsreg regularize`: the whole pipeline, volume → mesh file.
#pragma once

#include <CLI/CLI.hpp>

namespace dsreg::cli {

/// Registers the `regularize` subcommand on `app`; running it executes the pipeline.
void add_regularize_command(CLI::App& app);

}  // namespace dsreg::cli
