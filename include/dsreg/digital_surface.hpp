// dsreg — the digital surface of a binary volume as a closed, oriented quad 2-manifold
// (second stage of the pipeline).
//
// A surfel is a voxel face between an object voxel and a background voxel. Its quad lists the
// 4 corner vertices counter-clockwise seen from outside (normal from object to background).
// Vertex positions are the physical positions of the pointels (voxel corners, volume.hpp).
//
// The union of voxel cubes is not a manifold where voxels touch only along an edge or at a
// corner. Edges: at a linel shared by four surfels the surfels are paired according to the
// object connectivity (6: the two diagonal voxels stay apart; 26: they join). Vertices: the
// surfels around a pointel are split into their umbrella cycles, each with its own vertex. The
// result is a closed 2-manifold: every edge has two faces, every vertex a disc.
// One exception keeps it embeddable: where the connectivity's pairing would leave both end
// pointels of such a linel with a single vertex, its two edges would join the same two vertices,
// pinching the surface along a segment that no placement of the vertices can open (two voxels
// touching by one edge and nothing else, with 26-connectivity). Such a linel takes the other
// pairing, which gives each end pointel two vertices (docs/validity.md). So no two faces ever
// run along the same pair of vertices in the same direction.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

enum class Connectivity { Six = 6, TwentySix = 26 };

/// One voxel face: the object voxel it bounds and the direction of its outward normal.
struct Surfel {
    std::array<std::int32_t, 3> voxel;  ///< (i,j,k) of the object voxel
    std::int8_t axis;                   ///< 0, 1, 2 for x, y, z
    std::int8_t sign;                   ///< +1 if the background voxel is voxel + e_axis, else −1

    /// The unit outward normal of the face (the "trivial" normal).
    Eigen::Vector3d trivial_normal() const {
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        n[axis] = sign;
        return n;
    }
};

struct DigitalSurface {
    VoxelGrid grid;
    std::vector<Surfel> surfels;  ///< face f is surfels[f]
    FaceMatrix quads;             ///< m×4, counter-clockwise seen from outside
    PointMatrix vertices;         ///< n×3 physical positions p (pointel positions)
    Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor> vertex_pointels;  ///< pointel (a,b,c) of each vertex
    /// adjacent_face(f, e): the face across edge e of face f (edge e joins corners e and e+1 mod 4).
    FaceMatrix adjacent_face;
    std::vector<std::int32_t> face_component;  ///< connected component of each face, 0-based
    std::int32_t component_count = 0;
    std::int64_t split_pointel_count = 0;  ///< pointels that carry more than one vertex

    std::int64_t face_count() const { return quads.rows(); }
    std::int64_t vertex_count() const { return vertices.rows(); }
};

/// Extracts the digital surface of the object voxels of `volume` (outside the grid is background).
/// Throws dsreg::Error if the object is empty.
DigitalSurface extract_digital_surface(const BinaryVolume& volume, Connectivity connectivity);

/// Physical centre of each surfel (m×3).
PointMatrix surfel_centers(const DigitalSurface& surface);

/// Euler characteristic V − E + F of each connected component (E counts each mesh edge once).
std::vector<std::int64_t> component_euler_characteristics(const DigitalSurface& surface);

/// Vertex adjacency in compressed form: the link of vertex i (the vertices joined to it by a quad
/// edge, one entry per mesh edge) is neighbors[offsets[i] .. offsets[i+1]).
struct VertexLinks {
    std::vector<std::int64_t> offsets;
    std::vector<std::int32_t> neighbors;

    std::int64_t size(std::int64_t i) const { return offsets[i + 1] - offsets[i]; }
};

/// Links of a closed oriented polygon mesh (each directed face edge a→b adds b to link(a)).
VertexLinks vertex_links(const FaceMatrix& faces, std::int64_t vertex_count);

}  // namespace dsreg
