// dsreg CLI — `dsreg view`: one self-contained HTML page showing meshes in 3D.
#pragma once

#include <CLI/CLI.hpp>

namespace dsreg::cli {

/// Registers the `view` subcommand on `app`.
void add_view_command(CLI::App& app);

}  // namespace dsreg::cli
