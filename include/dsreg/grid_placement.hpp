// dsreg — where a voxel grid lies in the world, as a 4×4 voxel-to-world affine (nibabel's
// img.affine, ITK's origin + direction · diag(spacing)), to and from VoxelGrid.
//
// A VoxelGrid (volume.hpp) holds the placement itself: spacing, origin and the direction cosines
// `direction` (orthonormal, LPS). Voxel (i,j,k) is centred in LPS at
//     origin + direction · (spacing ⊙ (i,j,k))  =  affine · (i, j, k, 1);
// the pipeline works in the grid frame (direction left out) and world_space.hpp maps its output
// to lps, ras or voxel coordinates. This header only converts between the affine a caller or a
// file gives and the grid, with the readers' rule for directions: orthonormal within
// kOrthonormalTolerance (then orthonormalized), otherwise rejected (sheared grids).
#pragma once

#include <Eigen/Core>
#include <string>

#include "dsreg/volume.hpp"
#include "dsreg/world_space.hpp"

namespace dsreg {

/// Largest |DᵀD − I| of a direction matrix accepted (and then orthonormalized). ITK itself takes
/// 1e-4 as orthonormal; float32 storage (NIfTI sforms) rounds at ~1e-7.
constexpr double kOrthonormalTolerance = 1e-3;

/// max |DᵀD − I| over the entries: 0 for an orthonormal matrix.
double orthonormality_error(const Eigen::Matrix3d& direction);

/// The orthonormal matrix nearest to `direction` (polar decomposition U·Vᵀ of its SVD U·Σ·Vᵀ);
/// keeps the sign of the determinant.
Eigen::Matrix3d nearest_orthonormal(const Eigen::Matrix3d& direction);

/// Largest angle (degrees) by which two columns of `direction` depart from perpendicular.
double max_shear_degrees(const Eigen::Matrix3d& direction);

/// "" when `direction` is within kOrthonormalTolerance of orthonormal, else the reason it is
/// refused (a sentence for a message starting with the file or argument name).
std::string direction_problem(const Eigen::Matrix3d& direction);

/// The grid of `dims` voxels placed by `affine`, a voxel-to-world matrix into `world` (lps, or
/// ras as nibabel's; ras is turned into LPS by diag(−1,−1,1)): spacing = lengths of the first
/// three columns, direction = those columns normalized (then orthonormalized), origin = the
/// fourth column. Throws dsreg::Error naming "affine" unless every entry is finite, the last row
/// is (0, 0, 0, 1), no column is zero and the axes are perpendicular (direction_problem), or if
/// `world` is voxel. A negative determinant (a mirrored grid, as in radiological NIfTI files) is
/// allowed.
VoxelGrid grid_from_affine(const Index3& dims, const Eigen::Matrix4d& affine, OutputSpace world = OutputSpace::Lps);

/// The voxel-to-`space` affine of `grid`: index (i,j,k) → its voxel centre in lps or ras, or
/// itself in voxel coordinates. grid_from_affine(dims, grid_affine(grid, s), s) gives the grid back.
Eigen::Matrix4d grid_affine(const VoxelGrid& grid, OutputSpace space = OutputSpace::Lps);

/// `map` as a 4×4 homogeneous matrix.
Eigen::Matrix4d homogeneous_matrix(const AffineMap& map);

}  // namespace dsreg
