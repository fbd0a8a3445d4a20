#include "output_paths.hpp"

#include <filesystem>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"

namespace dsreg::cli {

void check_output_folder(const std::string& option, const std::string& path) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
        throw Error(option + " " + path + ": folder " + folder.string() + " does not exist");
}

void check_mesh_output_path(const std::string& option, const std::string& path) {
    const std::string ext = file_extension(path);
    if (ext != "obj" && ext != "off" && ext != "ply" && ext != "stl")
        throw Error(option + " " + path + ": unsupported mesh format '" + ext + "' (use .obj .off .ply or .stl)");
    check_output_folder(option, path);
}

}  // namespace dsreg::cli
