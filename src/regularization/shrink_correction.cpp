// Removal of the drift of a regularized surface along its normals (include/dsreg/shrink_correction.hpp).
#include "dsreg/shrink_correction.hpp"

#include <algorithm>
#include <string>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// u_f · (centroid of the regularized quad − surfel centre): how far the face moved along u.
Eigen::VectorXd face_offsets(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals) {
    const PointMatrix centres = surfel_centers(surface);
    Eigen::VectorXd offset(surface.face_count());
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
        for (int k = 0; k < 4; ++k) centroid += 0.25 * positions.row(surface.quads(f, k));
        offset[f] = normals.row(f).dot(centroid - centres.row(f));
    }
    return offset;
}

/// `steps` rounds of replacing each value by the mean of itself and its four edge neighbours.
Eigen::VectorXd average_over_faces(const DigitalSurface& surface, Eigen::VectorXd values, int steps) {
    Eigen::VectorXd next(values.size());
    for (int step = 0; step < steps; ++step) {
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            double sum = values[f];
            for (int e = 0; e < 4; ++e) sum += values[surface.adjacent_face(f, e)];
            next[f] = sum / 5.0;
        }
        values.swap(next);
    }
    return values;
}

}  // namespace

ShrinkCorrection correct_shrink(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals,
                                int steps) {
    if (positions.rows() != surface.vertex_count() || normals.rows() != surface.face_count())
        throw Error("correct_shrink: " + std::to_string(positions.rows()) + " positions and " +
                    std::to_string(normals.rows()) + " normals for a surface of " +
                    std::to_string(surface.vertex_count()) + " vertices and " + std::to_string(surface.face_count()) +
                    " faces");
    if (steps < 0) throw Error("correct_shrink: the number of averaging steps must not be negative");
    ShrinkCorrection result;
    result.positions = positions;
    if (steps == 0) return result;
    const Eigen::VectorXd drift = average_over_faces(surface, face_offsets(surface, positions, normals), steps);
    const std::int64_t n = surface.vertex_count();
    PointMatrix vertex_normal = PointMatrix::Zero(n, 3);
    Eigen::VectorXd vertex_drift = Eigen::VectorXd::Zero(n), faces = Eigen::VectorXd::Zero(n);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        for (int k = 0; k < 4; ++k) {
            const std::int32_t v = surface.quads(f, k);
            vertex_normal.row(v) += normals.row(f);
            vertex_drift[v] += drift[f];
            faces[v] += 1;
        }
    double total = 0;
    for (std::int64_t v = 0; v < n; ++v) {
        const double norm = vertex_normal.row(v).norm();
        if (!(norm > 0)) continue;  // opposite normals cancel: no direction to move along
        const Eigen::RowVector3d shift = -(vertex_drift[v] / faces[v]) * vertex_normal.row(v) / norm;
        result.positions.row(v) += shift;
        total += shift.norm();
        result.max_shift = std::max(result.max_shift, shift.norm());
    }
    result.mean_shift = n > 0 ? total / double(n) : 0.0;
    return result;
}

}  // namespace dsreg
