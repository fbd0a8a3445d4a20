// dsreg surface — edges, junctions, fairness links and per-label surfaces of the label complex
// (include/dsreg/label_surface.hpp, docs/multi-label.md).
#include "dsreg/label_surface.hpp"

#include <algorithm>
#include <string>

#include "dsreg/error.hpp"
#include "surface_internal.hpp"

namespace dsreg {

using surface_detail::corner_pointels;
using surface_detail::edge_between;
using surface_detail::label_corner;
using surface_detail::UnionFind;

ComplexEdges complex_edges(const DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    UnionFind face_edges(static_cast<std::size_t>(4 * m));
    for (std::int64_t f = 0; f < m; ++f) {
        const auto corners = corner_pointels(surface.surfels[std::size_t(f)]);
        for (const FaceMatrix* adjacent : {&surface.adjacent_face, &surface.adjacent_face_outer})
            for (int e = 0; e < 4; ++e) {
                const std::int64_t g = (*adjacent)(f, e);
                if (g < 0) continue;
                bool same = false;
                const int edge = edge_between(corner_pointels(surface.surfels[std::size_t(g)]), corners[e], corners[(e + 1) % 4], same);
                face_edges.unite(std::uint32_t(4 * f + e), std::uint32_t(4 * g + edge));
            }
    }
    ComplexEdges edges;
    edges.of_face_edge.resize(static_cast<std::size_t>(4 * m));
    std::vector<std::int32_t> edge_of_root(static_cast<std::size_t>(4 * m), -1);
    std::vector<FaceLabels> first_labels;
    for (std::int64_t q = 0; q < 4 * m; ++q) {
        const std::int64_t f = q / 4, e = q % 4;
        std::int32_t& id = edge_of_root[face_edges.find(std::uint32_t(q))];
        const FaceLabels& labels = surface.face_labels[std::size_t(f)];
        if (id < 0) {
            id = static_cast<std::int32_t>(edges.ends.size());
            edges.ends.push_back({surface.quads(f, e), surface.quads(f, (e + 1) % 4)});
            edges.face_count.push_back(0);
            edges.junction.push_back(0);
            first_labels.push_back(labels);
        }
        edges.of_face_edge[std::size_t(q)] = id;
        ++edges.face_count[std::size_t(id)];
        // Faces of one edge separate the same two labels, or at least three between them.
        const FaceLabels& first = first_labels[std::size_t(id)];
        if (first.inner != labels.inner || first.outer != labels.outer) edges.junction[std::size_t(id)] = 1;
    }
    return edges;
}

bool may_have_junctions(const DigitalSurface& surface) {
    const std::size_t faces = std::size_t(surface.face_count());
    return surface.face_labels.size() == faces && surface.surfels.size() == faces && surface.label_count() > 2;
}

Junctions find_junctions(const DigitalSurface& surface, const ComplexEdges& edges) {
    Junctions junctions;
    junctions.vertex.assign(static_cast<std::size_t>(surface.vertex_count()), 0);
    junctions.edges_at_vertex.assign(static_cast<std::size_t>(surface.vertex_count()), 0);
    for (std::int64_t c = 0; c < edges.count(); ++c) {
        if (!edges.junction[std::size_t(c)]) continue;
        ++junctions.edge_count;
        for (const std::int32_t v : edges.ends[std::size_t(c)]) {
            junctions.vertex[std::size_t(v)] = 1;
            ++junctions.edges_at_vertex[std::size_t(v)];
        }
    }
    for (std::size_t v = 0; v < junctions.vertex.size(); ++v) {
        if (!junctions.vertex[v]) continue;
        ++junctions.vertex_count;
        if (junctions.edges_at_vertex[v] != 2) ++junctions.point_count;
    }
    return junctions;
}

std::vector<char> junction_turn_vertices(const DigitalSurface& surface, const ComplexEdges& edges) {
    std::vector<char> turn(static_cast<std::size_t>(surface.vertex_count()), 0);
    const auto junction_edge = [&](std::int64_t f, int e) {
        return edges.junction[std::size_t(edges.of_face_edge[std::size_t(4 * f + e)])] != 0;
    };
    for (std::int64_t f = 0; f < surface.face_count(); ++f)
        for (int k = 0; k < 4; ++k)  // face edge k joins corners k and k + 1
            if (junction_edge(f, k) && junction_edge(f, (k + 3) % 4)) turn[std::size_t(surface.quads(f, k))] = 1;
    return turn;
}

PointMatrix junction_turn_targets(const DigitalSurface& surface, const ComplexEdges& edges, const VertexLinks& links,
                                  double share) {
    const std::vector<char> turn = junction_turn_vertices(surface, edges);
    if (std::find(turn.begin(), turn.end(), 1) == turn.end()) return {};
    PointMatrix targets = PointMatrix::Zero(surface.vertex_count(), 3);
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v) {
        if (!turn[std::size_t(v)] || links.size(v) != 2) continue;  // a junction point has no fairness to offset
        const std::int64_t q = links.offsets[std::size_t(v)];
        const Eigen::RowVector3d chord_middle =
            0.5 * (surface.vertices.row(links.neighbors[std::size_t(q)]) + surface.vertices.row(links.neighbors[std::size_t(q + 1)]));
        targets.row(v) = share * (surface.vertices.row(v) - chord_middle);
    }
    return targets;
}

