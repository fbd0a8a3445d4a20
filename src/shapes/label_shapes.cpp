// dsreg shapes — known label partitions with exact distances to their interfaces and junctions
// (include/dsreg/label_shapes.hpp). Every interface piece is convex in its plane or a region of
// a sphere bounded by circles, so each distance is a projection followed by a clamp.
#include "dsreg/label_shapes.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kRadius = 10.0;  // the ball of every shape, centred at kCentre
// Off the lattice of any sensible grid step, so that no interface passes through voxel centres
// (which would bias the digitization by half a lattice layer).
const Eigen::Vector3d kCentre(0.137, -0.241, 0.318);

/// Distance from p to the circle of centre c, unit normal n and radius r.
double circle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& c, const Eigen::Vector3d& n, double r) {
    const Eigen::Vector3d d = p - c;
    const double height = d.dot(n);
    const double radial = (d - height * n).norm();
    return std::hypot(height, radial - r);
}

/// Distance from p to the disc of centre c, unit normal n and radius r.
double disc_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& c, const Eigen::Vector3d& n, double r) {
    const Eigen::Vector3d d = p - c;
    const double height = d.dot(n);
    const double radial = (d - height * n).norm();
    return std::hypot(height, std::max(0.0, radial - r));
}

double segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    return (p - (a + t * ab)).norm();
}

// ---- sectors ---------------------------------------------------------------------------------

struct Sectors {
    Eigen::Vector3d axis;
    Eigen::Vector3d e1, e2;                 // an orthonormal frame of the plane ⊥ axis
    std::array<double, 3> azimuth{};        // boundary k starts sector k+1 (radians, increasing)

    Sectors() {
        axis = Eigen::Vector3d(1, 2, 3).normalized();
        e1 = axis.cross(Eigen::Vector3d::UnitX()).normalized();
        e2 = axis.cross(e1);
        azimuth = {0.0, 110.0 * M_PI / 180.0, 235.0 * M_PI / 180.0};
    }
    /// Unit direction of the half-plane at boundary k (in the plane ⊥ axis).
    Eigen::Vector3d direction(int k) const { return std::cos(azimuth[k]) * e1 + std::sin(azimuth[k]) * e2; }
    /// Sector (0, 1, 2) of the azimuth of p around the axis.
    int sector(const Eigen::Vector3d& p) const {
        double angle = std::atan2(p.dot(e2), p.dot(e1));
        if (angle < 0) angle += 2 * M_PI;
        if (angle < azimuth[1]) return 0;
        return angle < azimuth[2] ? 1 : 2;
    }
    std::int64_t label(const Eigen::Vector3d& p) const { return p.squaredNorm() <= kRadius * kRadius ? sector(p) + 1 : 0; }

    /// The half great circle where boundary k meets the sphere.
    double half_circle_distance(const Eigen::Vector3d& p, int k) const {
        const Eigen::Vector3d d = direction(k);
        const double u = p.dot(axis), w = p.dot(d);
        const double out = (p - u * axis - w * d).norm();  // distance to the plane of the circle
        if (w >= 0 && (u != 0 || w != 0)) {
            const double in_plane = std::hypot(u, w);
            return std::hypot(out, in_plane - kRadius);
        }
        const double to_poles = std::min((p - kRadius * axis).norm(), (p + kRadius * axis).norm());
        return w >= 0 ? std::hypot(out, kRadius) : to_poles;
    }
    /// The half-disc of boundary k inside the ball: {u·axis + w·d : w ≥ 0, u² + w² ≤ R²}.
    double half_disc_distance(const Eigen::Vector3d& p, int k) const {
        const Eigen::Vector3d d = direction(k);
        const double u = p.dot(axis), w = p.dot(d);
        const double out = (p - u * axis - w * d).norm();
        double cu = u, cw = w;  // the closest point, in the plane's coordinates
        if (cw < 0) {
            cw = 0;
            cu = std::clamp(u, -kRadius, kRadius);
        } else if (cu * cu + cw * cw > kRadius * kRadius) {
            const double scale = kRadius / std::hypot(cu, cw);
            cu *= scale;
            cw *= scale;
        }
        return std::sqrt(out * out + (u - cu) * (u - cu) + (w - cw) * (w - cw));
    }
    /// The part of the sphere in sector s.
    double lune_distance(const Eigen::Vector3d& p, int s) const {
        if (sector(p) == s && p.squaredNorm() > 0) return std::abs(p.norm() - kRadius);
        return std::min(half_circle_distance(p, s), half_circle_distance(p, (s + 1) % 3));
    }
    /// The boundary between sectors a and b (0-based, a ≠ b): they are cyclically adjacent.
    static int boundary_between(int a, int b) {
        if ((a + 1) % 3 == b) return b;
        return a;
    }
    double distance(const Eigen::Vector3d& p, const std::vector<std::int64_t>& labels) const {
        const bool background = labels.front() == 0;
        std::vector<int> sectors;
        for (std::int64_t l : labels)
            if (l != 0) sectors.push_back(int(l) - 1);
        if (background && sectors.size() == 3)
            return std::min((p - kRadius * axis).norm(), (p + kRadius * axis).norm());
        if (sectors.size() == 3) return segment_distance(p, -kRadius * axis, kRadius * axis);
        if (background && sectors.size() == 2) return half_circle_distance(p, boundary_between(sectors[0], sectors[1]));
        if (background && sectors.size() == 1) return lune_distance(p, sectors[0]);
        if (sectors.size() == 2) return half_disc_distance(p, boundary_between(sectors[0], sectors[1]));
        return kInfinity;
    }
};

