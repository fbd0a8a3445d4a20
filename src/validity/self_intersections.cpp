// dsreg — self-intersections of a triangle mesh by CGAL's Polygon_mesh_processing (the only
// translation unit that includes CGAL: its templates are heavy and compile once, here).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <iterator>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/mesh_validity.hpp"

namespace dsreg {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using CgalVertex = CgalMesh::Vertex_index;
using CgalFace = CgalMesh::Face_index;

void check_triangle_mesh(const PointMatrix& vertices, const FaceMatrix& triangles) {
    if (triangles.rows() > 0 && triangles.cols() != 3)
        throw Error("self-intersection test: faces have " + std::to_string(triangles.cols()) +
                    " vertices each; it needs triangles");
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
        for (int k = 0; k < 3; ++k)
            if (triangles(t, k) < 0 || triangles(t, k) >= vertices.rows())
                throw Error("self-intersection test: triangle " + std::to_string(t) + " refers to vertex " +
                            std::to_string(triangles(t, k)) + " but the mesh has " + std::to_string(vertices.rows()) +
                            " vertices");
    for (Eigen::Index v = 0; v < vertices.rows(); ++v)
        if (!vertices.row(v).allFinite())
            throw Error("self-intersection test: vertex " + std::to_string(v) + " has a non-finite coordinate");
}

/// The triangles as a CGAL surface mesh on the same vertex indices; `triangle_of` maps each CGAL
/// face back to its row. A triangle that does not fit the edge structure of those added before it
/// (a non-manifold edge or vertex, an orientation clash) gets its own copies of its vertices.
CgalMesh make_cgal_mesh(const PointMatrix& vertices, const FaceMatrix& triangles, std::vector<std::int64_t>& triangle_of) {
    CgalMesh mesh;
    mesh.reserve(CgalMesh::size_type(vertices.rows()), CgalMesh::size_type(3 * triangles.rows()),
                 CgalMesh::size_type(triangles.rows()));
    const auto point = [&](Eigen::Index v) { return Kernel::Point_3(vertices(v, 0), vertices(v, 1), vertices(v, 2)); };
    for (Eigen::Index v = 0; v < vertices.rows(); ++v) mesh.add_vertex(point(v));
    triangle_of.clear();
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        const auto corner = [&](int k) { return CgalVertex(CgalMesh::size_type(triangles(t, k))); };
        CgalFace face = mesh.add_face(corner(0), corner(1), corner(2));
        if (face == CgalMesh::null_face())
            face = mesh.add_face(mesh.add_vertex(point(triangles(t, 0))), mesh.add_vertex(point(triangles(t, 1))),
                                 mesh.add_vertex(point(triangles(t, 2))));
        if (std::size_t(face.idx()) != triangle_of.size())
            throw Error("self-intersection test: could not build triangle " + std::to_string(t));  // not expected
        triangle_of.push_back(t);
    }
    return mesh;
}

}  // namespace

TriangleSelfIntersections triangle_self_intersections(const PointMatrix& vertices, const FaceMatrix& triangles) {
    check_triangle_mesh(vertices, triangles);
    std::vector<std::int64_t> triangle_of;
    const CgalMesh mesh = make_cgal_mesh(vertices, triangles, triangle_of);
    std::vector<std::pair<CgalFace, CgalFace>> found;
    CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(found));

    TriangleSelfIntersections result;
    for (const auto& [f, g] : found) {
        const std::int64_t a = triangle_of[f.idx()], b = triangle_of[g.idx()];
        if (a == b)
            result.degenerate.push_back(a);  // CGAL reports a degenerate face as the pair (f, f)
        else
            result.pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
    std::sort(result.pairs.begin(), result.pairs.end());
    std::sort(result.degenerate.begin(), result.degenerate.end());
    return result;
}

}  // namespace dsreg
