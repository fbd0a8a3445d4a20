#include "dsreg/output_paths.hpp"

#include <filesystem>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

void check_output_folder(const std::string& option, const std::string& path) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
        throw Error(option + " " + path + ": folder " + folder.string() + " does not exist");
}

void check_mesh_output_path(const std::string& option, const std::string& path) {
    const std::string ext = file_extension(path);
    if (ext != "obj" && ext != "off" && ext != "ply" && ext != "stl" && ext != "vtk" && ext != "vtp")
        throw Error(option + " " + path + ": unsupported mesh format '" + ext + "' (use .obj .off .ply .stl .vtk or .vtp)");
    check_output_folder(option, path);
}

void check_page_output_path(const std::string& option, const std::string& path) {
    const std::string ext = file_extension(path);
    if (ext != "html" && ext != "htm")
        throw Error(option + " " + path + ": the page must be an .html file (got '" + ext + "')");
    check_output_folder(option, path);
}

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
    // weakly_canonical resolves ".", "..", symbolic links and the current folder, so that
    // "out/a.obj" and "./out/../out/a.obj" compare equal even before the files exist.
    std::vector<std::pair<std::string, std::filesystem::path>> seen;
    for (const auto& [option, path] : outputs) {
        if (path.empty()) continue;
        std::error_code error;
        std::filesystem::path resolved = std::filesystem::weakly_canonical(std::filesystem::absolute(path), error);
        if (error) resolved = std::filesystem::absolute(path).lexically_normal();
        for (const auto& [other_option, other] : seen)
            if (other == resolved)
                throw Error(option + " " + path + ": same file as " + other_option +
                            " (each output needs its own path)");
        seen.emplace_back(option, resolved);
    }
}

}  // namespace dsreg
