// dsreg — the last step before writing: the mesh from the grid frame to the output space.
#include "dsreg/world_space.hpp"

#include <algorithm>
#include <cctype>

#include "dsreg/error.hpp"

namespace dsreg {

OutputSpace parse_output_space(const std::string& name) {
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "lps") return OutputSpace::Lps;
    if (lower == "ras") return OutputSpace::Ras;
    if (lower == "voxel") return OutputSpace::Voxel;
    throw Error("unknown output space '" + name + "' (expected lps, ras or voxel)");
}

std::string output_space_name(OutputSpace space) {
    switch (space) {
    case OutputSpace::Lps: return "lps";
    case OutputSpace::Ras: return "ras";
    case OutputSpace::Voxel: return "voxel";
    }
    return "";
}

std::string slicer_coordinate_system(OutputSpace space) {
    switch (space) {
    case OutputSpace::Lps: return "LPS";
    case OutputSpace::Ras: return "RAS";
    case OutputSpace::Voxel: return "";
    }
    return "";
}

AffineMap grid_to_space(const VoxelGrid& grid, OutputSpace space) {
    AffineMap map;
    switch (space) {
    case OutputSpace::Lps:
    case OutputSpace::Ras: {
        // world = origin + D (p − origin)
        map.linear = grid.direction;
        map.offset = grid.origin - grid.direction * grid.origin;
        if (space == OutputSpace::Ras) {
            const Eigen::Matrix3d lps_to_ras = Eigen::Vector3d(-1, -1, 1).asDiagonal();
            map.linear = lps_to_ras * map.linear;
            map.offset = lps_to_ras * map.offset;
        }
        break;
    }
    case OutputSpace::Voxel: {
        // index = (p − origin) ⊘ spacing
        const Eigen::Vector3d inverse_spacing = grid.spacing.cwiseInverse();
        map.linear = inverse_spacing.asDiagonal();
        map.offset = -grid.origin.cwiseProduct(inverse_spacing);
        break;
    }
    }
    return map;
}

PointMatrix map_points(const AffineMap& map, const PointMatrix& points) {
    PointMatrix mapped(points.rows(), 3);
    for (Eigen::Index i = 0; i < points.rows(); ++i) mapped.row(i) = map.apply(points.row(i).transpose()).transpose();
    return mapped;
}

PointMatrix map_normals(const AffineMap& map, const PointMatrix& normals) {
    const Eigen::Matrix3d normal_map = map.linear.inverse().transpose();
    PointMatrix mapped(normals.rows(), 3);
    for (Eigen::Index i = 0; i < normals.rows(); ++i) {
        const Eigen::Vector3d n = normal_map * normals.row(i).transpose();
        const double length = n.norm();
        mapped.row(i) = (length > 0 ? Eigen::Vector3d(n / length) : n).transpose();
    }
    return mapped;
}

PolygonMesh mesh_in_space(PolygonMesh mesh, const VoxelGrid& grid, OutputSpace space) {
    const AffineMap map = grid_to_space(grid, space);
    mesh.vertices = map_points(map, mesh.vertices);
    if (mesh.face_normals.rows() > 0) mesh.face_normals = map_normals(map, mesh.face_normals);
    if (map.reverses_orientation())
        for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)  // (a,b,c,d) → (a,d,c,b): same first corner
            std::reverse(mesh.faces.row(f).data() + 1, mesh.faces.row(f).data() + mesh.faces.cols());
    mesh.coordinate_system = slicer_coordinate_system(space);
    return mesh;
}

}  // namespace dsreg
