// dsreg CLI — checks on output paths, made before any long computation.
#pragma once

#include <string>

namespace dsreg::cli {

/// Throws dsreg::Error naming `option` if `path` has no supported mesh extension or its folder
/// does not exist.
void check_mesh_output_path(const std::string& option, const std::string& path);

/// Throws dsreg::Error naming `option` if the folder of `path` does not exist.
void check_output_folder(const std::string& option, const std::string& path);

}  // namespace dsreg::cli
