#include "dsreg/normals.hpp"

#include <cmath>
#include <string>

#include "dsreg/error.hpp"

namespace dsreg {

PointMatrix trivial_normals(const DigitalSurface& surface) {
    PointMatrix u(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
    return u;
}

Eigen::Vector3d lift_into_half_space(const Eigen::Vector3d& u, const Eigen::Vector3d& n, double margin) {
    const double along = u.dot(n);
    if (along >= margin) return u;
    const Eigen::Vector3d tangential = u - along * n;
    const double length = tangential.norm();
    if (!(length > 1e-12)) return n;
    return std::sqrt(1 - margin * margin) * tangential / length + margin * n;
}

namespace {

void check_field_size(const DigitalSurface& surface, const PointMatrix& normals, const char* what) {
    if (normals.rows() != surface.face_count() || normals.cols() != 3)
        throw Error(std::string(what) + ": " + std::to_string(normals.rows()) + " normals for " +
                    std::to_string(surface.face_count()) + " faces");
}

}  // namespace

bool lift_into_surfel_half_space(const DigitalSurface& surface, PointMatrix& normals, std::int64_t f, double margin) {
    const Eigen::Vector3d n = surface.surfels[std::size_t(f)].trivial_normal();
    const Eigen::Vector3d u = normals.row(f).transpose();
    if (u.dot(n) >= margin) return false;
    normals.row(f) = lift_into_half_space(u, n, margin).transpose();
    return true;
}

std::int64_t lift_into_surfel_half_spaces(const DigitalSurface& surface, PointMatrix& normals, double margin) {
    check_field_size(surface, normals, "field lift");
    if (!(margin >= 0 && margin < 1)) throw Error("field lift: the margin must be in [0, 1)");
    std::int64_t lifted = 0;
    for (std::int64_t f = 0; f < surface.face_count(); ++f) lifted += lift_into_surfel_half_space(surface, normals, f, margin);
    return lifted;
}

std::vector<std::int32_t> faces_against_their_surfels(const DigitalSurface& surface, const PointMatrix& normals) {
    check_field_size(surface, normals, "faces against their surfels");
    std::vector<std::int32_t> faces;
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        if (normals.row(f).dot(surface.surfels[std::size_t(f)].trivial_normal().transpose()) < 0) faces.push_back(std::int32_t(f));
    return faces;
}

PointMatrix exact_normals(const ImplicitShape& shape, const DigitalSurface& surface) {
    const PointMatrix centers = surfel_centers(surface);
    PointMatrix u(surface.face_count(), 3);
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = true_normal(shape, closest_point(shape, centers.row(f).transpose())).transpose();
    return u;
}

}  // namespace dsreg
