// dsreg — voxel-to-world placements of grids (include/dsreg/grid_placement.hpp).
#include "dsreg/grid_placement.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/text.hpp"

namespace dsreg {

GridPlacement placement_from_affine(const Eigen::Matrix4d& affine) {
    if (!affine.allFinite()) throw Error("affine: every entry must be finite");
    if (affine.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw Error("affine: the last row must be 0 0 0 1 (a voxel-to-world affine)");
    GridPlacement placement;
    placement.origin = affine.block<3, 1>(0, 3);
    for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d column = affine.block<3, 1>(0, axis);
        placement.spacing[axis] = column.norm();
        if (!(placement.spacing[axis] > 0))
            throw Error("affine: column " + std::to_string(axis) + " is zero (a voxel of zero size)");
        placement.direction.col(axis) = column / placement.spacing[axis];
    }
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            const double cosine = placement.direction.col(a).dot(placement.direction.col(b));
            if (std::abs(cosine) > kMaxAxisCosine)
                throw Error("affine: the voxel axes " + std::to_string(a) + " and " + std::to_string(b) + " are at " +
                            format("%.4g", std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI) +
                            " degrees, not perpendicular (sheared grids are not supported)");
        }
    return placement;
}

Eigen::Matrix4d placement_affine(const GridPlacement& p) {
    Eigen::Matrix4d affine = Eigen::Matrix4d::Identity();
    affine.block<3, 3>(0, 0) = p.direction * p.spacing.asDiagonal();
    affine.block<3, 1>(0, 3) = p.origin;
    return affine;
}

bool is_axis_aligned(const Eigen::Matrix3d& direction) { return direction == Eigen::Matrix3d::Identity(); }

PolygonMesh move_to_world(PolygonMesh mesh, const Eigen::Matrix3d& direction, const Eigen::Vector3d& origin) {
    if (is_axis_aligned(direction)) return mesh;
    const Eigen::RowVector3d o = origin.transpose();
    mesh.vertices = ((mesh.vertices.rowwise() - o) * direction.transpose()).rowwise() + o;
    if (mesh.face_normals.rows() > 0) {
        // Normals map by the inverse transpose (the transpose of a row vector times the inverse).
        mesh.face_normals = mesh.face_normals * direction.inverse();
        mesh.face_normals.rowwise().normalize();
    }
    if (direction.determinant() < 0) mesh.faces = mesh.faces.rowwise().reverse().eval();
    return mesh;
}

}  // namespace dsreg
