// dsreg CLI — `dsreg convergence`: the multigrid convergence experiment of the paper's Fig. 7
// (CSV, SVG plot, fitted slopes).
#pragma once

#include <CLI/CLI.hpp>

namespace dsreg::cli {

/// Registers the `convergence` subcommand on `app`.
void add_convergence_command(CLI::App& app);

}  // namespace dsreg::cli
