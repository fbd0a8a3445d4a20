// Removal of the drift of a regularized surface along its normals (include/dsreg/shrink_correction.hpp).
#include "dsreg/shrink_correction.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// Centroid of each face (mean of its four vertices).
PointMatrix quad_centroids(const DigitalSurface& surface, const PointMatrix& positions) {
    PointMatrix centroid = PointMatrix::Zero(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        for (int k = 0; k < 4; ++k) centroid.row(f) += 0.25 * positions.row(surface.quads(f, k));
    return centroid;
}

/// How far the smooth surface through a quad's corners lies beyond the quad, on average over
/// the quad, along u_f. A surface with normal curvatures κ_a, κ_b along the quad's sides (lengths
/// a, b) is z = −(κ_a x² + κ_b y²)/2 over its tangent plane; through the corners (±a/2, ±b/2) the
/// quad is the plane z = −(κ_a a² + κ_b b²)/8, so the surface lies above it by
/// (κ_a (a²/4 − x²) + κ_b (b²/4 − y²))/2: (κ_a a² + κ_b b²)/8 at the centre (the sagitta) and
/// (κ_a a² + κ_b b²)/12 on average over the quad, two thirds of it. The normal curvature across
/// edge e is taken from the faces g, g' across the two sides parallel to it:
/// (u_g − u_g')·(c_g − c_g') / |c_g − c_g'|² (c: centroids; 1/R on a sphere of radius R).
double mean_height_over_quad(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals,
                             const PointMatrix& centroids, std::int64_t f) {
    double height = 0;
    for (int e = 0; e < 2; ++e) {
        // Sides e and e + 2 face each other; their neighbours lie along side e + 1.
        const std::int64_t g = surface.adjacent_face(f, e), g2 = surface.adjacent_face(f, e + 2);
        const Eigen::RowVector3d dc = centroids.row(g2) - centroids.row(g);
        const double length2 = dc.squaredNorm();
        if (!(length2 > 0)) continue;
        const double curvature = (normals.row(g2) - normals.row(g)).dot(dc) / length2;
        const double side = (positions.row(surface.quads(f, (e + 2) % 4)) - positions.row(surface.quads(f, e + 1))).norm();
        height += curvature * side * side / 12.0;
    }
    return height;
}

/// Per face: how far the regularized surface moved along u_f from the surfel centre, measured
/// as the mean over the quad of the smooth surface through its corners (centroid + two thirds of
/// the sagitta): the surfel centre is its surfel's mean point, so it is compared with the mean of
/// the surface patch that replaces the surfel. Not at the centroid (the flat quad), which lies
/// inside a convex surface (by 0.05 voxel on a tube 1.5 voxels in radius), nor at the patch's
/// apex (centroid + sagitta), which lies beyond its mean and so pulled small round objects in (a
/// ball 5.5 voxels in radius lost 3 % of its volume; docs/accuracy.md).
Eigen::VectorXd face_offsets(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals) {
    const PointMatrix centres = surfel_centers(surface);
    const PointMatrix centroids = quad_centroids(surface, positions);
    Eigen::VectorXd offset(surface.face_count());
#pragma omp parallel for schedule(static)
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        offset[f] = normals.row(f).dot(centroids.row(f) - centres.row(f)) +
                    mean_height_over_quad(surface, positions, normals, centroids, f);
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

/// The drift per face: the narrow average of the offsets, soft-thresholded towards the wide one
/// (shrink_correction.hpp), blended towards the local one by the local share.
Eigen::VectorXd averaged_drift(const DigitalSurface& surface, const Eigen::VectorXd& offsets, const ShrinkAveraging& a) {
    Eigen::VectorXd drift = average_over_faces(surface, offsets, a.steps);
    if (a.wide_steps > a.steps) {
        const Eigen::VectorXd wide = average_over_faces(surface, drift, a.wide_steps - a.steps);  // the same filter, longer
        const double tolerance = a.wide_tolerance * surface.grid.spacing.minCoeff();
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            const double difference = drift[f] - wide[f];
            drift[f] = wide[f] + std::copysign(std::max(0.0, std::abs(difference) - tolerance), difference);
        }
    }
    if (a.local_share.size() > 0 && (a.local_share.array() > 0).any()) {
        const Eigen::VectorXd local = average_over_faces(surface, offsets, a.local_steps);
        drift += a.local_share.cwiseMax(0.0).cwiseMin(1.0).cwiseProduct(local - drift);
    }
    return drift;
}

}  // namespace

ShrinkCorrection correct_shrink(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals,
                                const ShrinkAveraging& averaging) {
    if (positions.rows() != surface.vertex_count() || normals.rows() != surface.face_count())
        throw Error("correct_shrink: " + std::to_string(positions.rows()) + " positions and " +
                    std::to_string(normals.rows()) + " normals for a surface of " +
                    std::to_string(surface.vertex_count()) + " vertices and " + std::to_string(surface.face_count()) +
                    " faces");
    const ShrinkAveraging& a = averaging;
    if (a.steps < 0 || a.wide_steps < 0 || a.local_steps < 0)
        throw Error("correct_shrink: the number of averaging steps must not be negative");
    if (!(a.wide_tolerance >= 0) || !std::isfinite(a.wide_tolerance))
        throw Error("correct_shrink: the wide average's tolerance must be zero or positive and finite");
    if (a.local_share.size() != 0 && a.local_share.size() != surface.face_count())
        throw Error("correct_shrink: " + std::to_string(a.local_share.size()) + " local shares for " +
                    std::to_string(surface.face_count()) + " faces");
    ShrinkCorrection result;
    result.positions = positions;
    if (a.steps == 0) return result;
    const Eigen::VectorXd drift = averaged_drift(surface, face_offsets(surface, positions, normals), a);
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