VertexLinks fairness_links(const DigitalSurface& surface) {
    // Without junctions the surface is a closed manifold: its links are the quad links, which the
    // edge pass would find in the same order (LabelSurface.BinaryVolumeIsTheSpecialCase), at
    // about 0.4 µs a face.
    if (!may_have_junctions(surface)) return vertex_links(surface.quads, surface.vertex_count());
    return fairness_links(surface, complex_edges(surface));
}

VertexLinks fairness_links(const DigitalSurface& surface, const ComplexEdges& edges) {
    const Junctions junctions = find_junctions(surface, edges);
    const std::int64_t m = surface.face_count(), n = surface.vertex_count();
    // Each edge gives each of its ends one link entry, at the first face edge leaving that end
    // (or, if none leaves it, the first face edge of the edge): on a closed oriented manifold
    // that is the face edge a → b that vertex_links uses, so the links are the same, in order.
    std::vector<std::array<std::int64_t, 2>> designated(static_cast<std::size_t>(edges.count()), {-1, -1});
    std::vector<std::int64_t> first(static_cast<std::size_t>(edges.count()), -1);
    for (std::int64_t q = 0; q < 4 * m; ++q) {
        const std::size_t c = std::size_t(edges.of_face_edge[std::size_t(q)]);
        if (first[c] < 0) first[c] = q;
        const int end = surface.quads(q / 4, q % 4) == edges.ends[c][0] ? 0 : 1;
        if (designated[c][std::size_t(end)] < 0) designated[c][std::size_t(end)] = q;
    }
    for (std::size_t c = 0; c < designated.size(); ++c)
        for (std::int64_t& q : designated[c])
            if (q < 0) q = first[c];
    const auto linked = [&](std::size_t c, std::int32_t v) {
        if (!junctions.vertex[std::size_t(v)]) return true;
        return edges.junction[c] && junctions.edges_at_vertex[std::size_t(v)] == 2;
    };
    // Two passes over the face edges in order: count, then fill.
    VertexLinks links;
    links.offsets.assign(static_cast<std::size_t>(n + 1), 0);
    const auto visit = [&](auto add) {
        for (std::int64_t q = 0; q < 4 * m; ++q) {
            const std::size_t c = std::size_t(edges.of_face_edge[std::size_t(q)]);
            for (int end = 0; end < 2; ++end) {
                if (designated[c][std::size_t(end)] != q) continue;
                const std::int32_t v = edges.ends[c][std::size_t(end)], other = edges.ends[c][std::size_t(1 - end)];
                if (linked(c, v)) add(v, other);
            }
        }
    };
    visit([&](std::int32_t v, std::int32_t) { ++links.offsets[std::size_t(v) + 1]; });
    for (std::int64_t i = 0; i < n; ++i) links.offsets[std::size_t(i + 1)] += links.offsets[std::size_t(i)];
    links.neighbors.resize(static_cast<std::size_t>(links.offsets.back()));
    std::vector<std::int64_t> cursor(links.offsets.begin(), links.offsets.end() - 1);
    visit([&](std::int32_t v, std::int32_t other) { links.neighbors[std::size_t(cursor[std::size_t(v)]++)] = other; });
    return links;
}

std::vector<std::int64_t> LabelMesh::euler_characteristics() const {
    std::vector<std::int64_t> faces(static_cast<std::size_t>(component_count), 0), corners(faces.size(), 0);
    std::vector<char> seen(vertices.size(), 0);
    for (Eigen::Index f = 0; f < quads.rows(); ++f) {
        const std::size_t c = std::size_t(face_component[std::size_t(f)]);
        ++faces[c];
        for (int k = 0; k < 4; ++k) {
            char& s = seen[std::size_t(quads(f, k))];
            if (!s) ++corners[c];
            s = 1;
        }
    }
    std::vector<std::int64_t> chi(faces.size());
    for (std::size_t c = 0; c < faces.size(); ++c) chi[c] = corners[c] - 2 * faces[c] + faces[c];  // E = 4F/2
    return chi;
}

