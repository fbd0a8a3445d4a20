// dsreg — voxel-to-world affines of grids (include/dsreg/grid_placement.hpp).
#include "dsreg/grid_placement.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "dsreg/error.hpp"
#include "dsreg/text.hpp"

namespace dsreg {

double orthonormality_error(const Eigen::Matrix3d& direction) {
    return (direction.transpose() * direction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

Eigen::Matrix3d nearest_orthonormal(const Eigen::Matrix3d& direction) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(direction, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU() * svd.matrixV().transpose();
}

double max_shear_degrees(const Eigen::Matrix3d& direction) {
    double worst = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            const double cosine = direction.col(a).normalized().dot(direction.col(b).normalized());
            worst = std::max(worst, std::abs(90.0 - std::acos(std::max(-1.0, std::min(1.0, cosine))) * 180.0 / M_PI));
        }
    return worst;
}

std::string direction_problem(const Eigen::Matrix3d& direction) {
    if (orthonormality_error(direction) <= kOrthonormalTolerance) return "";
    return "the direction cosines are not orthonormal (axes up to " + format("%g", max_shear_degrees(direction)) +
           " degrees from perpendicular, or not of unit length): a sheared or skewed voxel grid, e.g. a CT with gantry "
           "tilt; resample it onto a rectangular grid first";
}

namespace {

const Eigen::Matrix3d& lps_to_ras() {  // its own inverse
    static const Eigen::Matrix3d flip = Eigen::Vector3d(-1, -1, 1).asDiagonal();
    return flip;
}

}  // namespace

VoxelGrid grid_from_affine(const Index3& dims, const Eigen::Matrix4d& affine, OutputSpace world) {
    if (world == OutputSpace::Voxel) throw Error("affine: a voxel-to-world matrix maps to lps or ras, not to voxel");
    if (!affine.allFinite()) throw Error("affine: every entry must be finite");
    if (affine.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw Error("affine: the last row must be 0 0 0 1 (a voxel-to-world affine)");
    Eigen::Matrix3d linear = affine.block<3, 3>(0, 0);
    Eigen::Vector3d origin = affine.block<3, 1>(0, 3);
    if (world == OutputSpace::Ras) linear = lps_to_ras() * linear, origin = lps_to_ras() * origin;
    VoxelGrid grid;
    grid.dims = dims;
    grid.origin = origin;
    for (int axis = 0; axis < 3; ++axis) {
        grid.spacing[axis] = linear.col(axis).norm();
        if (!(grid.spacing[axis] > 0))
            throw Error("affine: column " + std::to_string(axis) + " is zero (a voxel of zero size)");
        grid.direction.col(axis) = linear.col(axis) / grid.spacing[axis];
    }
    const std::string problem = direction_problem(grid.direction);
    if (!problem.empty()) throw Error("affine: " + problem);
    grid.direction = nearest_orthonormal(grid.direction);
    return grid;
}

Eigen::Matrix4d homogeneous_matrix(const AffineMap& map) {
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();
    matrix.block<3, 3>(0, 0) = map.linear;
    matrix.block<3, 1>(0, 3) = map.offset;
    return matrix;
}

Eigen::Matrix4d grid_affine(const VoxelGrid& grid, OutputSpace space) {
    // index → grid frame (origin + spacing ⊙ index) → space
    const AffineMap to_space = grid_to_space(grid, space);
    AffineMap from_index;
    from_index.linear = to_space.linear * grid.spacing.asDiagonal();
    from_index.offset = to_space.apply(grid.origin);
    return homogeneous_matrix(from_index);
}

}  // namespace dsreg
