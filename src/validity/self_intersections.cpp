// dsreg — self-intersections of a triangle mesh by CGAL's Polygon_mesh_processing (the only
// translation unit that includes CGAL: its templates are heavy and compile once, here).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <omp.h>

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
/// (a non-manifold edge or vertex, an orientation clash) gets its own copies of its vertices:
/// CGAL then sees no adjacency for it and reports every contact.
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

/// Whether triangles a and b (rows of `triangles`) meet beyond the vertices they share by index:
/// the rule CGAL applies to adjacent faces, on the indices (a triangle of a non-manifold edge,
/// such as a junction of a label complex, shares its edge with several others). Sharing an edge,
/// they intersect when coplanar and on the same side of it; sharing a vertex, when the edge of
/// either opposite that vertex meets the other triangle; sharing nothing, when they meet.
bool meet_beyond_shared_indices(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t a, std::int64_t b) {
    const auto point = [&](std::int64_t t, int k) {
        const Eigen::Index v = triangles(t, k);
        return Kernel::Point_3(vertices(v, 0), vertices(v, 1), vertices(v, 2));
    };
    const auto triangle = [&](std::int64_t t) { return Kernel::Triangle_3(point(t, 0), point(t, 1), point(t, 2)); };
    int shared = 0, a_shared[3] = {-1, -1, -1}, b_shared[3] = {-1, -1, -1};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (triangles(a, i) == triangles(b, j)) a_shared[shared] = i, b_shared[shared] = j, ++shared;
    if (shared == 0) return CGAL::do_intersect(triangle(a), triangle(b));
    if (shared == 3) return true;  // the same triangle twice
    if (shared == 2) {
        const int a_free = 3 - a_shared[0] - a_shared[1], b_free = 3 - b_shared[0] - b_shared[1];
        const Kernel::Point_3 u = point(a, a_shared[0]), v = point(a, a_shared[1]);
        return CGAL::coplanar(u, v, point(a, a_free), point(b, b_free)) &&
               CGAL::coplanar_orientation(u, v, point(a, a_free), point(b, b_free)) == CGAL::POSITIVE;
    }
    const int i = a_shared[0], j = b_shared[0];
    const Kernel::Segment_3 a_opposite(point(a, (i + 1) % 3), point(a, (i + 2) % 3));
    const Kernel::Segment_3 b_opposite(point(b, (j + 1) % 3), point(b, (j + 2) % 3));
    return CGAL::do_intersect(triangle(a), b_opposite) || CGAL::do_intersect(triangle(b), a_opposite);
}

/// The faces in slabs along the longest axis of the mesh, one slab per thread: a face belongs to
/// every slab its bounding box meets, so two faces whose boxes meet share a slab, and testing each
/// slab on its own finds every intersecting pair (some in two slabs).
std::vector<std::vector<CgalFace>> slabs_of(const CgalMesh& mesh, int count) {
    std::vector<CGAL::Bbox_3> boxes;
    boxes.reserve(mesh.number_of_faces());
    CGAL::Bbox_3 all;
    for (const CgalFace f : mesh.faces()) {
        CGAL::Bbox_3 box;
        for (const CgalVertex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) box += mesh.point(v).bbox();
        boxes.push_back(box);
        all += box;
    }
    int axis = 0;
    for (int d = 1; d < 3; ++d)
        if (all.max(d) - all.min(d) > all.max(axis) - all.min(axis)) axis = d;
    // Cuts at the quantiles of the box centres, so that the slabs hold as many faces each.
    std::vector<double> centres;
    centres.reserve(boxes.size());
    for (const CGAL::Bbox_3& box : boxes) centres.push_back(0.5 * (box.min(axis) + box.max(axis)));
    std::vector<double> cuts;
    for (int k = 1; k < count; ++k) {
        auto at = centres.begin() + std::ptrdiff_t(centres.size() * std::size_t(k) / std::size_t(count));
        std::nth_element(centres.begin(), at, centres.end());
        cuts.push_back(*at);
    }
    std::sort(cuts.begin(), cuts.end());
    std::vector<std::vector<CgalFace>> slabs(static_cast<std::size_t>(count));
    std::size_t index = 0;
    for (const CgalFace f : mesh.faces()) {
        const CGAL::Bbox_3& box = boxes[index++];
        const std::size_t first = std::size_t(std::upper_bound(cuts.begin(), cuts.end(), box.min(axis)) - cuts.begin());
        const std::size_t last = std::size_t(std::upper_bound(cuts.begin(), cuts.end(), box.max(axis)) - cuts.begin());
        for (std::size_t k = first; k <= last; ++k) slabs[k].push_back(f);
    }
    return slabs;
}

