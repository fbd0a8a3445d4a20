// dsreg — validity of a triangle or quad mesh: its shorter-diagonal triangles, their
// self-intersections (self_intersections.cpp) and the faces folded against the field u.
#include "dsreg/mesh_validity.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"

namespace dsreg {

namespace {

/// Rows of `faces` owning the given triangles of mesh_triangles(faces): a quad q gave the
/// triangles 2q and 2q + 1, a triangle t is triangle t. Sorted, each once.
std::vector<std::int32_t> owning_faces(const std::vector<std::int64_t>& triangles, Eigen::Index face_size) {
    std::vector<std::int32_t> faces;
    faces.reserve(triangles.size());
    for (const std::int64_t t : triangles) faces.push_back(std::int32_t(face_size == 4 ? t / 2 : t));
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    return faces;
}

std::vector<std::int32_t> sorted_union(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
    std::vector<std::int32_t> both;
    both.reserve(a.size() + b.size());
    std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(both));
    return both;
}

}  // namespace

std::vector<std::int32_t> MeshValidity::invalid_faces() const { return sorted_union(intersecting_faces, folded); }

std::vector<std::int32_t> faces_folded_against_field(const PointMatrix& vertices, const FaceMatrix& faces,
                                                     const PointMatrix& field) {
    if (field.rows() != faces.rows())
        throw Error("fold test: " + std::to_string(field.rows()) + " field vectors for " + std::to_string(faces.rows()) +
                    " faces");
    if (faces.rows() > 0 && faces.cols() != 3 && faces.cols() != 4)
        throw Error("fold test: faces have " + std::to_string(faces.cols()) + " vertices; triangles or quads only");
    if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= vertices.rows()))
        throw Error("fold test: a face refers to a vertex out of range (the mesh has " + std::to_string(vertices.rows()) +
                    " vertices)");
    // Corner triangles: the two splits of a quad (a,b,c,d), along ac and along bd.
    static constexpr int kQuadCorners[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 1, 3}, {1, 2, 3}};
    static constexpr int kTriangle[1][3] = {{0, 1, 2}};
    const bool quads = faces.cols() == 4;
    std::vector<std::int32_t> folded;
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        const Eigen::Vector3d u = field.row(f).transpose();
        bool against = false;
        for (int t = 0; t < (quads ? 4 : 1) && !against; ++t) {
            const int* corner = quads ? kQuadCorners[t] : kTriangle[t];
            const Eigen::Vector3d a = vertices.row(faces(f, corner[0])), b = vertices.row(faces(f, corner[1])),
                                  c = vertices.row(faces(f, corner[2]));
            // Not normalized: the sign of (b−a)×(c−a)·u is the fold test, and 0 (no area) fails it.
            against = !((b - a).cross(c - a).dot(u) > 0);
        }
        if (against) folded.push_back(std::int32_t(f));
    }
    return folded;
}

std::array<bool, 4> folded_corners(const std::array<Eigen::Vector3d, 4>& quad, const Eigen::Vector3d& u) {
    std::array<bool, 4> folded{};
    for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d& previous = quad[std::size_t((k + 3) % 4)];
        const Eigen::Vector3d to_corner = quad[std::size_t(k)] - previous, to_next = quad[std::size_t((k + 1) % 4)] - previous;
        folded[std::size_t(k)] = !(to_corner.cross(to_next).dot(u) > 0);
    }
    return folded;
}

MeshValidity check_mesh_validity(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& field) {
    const auto started = std::chrono::steady_clock::now();
    MeshValidity validity;
    const FaceMatrix triangles = mesh_triangles(vertices, faces);  // checks face sizes and indices
    validity.faces = faces.rows();
    validity.triangles = triangles.rows();

    const TriangleSelfIntersections found = triangle_self_intersections(vertices, triangles);
    validity.intersecting_pairs = std::int64_t(found.pairs.size());
    validity.degenerate_triangles = std::int64_t(found.degenerate.size());
    std::vector<std::int64_t> involved = found.degenerate;
    for (const auto& [a, b] : found.pairs) {
        involved.push_back(a);
        involved.push_back(b);
    }
    validity.intersecting_faces = owning_faces(involved, faces.cols());

    if (field.rows() > 0 || faces.rows() == 0) {
        validity.folded = faces_folded_against_field(vertices, faces, field);
        validity.folded_faces = std::int64_t(validity.folded.size());
    }
    validity.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return validity;
}

}  // namespace dsreg
