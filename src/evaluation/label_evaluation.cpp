// dsreg evaluation — label complexes against known partitions, and per-label measures
// (include/dsreg/label_evaluation.hpp).
#include "dsreg/label_evaluation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace dsreg {

std::vector<std::vector<std::int64_t>> vertex_label_values(const DigitalSurface& surface) {
    std::vector<std::vector<std::int64_t>> labels(static_cast<std::size_t>(surface.vertex_count()));
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const FaceLabels& l = surface.face_labels[std::size_t(f)];
        for (int k = 0; k < 4; ++k) {
            auto& set = labels[std::size_t(surface.quads(f, k))];
            set.push_back(surface.label_values[l.inner]);
            set.push_back(surface.label_values[l.outer]);
        }
    }
    for (auto& set : labels) {
        std::sort(set.begin(), set.end());
        set.erase(std::unique(set.begin(), set.end()), set.end());
    }
    return labels;
}

LabelComplexErrors label_complex_errors(const LabelShape& shape, const DigitalSurface& surface,
                                        const PointMatrix& positions) {
    const auto labels = vertex_label_values(surface);
    const std::int64_t n = surface.vertex_count();
    std::vector<double> nearest(static_cast<std::size_t>(n)), meet(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t v = 0; v < n; ++v) {
        const Eigen::Vector3d p = positions.row(v).transpose();
        const auto& set = labels[std::size_t(v)];
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t a = 0; a < set.size(); ++a)
            for (std::size_t b = a + 1; b < set.size(); ++b) best = std::min(best, shape.distance(p, {set[a], set[b]}));
        nearest[std::size_t(v)] = best;
        meet[std::size_t(v)] = set.size() >= 3 ? shape.distance(p, set) : best;
    }
    LabelComplexErrors errors;
    std::vector<double> all, sheets, junctions;
    for (std::int64_t v = 0; v < n; ++v) {
        if (std::isfinite(nearest[std::size_t(v)])) all.push_back(nearest[std::size_t(v)]);
        if (labels[std::size_t(v)].size() == 2) {
            sheets.push_back(nearest[std::size_t(v)]);
        } else if (std::isfinite(meet[std::size_t(v)])) {
            junctions.push_back(meet[std::size_t(v)]);
        } else {
            ++errors.unmatched_junctions;
        }
    }
    errors.interfaces = error_stats(all);
    errors.sheets = error_stats(sheets);
    errors.junctions = error_stats(junctions);
    return errors;
}

LabelMeasures measure_label(const DigitalSurface& surface, const LabelMesh& mesh, const PointMatrix& positions,
                            std::int64_t voxel_count) {
    LabelMeasures m;
    m.value = surface.label_values[mesh.label];
    m.faces = mesh.face_count();
    m.vertices = mesh.vertex_count();
    const PolygonMesh polygons = label_polygon_mesh(mesh, positions, PointMatrix());
    const FaceMatrix triangles = mesh_triangles(polygons.vertices, polygons.faces);
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        const Eigen::Vector3d a = polygons.vertices.row(triangles(t, 0)), b = polygons.vertices.row(triangles(t, 1)),
                              c = polygons.vertices.row(triangles(t, 2));
        m.area += 0.5 * (b - a).cross(c - a).norm();
    }
    m.volume = enclosed_volume(polygons.vertices, triangles);
    m.voxel_volume = double(voxel_count) * surface.grid.spacing.prod();
    m.components = mesh.component_count;
    m.euler_characteristics = mesh.euler_characteristics();
    for (const std::int64_t chi : m.euler_characteristics) m.genus += (2 - chi) / 2;
    m.pinch_vertices = mesh.pinch_vertices;
    return m;
}

}  // namespace dsreg
