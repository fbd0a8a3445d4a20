// dsreg — from the grid frame, where the pipeline works, to the space a mesh is written in.
//
// Every stage works in the axis-aligned grid frame of dsreg/volume.hpp: voxel (i,j,k) is centred
// at origin + spacing ⊙ (i,j,k). A medical image adds direction cosines D (orthonormal), so that
// its world position (ITK, DICOM and 3D Slicer files: LPS, x towards the patient's Left, y
// Posterior, z Superior) is world = origin + D·(p − origin). Distances are the same in both
// frames (D is orthonormal), so the mesh is computed in the grid frame and mapped once, last:
//  * lps:   world = origin + D·(p − origin);
//  * ras:   diag(−1,−1,1)·world (nibabel, FreeSurfer, FSL, MRtrix: Right, Anterior, Superior);
//  * voxel: the continuous voxel index (p − origin) ⊘ spacing: voxel centres at integers,
//           mesh vertices (voxel corners) at half-integers.
// A map of negative determinant (a left-handed index frame, common in NIfTI) turns a
// counter-clockwise face clockwise: the faces are then listed in reverse order, so that they stay
// counter-clockwise seen from outside with the right-hand normal pointing out.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <string>

#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

enum class OutputSpace { Lps, Ras, Voxel };

/// "lps", "ras" or "voxel" (any case). Throws dsreg::Error for anything else.
OutputSpace parse_output_space(const std::string& name);
/// "lps", "ras" or "voxel".
std::string output_space_name(OutputSpace space);
/// The name 3D Slicer writes in its model files ("LPS", "RAS"), or "" for voxel coordinates,
/// which Slicer has no name for.
std::string slicer_coordinate_system(OutputSpace space);

/// An affine map y = linear·x + offset.
struct AffineMap {
    Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();

    Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return linear * x + offset; }
    /// True when the map turns counter-clockwise faces clockwise (negative determinant).
    bool reverses_orientation() const { return linear.determinant() < 0; }
};

/// The map from the grid frame of `grid` to `space` (see above).
AffineMap grid_to_space(const VoxelGrid& grid, OutputSpace space);

/// Each row of `points` mapped by `map`.
PointMatrix map_points(const AffineMap& map, const PointMatrix& points);

/// Each row of `normals` mapped as a surface normal: by the inverse transpose of map.linear, then
/// rescaled to unit length (zero rows stay zero). For an orthonormal map that is linear·n.
PointMatrix map_normals(const AffineMap& map, const PointMatrix& normals);

/// `mesh` (in the grid frame of `grid`) in `space`: vertices and face normals mapped, faces
/// reversed when the map reverses orientation, mesh.coordinate_system set to
/// slicer_coordinate_system(space). Vertex scalars are kept.
PolygonMesh mesh_in_space(PolygonMesh mesh, const VoxelGrid& grid, OutputSpace space);

}  // namespace dsreg
