#include "dsreg/normals.hpp"

namespace dsreg {

PointMatrix trivial_normals(const DigitalSurface& surface) {
    PointMatrix u(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        u.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
    return u;
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
