#include "mesh_parts.hpp"

#include <algorithm>
#include <numeric>

namespace dsreg::detail {

namespace {

std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t v) {
    while (parent[std::size_t(v)] != v) {
        parent[std::size_t(v)] = parent[std::size_t(parent[std::size_t(v)])];  // path halving
        v = parent[std::size_t(v)];
    }
    return v;
}

/// Component of each vertex (vertices sharing a face, or one in the other's link, are in the
/// same one), numbered 0.. in the order of their smallest vertex.
std::vector<std::int32_t> vertex_components(const FaceMatrix& quads, const VertexLinks& links, std::int64_t n, std::int32_t& count) {
    std::vector<std::int32_t> parent(static_cast<std::size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    const auto join = [&](std::int32_t u, std::int32_t v) {
        const std::int32_t a = find_root(parent, u), b = find_root(parent, v);
        if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    };
    for (Eigen::Index f = 0; f < quads.rows(); ++f)
        for (Eigen::Index e = 1; e < quads.cols(); ++e) join(quads(f, 0), quads(f, e));
    for (std::int64_t i = 0; i < n; ++i)
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            join(std::int32_t(i), links.neighbors[std::size_t(q)]);
    std::vector<std::int32_t> component(static_cast<std::size_t>(n), -1);
    count = 0;
    for (std::int64_t v = 0; v < n; ++v) {
        const std::int32_t root = find_root(parent, std::int32_t(v));
        if (component[std::size_t(root)] < 0) component[std::size_t(root)] = count++;
        component[std::size_t(v)] = component[std::size_t(root)];
    }
    return component;
}

}  // namespace

std::vector<MeshPart> mesh_parts(const FaceMatrix& quads, const VertexLinks& links, std::int64_t n, std::int64_t small_vertices,
                                 std::int64_t batch_vertices) {
    std::int32_t count = 0;
    const std::vector<std::int32_t> component = vertex_components(quads, links, n, count);
    std::vector<std::int64_t> size(static_cast<std::size_t>(count), 0);
    for (std::int32_t c : component) ++size[std::size_t(c)];

    // Part of each component: large ones alone (largest first), small ones in batches.
    std::vector<std::int32_t> order(static_cast<std::size_t>(count));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) { return size[std::size_t(a)] > size[std::size_t(b)]; });
    std::vector<std::int32_t> part_of(static_cast<std::size_t>(count), -1);
    std::vector<MeshPart> parts;
    std::int64_t batch_size = 0;
    for (std::int32_t c : order) {
        const bool small = size[std::size_t(c)] <= small_vertices;
        if (!small || parts.empty() || !parts.back().small || batch_size + size[std::size_t(c)] > batch_vertices) {
            parts.emplace_back();
            parts.back().small = small;
            batch_size = 0;
        }
        part_of[std::size_t(c)] = std::int32_t(parts.size() - 1);
        ++parts.back().components;
        batch_size += size[std::size_t(c)];
    }
    for (std::int64_t v = 0; v < n; ++v) parts[std::size_t(part_of[std::size_t(component[std::size_t(v)])])].vertices.push_back(std::int32_t(v));
    for (Eigen::Index f = 0; f < quads.rows(); ++f)
        parts[std::size_t(part_of[std::size_t(component[std::size_t(quads(f, 0))])])].faces.push_back(std::int32_t(f));
    if (parts.size() == 1) parts.front().whole = true;
    return parts;
}

PartMesh extract_part(const MeshPart& part, const PointMatrix& positions, const FaceMatrix& quads, const VertexLinks& links,
                      const PointMatrix& normals, const RegularizationWeights& w) {
    PartMesh mesh;
    const std::int64_t n = std::int64_t(part.vertices.size()), m = std::int64_t(part.faces.size());
    std::vector<std::int32_t> local(static_cast<std::size_t>(positions.rows()), -1);
    for (std::int64_t i = 0; i < n; ++i) local[std::size_t(part.vertices[std::size_t(i)])] = std::int32_t(i);
    mesh.positions.resize(n, 3);
    for (std::int64_t i = 0; i < n; ++i) mesh.positions.row(i) = positions.row(part.vertices[std::size_t(i)]);
    mesh.quads.resize(m, quads.cols());
    mesh.normals.resize(m, 3);
    for (std::int64_t f = 0; f < m; ++f) {
        const std::int32_t g = part.faces[std::size_t(f)];
        for (Eigen::Index e = 0; e < quads.cols(); ++e) mesh.quads(f, e) = local[std::size_t(quads(g, e))];
        mesh.normals.row(f) = normals.row(g);
    }
    // The links, in the same order (a vertex's links are in its part: mesh_parts joins them).
    mesh.links.offsets.assign(std::size_t(n + 1), 0);
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int32_t g = part.vertices[std::size_t(i)];
        for (std::int64_t q = links.offsets[std::size_t(g)]; q < links.offsets[std::size_t(g + 1)]; ++q)
            mesh.links.neighbors.push_back(local[std::size_t(links.neighbors[std::size_t(q)])]);
        mesh.links.offsets[std::size_t(i + 1)] = std::int64_t(mesh.links.neighbors.size());
    }
    const auto rows_of = [](const Eigen::VectorXd& values, const std::vector<std::int32_t>& index) {
        Eigen::VectorXd out(values.size() ? Eigen::Index(index.size()) : 0);
        for (Eigen::Index i = 0; i < out.size(); ++i) out[i] = values[index[std::size_t(i)]];
        return out;
    };
    mesh.weights.alpha = w.alpha;
    mesh.weights.beta = w.beta;
    mesh.weights.gamma = w.gamma;
    mesh.weights.vertex_weights = rows_of(w.vertex_weights, part.vertices);
    mesh.weights.face_weights = rows_of(w.face_weights, part.faces);
    mesh.weights.vertex_alpha = rows_of(w.vertex_alpha, part.vertices);
    mesh.weights.face_beta = rows_of(w.face_beta, part.faces);
    mesh.weights.vertex_gamma = rows_of(w.vertex_gamma, part.vertices);
    if (w.fairness_targets.rows() > 0) mesh.weights.fairness_targets = w.fairness_targets(part.vertices, Eigen::all);
    return mesh;
}

Eigen::VectorXd gather_part(const MeshPart& part, const Eigen::VectorXd& x) {
    if (part.whole) return x;
    Eigen::VectorXd local(3 * Eigen::Index(part.vertices.size()));
    for (std::size_t i = 0; i < part.vertices.size(); ++i) local.segment<3>(3 * Eigen::Index(i)) = x.segment<3>(3 * Eigen::Index(part.vertices[i]));
    return local;
}

void scatter_part(const MeshPart& part, const Eigen::VectorXd& local, Eigen::VectorXd& x) {
    if (part.whole) {
        x = local;
        return;
    }
    for (std::size_t i = 0; i < part.vertices.size(); ++i) x.segment<3>(3 * Eigen::Index(part.vertices[i])) = local.segment<3>(3 * Eigen::Index(i));
}

}  // namespace dsreg::detail
