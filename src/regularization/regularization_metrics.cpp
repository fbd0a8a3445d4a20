// dsreg — identity and area metrics W0, W2 (§3.4 eq. 15–17, §6).
#include "dsreg/regularization_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

/// Area of one voxel face of axis `axis` (the product of the two other spacings), length².
double voxel_face_area(const Eigen::Vector3d& spacing, int axis) {
    return spacing[(axis + 1) % 3] * spacing[(axis + 2) % 3];
}

Eigen::VectorXd estimated_face_areas(const DigitalSurface& surface, const PointMatrix& normals, double min_cosine) {
    Eigen::VectorXd areas(surface.face_count());
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const double cosine = std::abs(normals(f, s.axis));  // |u_f · n_f| with n_f = ±e_axis
        areas[f] = std::max(cosine, min_cosine) * voxel_face_area(surface.grid.spacing, s.axis);
    }
    return areas;
}

/// w0_i = ¼ Σ_{f ∋ i} a_f.
Eigen::VectorXd dual_vertex_areas(const FaceMatrix& quads, const Eigen::VectorXd& face_areas, std::int64_t vertex_count) {
    Eigen::VectorXd areas = Eigen::VectorXd::Zero(vertex_count);
    for (Eigen::Index f = 0; f < quads.rows(); ++f)
        for (Eigen::Index c = 0; c < quads.cols(); ++c) areas[quads(f, c)] += face_areas[f] / double(quads.cols());
    return areas;
}

}  // namespace

MetricKind parse_metric_kind(const std::string& name) {
    if (name == "identity") return MetricKind::Identity;
    if (name == "area") return MetricKind::Area;
    throw Error("unknown metric '" + name + "' (choose identity or area)");
}

std::string metric_name(MetricKind kind) { return kind == MetricKind::Area ? "area" : "identity"; }

std::vector<std::string> metric_names() { return {"identity", "area"}; }

AreaMetric estimate_area_metric(const DigitalSurface& surface, const PointMatrix& normals, const AreaMetricOptions& options) {
    if (normals.rows() != surface.face_count())
        throw Error("area metric: the normal field has " + std::to_string(normals.rows()) + " vectors for " +
                    std::to_string(surface.face_count()) + " faces");
    if (!(options.min_cosine > 0 && options.min_cosine <= 1))
        throw Error("area metric: min_cosine must be in (0, 1] (got " + std::to_string(options.min_cosine) + ")");
    AreaMetric metric;
    metric.face_areas = estimated_face_areas(surface, normals, options.min_cosine);
    metric.vertex_areas = dual_vertex_areas(surface.quads, metric.face_areas, surface.vertex_count());
    return metric;
}

void apply_metric(MetricKind kind, const DigitalSurface& surface, const PointMatrix& normals, RegularizationWeights& weights,
                  const AreaMetricOptions& options) {
    if (kind == MetricKind::Identity) {
        weights.vertex_weights.resize(0);
        weights.face_weights.resize(0);
        return;
    }
    AreaMetric metric = estimate_area_metric(surface, normals, options);
    weights.vertex_weights = std::move(metric.vertex_areas);
    weights.face_weights = std::move(metric.face_areas);
}

}  // namespace dsreg
