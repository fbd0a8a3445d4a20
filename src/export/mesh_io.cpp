// dsreg — mesh files: choice of the format, checks before writing, quad triangulation.
// The formats themselves live in obj_format.cpp, off_format.cpp, ply_format.cpp, stl_format.cpp.
#include "dsreg/mesh_io.hpp"

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg {

namespace {

enum class MeshFormat { Obj, Off, Ply, Stl, Vtk, Vtp };

MeshFormat format_of(const std::string& path) {
    const std::string extension = file_extension(path);
    if (extension == "obj") return MeshFormat::Obj;
    if (extension == "off") return MeshFormat::Off;
    if (extension == "ply") return MeshFormat::Ply;
    if (extension == "stl") return MeshFormat::Stl;
    if (extension == "vtk") return MeshFormat::Vtk;
    if (extension == "vtp") return MeshFormat::Vtp;
    const std::string problem =
        extension.empty() ? "has no file extension" : "has unknown extension '." + extension + "'";
    throw Error(path + ": " + problem + "; supported mesh formats are .obj, .off, .ply, .stl, .vtk and .vtp");
}

std::string read_file_content(const std::string& path) {
    std::error_code error;
    const auto status = std::filesystem::status(path, error);
    if (!std::filesystem::exists(status)) throw FileError(path + ": no such file", ENOENT);
    if (std::filesystem::is_directory(status)) throw FileError(path + ": is a directory, not a mesh file", EISDIR);
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path + ": cannot open file for reading", errno);
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size < 0 || !in) throw FileError(path + ": cannot determine the size of the file", EIO);
    std::string content(static_cast<std::size_t>(size), '\0');
    in.read(content.data(), size);
    if (in.gcount() != size) throw FileError(path + ": read failed", EIO);
    return content;
}

/// The '#' comment lines at the start of a text file (after its first line if `skip_first`), as
/// vtkOBJReader collects them.
std::string leading_comments(std::string_view content, bool skip_first) {
    std::string comments;
    std::size_t position = 0;
    bool first = true;
    while (position < content.size()) {
        const std::size_t end = std::min(content.find('\n', position), content.size());
        std::string_view line = content.substr(position, end - position);
        position = end + 1;
        if (first && skip_first) {
            first = false;
            continue;
        }
        first = false;
        while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
        if (line.empty() || line == "\r") continue;
        if (line.front() != '#') break;
        comments.append(line.substr(1)).push_back('\n');
    }
    return comments;
}

/// The text where 3D Slicer looks for "SPACE=..." in each format (vtk and vtp readers do it themselves).
std::string coordinate_header(MeshFormat format, std::string_view content) {
    switch (format) {
    case MeshFormat::Obj: return leading_comments(content, false);
    case MeshFormat::Off: return leading_comments(content, true);
    case MeshFormat::Ply: {
        const std::size_t end = content.find("end_header");
        std::string comments;
        std::size_t position = 0;
        while (position < std::min(end, content.size())) {
            const std::size_t line_end = std::min(content.find('\n', position), content.size());
            const std::string_view line = content.substr(position, line_end - position);
            if (line.rfind("comment", 0) == 0) comments.append(line).push_back('\n');
            position = line_end + 1;
        }
        return comments;
    }
    case MeshFormat::Stl: {
        const bool ascii = content.rfind("solid", 0) == 0;
        return std::string(ascii ? content.substr(0, std::min(content.find('\n'), content.size())) : content.substr(0, 80));
    }
    case MeshFormat::Vtk:
    case MeshFormat::Vtp: return "";
    }
    return "";
}

}  // namespace

PolygonMesh triangulate_shorter_diagonal(const PolygonMesh& mesh) {
    mesh_format::check_faces("triangulate_shorter_diagonal", mesh);
    if (mesh.faces.cols() == 3) return mesh;

    PolygonMesh result;
    result.vertices = mesh.vertices;
    result.vertex_scalars = mesh.vertex_scalars;
    const Eigen::Index quad_count = mesh.faces.rows();
    const bool with_normals = mesh.face_normals.rows() > 0;
    result.faces.resize(2 * quad_count, 3);
    if (with_normals) result.face_normals.resize(2 * quad_count, 3);
    for (const auto& [name, values] : mesh.face_integers) result.face_integers.emplace_back(name, Eigen::VectorXi(2 * quad_count));
    for (Eigen::Index q = 0; q < quad_count; ++q) {
        const auto triangles = mesh_format::split_quad(mesh.vertices, mesh.faces.row(q).data());
        for (int t = 0; t < 2; ++t) {
            result.faces.row(2 * q + t) << triangles[t][0], triangles[t][1], triangles[t][2];
            if (with_normals) result.face_normals.row(2 * q + t) = mesh.face_normals.row(q);
            for (std::size_t i = 0; i < mesh.face_integers.size(); ++i)
                result.face_integers[i].second[2 * q + t] = mesh.face_integers[i].second[q];
        }
    }
    return result;
}

void check_mesh(const std::string& context, const PolygonMesh& mesh) {
    mesh_format::check_mesh_for_writing(context, mesh);
}

void write_mesh(const std::string& path, const PolygonMesh& mesh) {
    const MeshFormat format = format_of(path);
    mesh_format::check_mesh_for_writing(path, mesh);
    switch (format) {
        case MeshFormat::Obj:
            return mesh_format::write_obj(path, mesh);
        case MeshFormat::Off:
            return mesh_format::write_off(path, mesh);
        case MeshFormat::Ply:
            return mesh_format::write_ply(path, mesh);
        case MeshFormat::Stl:
            return mesh_format::write_stl(path, mesh);
        case MeshFormat::Vtk:
            return mesh_format::write_vtk(path, mesh);
        case MeshFormat::Vtp:
            return mesh_format::write_vtp(path, mesh);
    }
}

namespace {

PolygonMesh parse_mesh(MeshFormat format, const std::string& path, std::string_view content) {
    switch (format) {
        case MeshFormat::Obj:
            return mesh_format::read_obj(path, content);
        case MeshFormat::Off:
            return mesh_format::read_off(path, content);
        case MeshFormat::Ply:
            return mesh_format::read_ply(path, content);
        case MeshFormat::Stl:
            return mesh_format::read_stl(path, content);
        case MeshFormat::Vtk:
            return mesh_format::read_vtk(path, content);
        case MeshFormat::Vtp:
            return mesh_format::read_vtp(path, content);
    }
    throw Error(path + ": unsupported mesh format");  // not reached
}

}  // namespace

PolygonMesh read_mesh(const std::string& path) {
    const MeshFormat format = format_of(path);
    const std::string content = read_file_content(path);
    PolygonMesh mesh = parse_mesh(format, path, content);
    if (mesh.coordinate_system.empty()) mesh.coordinate_system = mesh_format::coordinate_system_in(coordinate_header(format, content));
    return mesh;
}

}  // namespace dsreg
