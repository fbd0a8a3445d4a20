// dsreg — per-face geometry of triangle and quad meshes: normals, centroids, enclosed volume,
// triangle angles.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"

namespace dsreg {
namespace {

void check_face_size(const FaceMatrix& faces) {
    if (faces.rows() > 0 && faces.cols() != 3 && faces.cols() != 4)
        throw Error("mesh faces must be triangles or quads (got " + std::to_string(faces.cols()) + " vertices per face)");
}

Eigen::Vector3d vertex(const PointMatrix& vertices, std::int32_t index) { return vertices.row(index).transpose(); }

/// Unit normal of triangle (a,b,c), or zero if it has no area.
Eigen::Vector3d unit_triangle_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double length = n.norm();
    return length > 0 && std::isfinite(length) ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

}  // namespace

PointMatrix face_normals(const PointMatrix& vertices, const FaceMatrix& faces) {
    check_face_size(faces);
    PointMatrix normals(faces.rows(), 3);
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        const Eigen::Vector3d a = vertex(vertices, faces(f, 0)), b = vertex(vertices, faces(f, 1)),
                              c = vertex(vertices, faces(f, 2));
        Eigen::Vector3d n = unit_triangle_normal(a, b, c);
        if (faces.cols() == 4) {
            // Footnote 5 of the paper: the mean of the unit normals of triangles abc and acd.
            n += unit_triangle_normal(a, c, vertex(vertices, faces(f, 3)));
            const double length = n.norm();
            n = length > 1e-12 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
        }
        normals.row(f) = n.transpose();
    }
    return normals;
}

std::int64_t count_faces_against_field(const PointMatrix& vertices, const FaceMatrix& faces, const PointMatrix& field) {
    if (field.rows() != faces.rows())
        throw Error("count_faces_against_field: " + std::to_string(field.rows()) + " field vectors for " +
                    std::to_string(faces.rows()) + " faces");
    const PointMatrix normals = face_normals(vertices, faces);
    std::int64_t against = 0;
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
        against += (normals.row(f).squaredNorm() == 0 || normals.row(f).dot(field.row(f)) < 0) ? 1 : 0;
    return against;
}

PointMatrix face_centroids(const PointMatrix& vertices, const FaceMatrix& faces) {
    PointMatrix centroids = PointMatrix::Zero(faces.rows(), 3);
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        for (Eigen::Index k = 0; k < faces.cols(); ++k) centroids.row(f) += vertices.row(faces(f, k));
        centroids.row(f) /= double(faces.cols());
    }
    return centroids;
}

double angle_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    // atan2(|a×b|, a·b) keeps full precision for angles near 0 and 180 degrees (acos does not).
    constexpr double degrees_per_radian = 180.0 / 3.14159265358979323846;
    return std::atan2(a.cross(b).norm(), a.dot(b)) * degrees_per_radian;
}

FaceMatrix mesh_triangles(const PointMatrix& vertices, const FaceMatrix& faces) {
    check_face_size(faces);
    PolygonMesh mesh;
    mesh.vertices = vertices;
    mesh.faces = faces;
    return triangulate_shorter_diagonal(mesh).faces;
}

double enclosed_volume(const PointMatrix& vertices, const FaceMatrix& triangles) {
    double six_volume = 0;
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        const Eigen::Vector3d a = vertex(vertices, triangles(t, 0)), b = vertex(vertices, triangles(t, 1)),
                              c = vertex(vertices, triangles(t, 2));
        six_volume += a.dot(b.cross(c));
    }
    return six_volume / 6.0;
}

std::vector<double> triangle_min_angles(const PointMatrix& vertices, const FaceMatrix& triangles) {
    std::vector<double> angles(std::size_t(triangles.rows()), 0.0);
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        const Eigen::Vector3d a = vertex(vertices, triangles(t, 0)), b = vertex(vertices, triangles(t, 1)),
                              c = vertex(vertices, triangles(t, 2));
        if ((b - a).norm() == 0 || (c - b).norm() == 0 || (a - c).norm() == 0) continue;  // degenerate: 0
        angles[std::size_t(t)] =
            std::min({angle_degrees(b - a, c - a), angle_degrees(c - b, a - b), angle_degrees(a - c, b - c)});
    }
    return angles;
}

}  // namespace dsreg
