// dsreg — where a voxel grid lies in the world: a voxel-to-world affine (nibabel's img.affine,
// ITK's origin + direction · spacing) split into what the pipeline works with.
//
// The pipeline works in the grid frame of volume.hpp: voxel (i,j,k) centred at
// origin + spacing ⊙ (i,j,k), axes along x, y, z. A placement adds the directions of the grid's
// axes in the world, `direction` (its columns, unit vectors; the direction cosines of ITK and
// DICOM). Voxel (i,j,k) is then centred at
//     origin + direction · (spacing ⊙ (i,j,k))  =  affine · (i, j, k, 1),
// and a point p of the grid frame is at origin + direction · (p − origin) in the world. Lengths
// and angles are the same in both frames when the axes are perpendicular, so the pipeline runs in
// the grid frame and only its output is moved into the world.
#pragma once

#include <Eigen/Core>

#include "dsreg/mesh.hpp"

namespace dsreg {

struct GridPlacement {
    Eigen::Vector3d spacing{1.0, 1.0, 1.0};  ///< voxel size along the grid's axes, physical units
    Eigen::Vector3d origin{0.0, 0.0, 0.0};   ///< world position of the centre of voxel (0,0,0)
    Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();  ///< unit axis directions, as columns
};

/// Largest |cosine| between two axis directions accepted as perpendicular: 1e-3 (0.057°). Affines
/// stored in single precision (NIfTI's sform) are perpendicular to about 1e-7; sheared grids are
/// refused, since the normal estimation and the regularization assume perpendicular axes.
constexpr double kMaxAxisCosine = 1e-3;

/// Splits a 4×4 voxel-to-world affine: spacing = lengths of the first three columns, direction =
/// those columns normalized, origin = the fourth column. Throws dsreg::Error naming "affine"
/// unless every entry is finite, the last row is (0, 0, 0, 1), no column is zero and the axes are
/// perpendicular (kMaxAxisCosine). A negative determinant (a mirrored grid, as in radiological
/// NIfTI files) is allowed.
GridPlacement placement_from_affine(const Eigen::Matrix4d& affine);

/// The voxel-to-world affine [direction · diag(spacing) | origin; 0 0 0 1].
Eigen::Matrix4d placement_affine(const GridPlacement& placement);

/// True when the grid frame is the world (direction = identity): nothing to move.
bool is_axis_aligned(const Eigen::Matrix3d& direction);

/// A mesh of the grid frame (around `origin`) moved into the world: vertices to
/// origin + direction · (p − origin), face normals by the inverse transpose of `direction`
/// (renormalized), and, when the direction mirrors (determinant < 0), every face's vertex order
/// reversed so that faces stay counter-clockwise seen from outside. Vertex scalars are kept.
/// An axis-aligned direction returns the mesh unchanged.
PolygonMesh move_to_world(PolygonMesh mesh, const Eigen::Matrix3d& direction, const Eigen::Vector3d& origin);

}  // namespace dsreg