/// CGAL's self-intersection test, its work split in slabs over the available threads (CGAL's own
/// parallel version needs TBB). Pairs found twice are merged by the caller.
std::vector<std::pair<CgalFace, CgalFace>> cgal_self_intersections(const CgalMesh& mesh) {
    constexpr std::size_t faces_per_thread = 20000;  // below that, one slab: splitting costs more than it saves
    const int threads = int(std::min<std::size_t>(std::size_t(std::max(omp_get_max_threads(), 1)),
                                                  std::max<std::size_t>(mesh.number_of_faces() / faces_per_thread, 1)));
    std::vector<std::pair<CgalFace, CgalFace>> found;
    if (threads == 1) {
        CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(found));
        return found;
    }
    const std::vector<std::vector<CgalFace>> slabs = slabs_of(mesh, threads);
    std::vector<std::vector<std::pair<CgalFace, CgalFace>>> per_slab(slabs.size());
    bool failed = false;
#pragma omp parallel for schedule(static, 1) num_threads(threads)
    for (int k = 0; k < threads; ++k) {
        try {
            CGAL::Polygon_mesh_processing::self_intersections(slabs[std::size_t(k)], mesh,
                                                              std::back_inserter(per_slab[std::size_t(k)]));
        } catch (...) {
            failed = true;  // benign race: only ever set to true
        }
    }
    if (failed) throw Error("self-intersection test: CGAL failed");
    for (const auto& pairs : per_slab) found.insert(found.end(), pairs.begin(), pairs.end());
    return found;
}

}  // namespace

TriangleSelfIntersections triangle_self_intersections(const PointMatrix& vertices, const FaceMatrix& triangles) {
    check_triangle_mesh(vertices, triangles);
    std::vector<std::int64_t> triangle_of;
    const CgalMesh mesh = make_cgal_mesh(vertices, triangles, triangle_of);
    const std::vector<std::pair<CgalFace, CgalFace>> found = cgal_self_intersections(mesh);

    TriangleSelfIntersections result;
    for (const auto& [f, g] : found) {
        const std::int64_t a = triangle_of[f.idx()], b = triangle_of[g.idx()];
        if (a == b)
            result.degenerate.push_back(a);  // CGAL reports a degenerate face as the pair (f, f)
        // CGAL's candidates, decided by the index rule: CGAL's own rule for faces sharing vertices
        // sees only the adjacency of its mesh (none for a copied triangle) and assumes a manifold
        // neighbourhood, which the junctions of a label complex are not (around one junction
        // vertex of a 100-label map it reported two pairs that only touch where they share).
        else if (!meet_beyond_shared_indices(vertices, triangles, a, b))
            continue;
        else
            result.pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
    std::sort(result.pairs.begin(), result.pairs.end());
    result.pairs.erase(std::unique(result.pairs.begin(), result.pairs.end()), result.pairs.end());
    std::sort(result.degenerate.begin(), result.degenerate.end());
    result.degenerate.erase(std::unique(result.degenerate.begin(), result.degenerate.end()), result.degenerate.end());
    return result;
}

}  // namespace dsreg