namespace {

/// The faces of every label, each label's in increasing face order: (face, side) pairs.
std::vector<std::vector<std::pair<std::int64_t, int>>> faces_by_label(const DigitalSurface& surface) {
    std::vector<std::vector<std::pair<std::int64_t, int>>> faces(static_cast<std::size_t>(surface.label_count()));
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const FaceLabels& l = surface.face_labels[std::size_t(f)];
        faces[l.inner].emplace_back(f, 0);
        if (l.outer != 0) faces[l.outer].emplace_back(f, 1);
    }
    return faces;
}

void label_mesh_components(const DigitalSurface& surface, const std::vector<std::int32_t>& local_face, int sides,
                           LabelMesh& mesh) {
    const std::int64_t count = mesh.face_count();
    UnionFind components(static_cast<std::size_t>(count));
    for (std::int64_t local = 0; local < count; ++local) {
        const std::int64_t f = mesh.faces[std::size_t(local)];
        const int side = mesh.reversed[std::size_t(local)];
        const FaceMatrix& adjacent = side == 0 ? surface.adjacent_face : surface.adjacent_face_outer;
        for (int e = 0; e < 4; ++e) {
            const std::int64_t g = adjacent(f, e);
            const int g_side = surface.face_labels[std::size_t(g)].inner == mesh.label ? 0 : 1;
            components.unite(std::uint32_t(local), std::uint32_t(local_face[std::size_t(g * sides + g_side)]));
        }
    }
    mesh.face_component.assign(static_cast<std::size_t>(count), -1);
    std::vector<std::int32_t> of_root(static_cast<std::size_t>(count), -1);
    for (std::int64_t local = 0; local < count; ++local) {
        std::int32_t& c = of_root[components.find(std::uint32_t(local))];
        if (c < 0) c = mesh.component_count++;
        mesh.face_component[std::size_t(local)] = c;
    }
}

}  // namespace

std::vector<LabelMesh> label_meshes(const DigitalSurface& surface) {
    const std::int64_t m = surface.face_count();
    const int sides = surface_detail::label_sides(surface);
    UnionFind corners(static_cast<std::size_t>(4 * sides * m));
    surface_detail::unite_label_corners(surface, sides, corners);
    // The label corners of one class all belong to one label, so local vertex numbers can share
    // one table for every label.
    std::vector<std::int32_t> local_vertex(corners.size(), -1);
    std::vector<std::int32_t> local_face(static_cast<std::size_t>(sides * m), -1);
    std::vector<std::int32_t> own_vertices_at(static_cast<std::size_t>(surface.vertex_count()), 0);
    std::vector<LabelMesh> meshes;
    const auto by_label = faces_by_label(surface);
    for (std::size_t label = 1; label < by_label.size(); ++label) {
        const auto& faces = by_label[label];
        if (faces.empty()) continue;
        LabelMesh mesh;
        mesh.label = static_cast<std::uint32_t>(label);
        mesh.quads.resize(static_cast<Eigen::Index>(faces.size()), 4);
        for (std::size_t local = 0; local < faces.size(); ++local) {
            const auto [f, side] = faces[local];
            mesh.faces.push_back(f);
            mesh.reversed.push_back(static_cast<std::uint8_t>(side));
            local_face[std::size_t(f * sides + side)] = static_cast<std::int32_t>(local);
            for (int k = 0; k < 4; ++k) {
                const int stored = side == 0 ? k : (4 - k) % 4;  // the outer side reads the quad backwards
                std::int32_t& id = local_vertex[corners.find(label_corner(f, side, stored, sides))];
                if (id < 0) {
                    id = static_cast<std::int32_t>(mesh.vertices.size());
                    const std::int32_t vertex = surface.quads(f, stored);
                    mesh.vertices.push_back(vertex);
                    if (++own_vertices_at[std::size_t(vertex)] == 2) ++mesh.pinch_vertices;
                }
                mesh.quads(Eigen::Index(local), k) = id;
            }
        }
        for (const std::int32_t vertex : mesh.vertices) own_vertices_at[std::size_t(vertex)] = 0;
        label_mesh_components(surface, local_face, sides, mesh);
        meshes.push_back(std::move(mesh));
    }
    return meshes;
}

PolygonMesh label_polygon_mesh(const LabelMesh& mesh, const PointMatrix& positions, const PointMatrix& normals) {
    PolygonMesh out;
    out.vertices.resize(mesh.vertex_count(), 3);
    for (std::int64_t v = 0; v < mesh.vertex_count(); ++v) out.vertices.row(v) = positions.row(mesh.vertices[std::size_t(v)]);
    out.faces = mesh.quads;
    if (normals.rows() > 0) {
        out.face_normals.resize(mesh.face_count(), 3);
        for (std::int64_t f = 0; f < mesh.face_count(); ++f) {
            const double sign = mesh.reversed[std::size_t(f)] ? -1.0 : 1.0;
            out.face_normals.row(f) = sign * normals.row(mesh.faces[std::size_t(f)]);
        }
    }
    return out;
}

}  // namespace dsreg
