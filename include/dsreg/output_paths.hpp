// dsreg — checks on output paths, made before any long computation (folders exist, formats are
// known, no two outputs on one file).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace dsreg {

/// Throws dsreg::Error naming `option` if `path` has no supported mesh extension or its folder
/// does not exist.
void check_mesh_output_path(const std::string& option, const std::string& path);

/// Throws dsreg::Error naming `option` if `path` does not end in .html or .htm or its folder
/// does not exist.
void check_page_output_path(const std::string& option, const std::string& path);

/// Throws dsreg::Error naming `option` if the folder of `path` does not exist.
void check_output_folder(const std::string& option, const std::string& path);

/// Throws dsreg::Error naming both options if two of the (option, path) outputs given (empty
/// paths are skipped) are the same file, which one would silently overwrite with the other.
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs);

}  // namespace dsreg
