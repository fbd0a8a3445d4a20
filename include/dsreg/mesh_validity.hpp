// dsreg — is a mesh a valid solid? Self-intersections and faces folded against the normal field
// (docs/validity.md).
//
// Definition. A triangle or quad mesh is *valid* when the triangle mesh users get from it — each
// quad (a,b,c,d) split along its shorter diagonal, exactly as `--triangulate`, the STL writer and
// the evaluation do (triangulate_shorter_diagonal, mesh_io.hpp) — has
//  1. no degenerate triangle (three collinear vertices, so zero area);
//  2. no self-intersection: two triangles may meet only in what they share by index — the common
//     edge of two triangles with two vertex indices in common, the common vertex of two
//     triangles with one. Two triangles sharing an edge intersect if they overlap (they are
//     coplanar and folded onto each other); two sharing a vertex intersect if they meet anywhere
//     else; two sharing nothing intersect if they meet at all, even in one point. Vertices with
//     distinct indices at the same position (e.g. the copies of a split pointel of the digital
//     surface, digital_surface.hpp) therefore count as an intersection: the surface touches
//     itself there, which a solid's boundary must not do;
//  3. (with a field u, one vector per face, e.g. the normals the regularization aligned to) no
//     face folded against u: every triangle the face can be split into has a normal n with
//     n·u_f > 0 — for a quad (a,b,c,d) the four corner triangles abc, acd, abd, bcd, so that it
//     holds along either diagonal, whichever a viewer splits along. A folded quad is a crease or
//     a face turned inside out. This implies count_faces_against_field (evaluation.hpp) = 0,
//     which looks only at the mean normal of abc and acd.
// A closed oriented 2-manifold mesh satisfying 1–2 is the boundary of a solid (it bounds a
// region, its winding number is 0 or 1 everywhere): it can be 3D printed, tetrahedralized,
// used in a simulation.
//
// The intersection test is CGAL's Polygon_mesh_processing::self_intersections (exact
// predicates): the triangles are built into a CGAL surface mesh with the mesh's own vertex
// indices, so adjacency is exactly "shares an index" above. All positions in any units.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "dsreg/mesh.hpp"

namespace dsreg {

/// What CGAL finds in a triangle mesh (indices into its rows).
struct TriangleSelfIntersections {
    std::vector<std::pair<std::int64_t, std::int64_t>> pairs;  ///< intersecting triangles, first < second, sorted
    std::vector<std::int64_t> degenerate;                       ///< triangles with collinear vertices, sorted
};

/// Self-intersections of a triangle mesh (n×3 faces, any orientation, need not be closed or
/// manifold: two triangles may meet in what they share by index, whatever the edge structure —
/// at the non-manifold edges and vertices of a label complex too). Throws dsreg::Error for faces that are not
/// triangles, indices out of range or non-finite coordinates.
TriangleSelfIntersections triangle_self_intersections(const PointMatrix& vertices, const FaceMatrix& triangles);

struct MeshValidity {
    std::int64_t faces = 0;                 ///< faces of the mesh (quads or triangles)
    std::int64_t triangles = 0;             ///< triangles of its shorter-diagonal split
    std::int64_t intersecting_pairs = 0;    ///< pairs of triangles that intersect (2 above)
    std::int64_t degenerate_triangles = 0;  ///< (1 above)
    std::int64_t folded_faces = 0;          ///< faces with a triangle against u (3 above; 0 without u)
    /// Faces (rows of the input faces) with a degenerate or intersecting triangle, sorted.
    std::vector<std::int32_t> intersecting_faces;
    /// Faces folded against u, sorted.
    std::vector<std::int32_t> folded;
    double seconds = 0;  ///< wall time of the check

    bool valid() const { return intersecting_pairs == 0 && degenerate_triangles == 0 && folded_faces == 0; }
    /// Every invalid face (intersecting, degenerate or folded), sorted, each once.
    std::vector<std::int32_t> invalid_faces() const;
};

/// Checks a triangle or quad mesh by the definition above. `field`: empty (no fold test) or one
/// vector per face. Throws dsreg::Error for faces other than triangles or quads, indices out of
/// range, or a field of the wrong size.
MeshValidity check_mesh_validity(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& field = {});

/// Faces of `faces` (triangles or quads) folded against `field` (3 above): a triangle of either
/// split of the quad (or the triangle itself) whose normal has a non-positive dot product with
/// that face's row of `field`, degenerate triangles included. Sorted.
std::vector<std::int32_t> faces_folded_against_field(const PointMatrix& vertices, const FaceMatrix& faces,
                                                     const PointMatrix& field);

/// The corners at which quad (q0, q1, q2, q3) is folded against u (3 above): corner k when the
/// triangle (q_{k−1}, q_k, q_{k+1}) has n·u ≤ 0, i.e. q_k lies on the wrong side of the diagonal
/// between its two neighbours (or on it). A quad folded along one diagonal only has one or two
/// such corners, the apexes of its turned triangles; a quad turned over has all four; a quad
/// with none is not folded.
std::array<bool, 4> folded_corners(const std::array<Eigen::Vector3d, 4>& quad, const Eigen::Vector3d& u);

}  // namespace dsreg
