// dsreg — the digital surface of a binary volume as a closed, oriented quad 2-manifold, and of a
// label map as a complex of such manifolds sharing their interfaces (second stage of the
// pipeline; docs/multi-label.md).
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
//
// Label maps. A face lies between every two voxels of different labels (the background, label
// 0, included; outside the grid is background). It is stored once, as the surfel of its
// *inner* label, the higher label index of the two, with its normal towards the *outer* (lower)
// one; a binary volume is the label map {0, 1}, and gives the surface above, face for face.
// Each label's faces are paired at its linels by the rule above, applied to that label's own
// indicator, so each label's umbrellas are exactly those of its binary digital surface. A
// vertex is a class of face corners at one pointel that some label's umbrella joins: faces
// between two labels carry one set of vertices, shared by both. Where three or more regions
// meet (junction curves and points) the complex is not a manifold; each label's surface still
// is (label_meshes() in label_surface.hpp, with one vertex per umbrella).
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

/// The two labels of a face: `inner` (the voxel of its surfel) > `outer` (across the face).
struct FaceLabels {
    std::uint32_t inner;
    std::uint32_t outer;
};

struct DigitalSurface {
    VoxelGrid grid;
    std::vector<Surfel> surfels;  ///< face f is surfels[f]; its voxel is the one of the inner label
    FaceMatrix quads;             ///< m×4, counter-clockwise seen from outside the inner label
    PointMatrix vertices;         ///< n×3 physical positions p (pointel positions)
    Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor> vertex_pointels;  ///< pointel (a,b,c) of each vertex
    /// adjacent_face(f, e): the face across edge e of face f (edge e joins corners e and e+1 mod 4)
    /// in the surface of the inner label of f.
    FaceMatrix adjacent_face;
    /// The same in the surface of the outer label of f; −1 where that is the background (so all
    /// −1 for a binary volume).
    FaceMatrix adjacent_face_outer;
    std::vector<FaceLabels> face_labels;       ///< label indices of each face (binary: all {1, 0})
    std::vector<std::int64_t> label_values;    ///< input value of each label index (binary: {0, 1})
    std::vector<std::int32_t> face_component;  ///< connected component of each face, 0-based
    std::int32_t component_count = 0;
    std::int64_t split_pointel_count = 0;  ///< pointels that carry more than one vertex

    std::int64_t face_count() const { return quads.rows(); }
    std::int64_t vertex_count() const { return vertices.rows(); }
    std::int64_t label_count() const { return static_cast<std::int64_t>(label_values.size()); }
};

/// Extracts the digital surface of the object voxels of `volume` (outside the grid is background).
/// Throws dsreg::Error if the object is empty.
DigitalSurface extract_digital_surface(const BinaryVolume& volume, Connectivity connectivity);

/// The complex of every interface of a label map: the same construction, a binary volume being
/// the label map {0, 1} (label_volume_from_mask gives the surface above exactly). Connectivity
/// applies to each label's own indicator. Throws dsreg::Error if no voxel has a label.
DigitalSurface extract_digital_surface(const LabelVolume& volume, Connectivity connectivity);

/// Pointel (a,b,c) of corner `corner` (0–3, the order of DigitalSurface::quads: counter-clockwise
/// seen from outside) of surfel s, in the voxel coordinates of s.
std::array<std::int64_t, 3> surfel_corner_pointel(const Surfel& s, int corner);

/// Labels the connected components of the faces (face_component, component_count) from
/// adjacent_face (and adjacent_face_outer on a label complex).
void label_components(DigitalSurface& surface);

/// Pointels that carry more than one vertex (from vertex_pointels).
std::int64_t count_split_pointels(const DigitalSurface& surface);

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

/// The corners of a face array at each vertex in compressed form: vertex i is corner e of face f
/// for each code f·k + e in codes[offsets[i] .. offsets[i+1]) (k = face_size), in increasing f.
/// About 24 bytes per quad, against 60 for a vector of faces per vertex.
struct VertexCorners {
    std::vector<std::int64_t> offsets;
    std::vector<std::int32_t> codes;
    std::int32_t face_size = 0;

    /// Calls visit(f) for each face with a corner at vertex i, in increasing order.
    template <class Visit>
    void for_each_face(std::int64_t i, Visit visit) const {
        for (std::int64_t q = offsets[std::size_t(i)]; q < offsets[std::size_t(i) + 1]; ++q) visit(codes[std::size_t(q)] / face_size);
    }
};

/// The corners of `faces` at each of the vertex_count vertices. Throws dsreg::Error if the codes
/// f·k + e do not fit in 32 bits.
VertexCorners vertex_corners(const FaceMatrix& faces, std::int64_t vertex_count);

}  // namespace dsreg