// ---- layers ----------------------------------------------------------------------------------

struct Layers {
    Eigen::Vector3d normal = Eigen::Vector3d(2, -1, 2) / 3.0;
    std::array<double, 2> cut{-3.43, 4.57};

    std::int64_t label(const Eigen::Vector3d& p) const {
        if (p.squaredNorm() > kRadius * kRadius) return 0;
        const double h = p.dot(normal);
        return h < cut[0] ? 1 : h < cut[1] ? 2 : 3;
    }
    double circle(const Eigen::Vector3d& p, int k) const {
        return circle_distance(p, cut[k] * normal, normal, std::sqrt(kRadius * kRadius - cut[k] * cut[k]));
    }
    double disc(const Eigen::Vector3d& p, int k) const {
        return disc_distance(p, cut[k] * normal, normal, std::sqrt(kRadius * kRadius - cut[k] * cut[k]));
    }
    /// The part of the sphere with height in [low, high] (layer `layer`).
    double zone(const Eigen::Vector3d& p, int layer) const {
        const double low = layer == 0 ? -kRadius : cut[layer - 1], high = layer == 2 ? kRadius : cut[layer];
        if (p.squaredNorm() > 0) {
            const double h = kRadius * p.normalized().dot(normal);
            if (h >= low && h <= high) return std::abs(p.norm() - kRadius);
        }
        double best = kInfinity;
        if (layer > 0) best = std::min(best, circle(p, layer - 1));
        if (layer < 2) best = std::min(best, circle(p, layer));
        return best;
    }
    double distance(const Eigen::Vector3d& p, const std::vector<std::int64_t>& labels) const {
        if (labels == std::vector<std::int64_t>{0, 1, 2}) return circle(p, 0);
        if (labels == std::vector<std::int64_t>{0, 2, 3}) return circle(p, 1);
        if (labels == std::vector<std::int64_t>{1, 2}) return disc(p, 0);
        if (labels == std::vector<std::int64_t>{2, 3}) return disc(p, 1);
        if (labels.size() == 2 && labels[0] == 0) return zone(p, int(labels[1]) - 1);
        return kInfinity;
    }
};

// ---- nested ----------------------------------------------------------------------------------

struct Nested {
    Eigen::Vector3d centre = Eigen::Vector3d(1.5, -1.0, 0.5);
    double radius = 5.0;

    std::int64_t label(const Eigen::Vector3d& p) const {
        if ((p - centre).squaredNorm() <= radius * radius) return 2;
        return p.squaredNorm() <= kRadius * kRadius ? 1 : 0;
    }
    double distance(const Eigen::Vector3d& p, const std::vector<std::int64_t>& labels) const {
        if (labels == std::vector<std::int64_t>{0, 1}) return std::abs(p.norm() - kRadius);
        if (labels == std::vector<std::int64_t>{1, 2}) return std::abs((p - centre).norm() - radius);
        return kInfinity;
    }
};

template <class Shape>
LabelShape wrap(const std::string& name, const Shape& shape) {
    LabelShape out;
    out.name = name;
    out.lower = kCentre - Eigen::Vector3d::Constant(kRadius);
    out.upper = kCentre + Eigen::Vector3d::Constant(kRadius);
    out.label = [shape](const Eigen::Vector3d& p) { return shape.label(p - kCentre); };
    out.distance = [shape](const Eigen::Vector3d& p, const std::vector<std::int64_t>& labels) {
        return shape.distance(p - kCentre, labels);
    };
    return out;
}

}  // namespace

std::vector<std::string> label_shape_names() { return {"sectors", "layers", "nested"}; }

LabelShape make_label_shape(const std::string& name) {
    if (name == "sectors") return wrap(name, Sectors());
    if (name == "layers") return wrap(name, Layers());
    if (name == "nested") return wrap(name, Nested());
    throw Error("unknown label shape '" + name + "' (known: sectors, layers, nested)");
}

LabelVolume digitize_labels(const LabelShape& shape, double h) {
    if (!(h > 0) || !std::isfinite(h)) throw Error("digitize_labels: h must be positive and finite");
    Index3 first{}, dims{};
    for (int d = 0; d < 3; ++d) {
        first[d] = static_cast<std::int64_t>(std::floor(shape.lower[d] / h)) - 1;
        dims[d] = static_cast<std::int64_t>(std::ceil(shape.upper[d] / h)) + 1 - first[d] + 1;
    }
    if (double(dims[0]) * double(dims[1]) * double(dims[2]) > double(1 << 30))
        throw Error("digitize_labels: shape '" + shape.name + "' at h = " + std::to_string(h) + " needs more than 2^30 voxels");
    LabelVolume volume;
    volume.grid.dims = dims;
    volume.grid.spacing = Eigen::Vector3d::Constant(h);
    volume.grid.origin = h * Eigen::Vector3d(double(first[0]), double(first[1]), double(first[2]));
    volume.labels.assign(static_cast<std::size_t>(volume.grid.voxel_count()), 0u);
    std::int64_t largest = 0;
#pragma omp parallel for schedule(dynamic) reduction(max : largest)
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const Eigen::Vector3d p = volume.grid.voxel_center(i, j, k);
                const std::int64_t label = shape.label(p);
                volume.labels[std::size_t(volume.grid.linear_index(i, j, k))] = static_cast<std::uint32_t>(label);
                largest = std::max(largest, label);
            }
    for (std::int64_t l = 0; l <= largest; ++l) volume.values.push_back(l);
    return volume;
}

}  // namespace dsreg
