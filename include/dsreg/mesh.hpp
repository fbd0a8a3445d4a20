// dsreg — plain mesh data passed between stages (in the spirit of libigl: arrays, no objects).
//
// Positions are in physical units (see volume.hpp for the voxel/pointel conventions). Faces list
// vertex indices (0-based) counter-clockwise seen from outside, so that the right-hand normal
// points out of the object.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace dsreg {

/// n×3 matrix of points or vectors, one per row.
using PointMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// m×k matrix of vertex indices, one face per row (k = 4 for quads, 3 for triangles).
using FaceMatrix = Eigen::Matrix<std::int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A polygon mesh with all faces of the same size (quads or triangles), plus optional
/// attributes that writers export when the format can hold them.
struct PolygonMesh {
    PointMatrix vertices;
    FaceMatrix faces;
    PointMatrix face_normals;  ///< empty, or one unit vector per face (e.g. the input field u)
    std::vector<std::pair<std::string, Eigen::VectorXd>> vertex_scalars;  ///< named per-vertex values
    /// The coordinate system of the positions as 3D Slicer names it: "LPS", "RAS", or "" when
    /// unspecified (grid frame, voxel coordinates). Writers record it the way Slicer does
    /// (dsreg/mesh_io.hpp) so that Slicer places the mesh without asking; readers restore it.
    std::string coordinate_system;
    /// Named per-face integers, e.g. the labels on either side of each face of a label complex.
    /// Added last, with a default member initializer, so that aggregate initialization
    /// {vertices, faces, normals, scalars} stays valid and warning-free.
    std::vector<std::pair<std::string, Eigen::VectorXi>> face_integers{};
};

}  // namespace dsreg
