// dsreg — any triangle or quad mesh against an implicit shape: distances, normals, volume,
// voxel classification, triangle quality.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "parallel_checked.hpp"

namespace dsreg {

using detail::parallel_for_checked;

namespace {

void check_mesh(const PolygonMesh& mesh) {
    if (mesh.vertices.rows() == 0 || mesh.faces.rows() == 0) throw Error("the mesh is empty (no vertices or no faces)");
    if (mesh.faces.cols() != 3 && mesh.faces.cols() != 4)
        throw Error("the mesh faces must be triangles or quads (got " + std::to_string(mesh.faces.cols()) + " vertices per face)");
    if ((mesh.faces.array() < 0).any() || (mesh.faces.array() >= mesh.vertices.rows()).any())
        throw Error("a mesh face has a vertex index out of range");
}

/// Indices of the vertices used by some face.
std::vector<std::int64_t> referenced_vertices(const PolygonMesh& mesh) {
    Eigen::Array<bool, Eigen::Dynamic, 1> used = Eigen::Array<bool, Eigen::Dynamic, 1>::Zero(mesh.vertices.rows());
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
        for (Eigen::Index k = 0; k < mesh.faces.cols(); ++k) used[mesh.faces(f, k)] = true;
    std::vector<std::int64_t> indices;
    for (Eigen::Index i = 0; i < used.size(); ++i)
        if (used[i]) indices.push_back(std::int64_t(i));
    return indices;
}

void evaluate_vertex_distances(const PolygonMesh& mesh, const ImplicitShape& shape, double wall_margin,
                               MeshEvaluation& result) {
    PointMatrix points(0, 3);
    std::vector<Eigen::Vector3d> kept;
    for (std::int64_t i : referenced_vertices(mesh)) {
        const Eigen::Vector3d p = mesh.vertices.row(i).transpose();
        if (in_evaluation_region(shape, p, wall_margin)) kept.push_back(p);
        else result.vertices_outside_region += 1;
    }
    points.resize(Eigen::Index(kept.size()), 3);
    for (std::size_t i = 0; i < kept.size(); ++i) points.row(Eigen::Index(i)) = kept[i].transpose();
    result.vertices_evaluated = points.rows();
    result.vertex_distance = error_stats(distances_to_surface(shape, points));
}

void evaluate_face_normals(const PolygonMesh& mesh, const ImplicitShape& shape, double wall_margin,
                           MeshEvaluation& result) {
    const PointMatrix normals = face_normals(mesh.vertices, mesh.faces);
    const PointMatrix centroids = face_centroids(mesh.vertices, mesh.faces);
    constexpr double not_evaluated = -1.0, outside_region = -2.0;
    std::vector<double> angles(std::size_t(mesh.faces.rows()), not_evaluated);
    parallel_for_checked(mesh.faces.rows(), [&](std::int64_t f) {
        const Eigen::Vector3d c = centroids.row(f).transpose();
        if (!in_evaluation_region(shape, c, wall_margin)) {
            angles[std::size_t(f)] = outside_region;
            return;
        }
        const Eigen::Vector3d n = normals.row(f).transpose();
        if (n.isZero()) return;  // degenerate face
        Eigen::Vector3d truth;
        try {
            truth = true_normal(shape, closest_point(shape, c));
        } catch (const Error&) {
            return;  // the projection is a singular point of F = 0: no true normal
        }
        angles[std::size_t(f)] = angle_degrees(n, truth);
    });
    result.face_angle_deg = angles;
    for (double& a : result.face_angle_deg)
        if (a < 0) a = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> evaluated;
    for (double a : angles) {
        if (a == outside_region) result.faces_outside_region += 1;
        else if (a == not_evaluated) result.faces_degenerate += 1;
        else evaluated.push_back(a);
    }
    result.faces_evaluated = std::int64_t(evaluated.size());
    result.normal_angle_deg = error_stats(std::move(evaluated));
}

/// Whether voxel (i,j,k) of `volume` has a 6-neighbour of the other kind (outside the grid is
/// background).
bool next_to_surface(const BinaryVolume& volume, std::int64_t i, std::int64_t j, std::int64_t k) {
    const bool inside = volume.inside(i, j, k);
    static constexpr int steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& d : steps)
        if (volume.inside(i + d[0], j + d[1], k + d[2]) != inside) return true;
    return false;
}

}  // namespace

VoxelClassification classify_voxel_centres(const PolygonMesh& mesh, const BinaryVolume& volume) {
    check_mesh(mesh);
    const FaceMatrix triangles = mesh_triangles(mesh.vertices, mesh.faces);
    const std::vector<std::uint8_t> inside = voxel_centres_inside(mesh.vertices, triangles, volume.grid);
    const Index3& d = volume.grid.dims;
    VoxelClassification c;
    c.total = volume.grid.voxel_count();
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j)
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const std::size_t v = std::size_t(volume.grid.linear_index(i, j, k));
                const bool object = volume.mask[v] != 0;
                const int right = (inside[v] != 0) == object ? 1 : 0;
                c.correct += right;
                if (object) {
                    c.object_total += 1;
                    c.object_correct += right;
                }
                if (next_to_surface(volume, i, j, k)) {
                    c.boundary_total += 1;
                    c.boundary_correct += right;
                }
            }
    return c;
}

bool in_evaluation_region(const ImplicitShape& shape, const Eigen::Vector3d& p, double wall_margin) {
    for (int a = 0; a < 3; ++a)
        if (shape.clipped[std::size_t(a)] && (p[a] < shape.lower[a] + wall_margin || p[a] > shape.upper[a] - wall_margin))
            return false;
    return true;
}

std::vector<double> distances_to_surface(const ImplicitShape& shape, const PointMatrix& points) {
    std::vector<double> distances(std::size_t(points.rows()), 0.0);
    parallel_for_checked(points.rows(), [&](std::int64_t i) {
        const Eigen::Vector3d p = points.row(i).transpose();
        distances[std::size_t(i)] = (p - closest_point(shape, p)).norm();
    });
    return distances;
}

MeshEvaluation evaluate_mesh(const PolygonMesh& mesh, const ImplicitShape& shape, const MeshEvaluationOptions& options) {
    check_mesh(mesh);
    if (!(options.wall_margin >= 0) || !std::isfinite(options.wall_margin))
        throw Error("evaluate_mesh: the wall margin must be finite and non-negative");
    MeshEvaluation result;
    evaluate_vertex_distances(mesh, shape, options.wall_margin, result);
    evaluate_face_normals(mesh, shape, options.wall_margin, result);

    const FaceMatrix triangles = mesh_triangles(mesh.vertices, mesh.faces);
    result.mesh_volume = enclosed_volume(mesh.vertices, triangles);
    result.shape_volume = shape_volume(shape, options.volume_cells);
    result.relative_volume_error = result.shape_volume != 0
                                       ? (result.mesh_volume - result.shape_volume) / result.shape_volume
                                       : std::numeric_limits<double>::quiet_NaN();

    if (options.grid_step > 0) {
        result.has_voxel_classification = true;
        result.voxels = classify_voxel_centres(mesh, digitize(shape, options.grid_step));
    }

    const std::vector<double> min_angles = triangle_min_angles(mesh.vertices, triangles);
    result.triangles = std::int64_t(min_angles.size());
    const ErrorStats angle_stats = error_stats(min_angles);
    result.triangle_min_angle_min_deg = *std::min_element(min_angles.begin(), min_angles.end());
    result.triangle_min_angle_mean_deg = angle_stats.mean;
    return result;
}

}  // namespace dsreg
