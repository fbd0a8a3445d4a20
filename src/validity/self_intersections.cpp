// dsreg — self-intersections of a triangle mesh: CGAL's box intersection finds the pairs of
// triangles whose boxes meet, CGAL's exact predicates decide each pair (the only translation unit
// that includes CGAL: its templates are heavy and compile once, here).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <omp.h>

#include <algorithm>
#include <iterator>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/mesh_validity.hpp"
#include "triangle_predicates.hpp"

namespace dsreg {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

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

/// A triangle's bounding box, named by its row; handled by pointer (ids from the box addresses),
/// as CGAL's own self-intersection test does, so that sorting moves pointers, not boxes.
using TriangleBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::int64_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;

Kernel::Point_3 corner(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t t, int k) {
    const Eigen::Index v = triangles(t, k);
    return Kernel::Point_3(vertices(v, 0), vertices(v, 1), vertices(v, 2));
}

/// The boxes in slabs along the longest axis of their union, one slab per thread: a box belongs
/// to every slab it meets, so two boxes that meet share a slab, and testing each slab on its own
/// finds every pair (some in two slabs).
std::vector<std::vector<const TriangleBox*>> slabs_of(const std::vector<TriangleBox>& boxes, int count) {
    CGAL::Bbox_3 all;
    for (const TriangleBox& box : boxes) all += box.bbox();
    int axis = 0;
    for (int d = 1; d < 3; ++d)
        if (all.max(d) - all.min(d) > all.max(axis) - all.min(axis)) axis = d;
    // Cuts at the quantiles of the box centres, so that the slabs hold as many boxes each.
    std::vector<double> centres;
    centres.reserve(boxes.size());
    for (const TriangleBox& box : boxes) centres.push_back(0.5 * (box.min_coord(axis) + box.max_coord(axis)));
    std::vector<double> cuts;
    for (int k = 1; k < count; ++k) {
        auto at = centres.begin() + std::ptrdiff_t(centres.size() * std::size_t(k) / std::size_t(count));
        std::nth_element(centres.begin(), at, centres.end());
        cuts.push_back(*at);
    }
    std::sort(cuts.begin(), cuts.end());
    std::vector<std::vector<const TriangleBox*>> slabs(static_cast<std::size_t>(count));
    for (const TriangleBox& box : boxes) {
        const std::size_t first = std::size_t(std::upper_bound(cuts.begin(), cuts.end(), box.min_coord(axis)) - cuts.begin());
        const std::size_t last = std::size_t(std::upper_bound(cuts.begin(), cuts.end(), box.max_coord(axis)) - cuts.begin());
        for (std::size_t k = first; k <= last; ++k) slabs[k].push_back(&box);
    }
    return slabs;
}

/// The pairs of boxes that meet (closed boxes: touching counts), decided by `meet(a, b)`: CGAL's
/// box intersection, its work split in slabs over the available threads (CGAL's own parallel
/// version needs TBB). Unsorted; a pair may appear twice.
template <class Meet>
std::vector<std::pair<std::int64_t, std::int64_t>> pairs_that_meet(const std::vector<TriangleBox>& boxes, Meet meet) {
    constexpr std::size_t boxes_per_thread = 20000;  // below that, one slab: splitting costs more than it saves
    constexpr std::ptrdiff_t cutoff = 2000;          // CGAL's self-intersection test's: brute force below that
    const int threads = int(std::min<std::size_t>(std::size_t(std::max(omp_get_max_threads(), 1)),
                                                  std::max<std::size_t>(boxes.size() / boxes_per_thread, 1)));
    std::vector<std::vector<const TriangleBox*>> slabs = slabs_of(boxes, threads);
    std::vector<std::vector<std::pair<std::int64_t, std::int64_t>>> per_slab(slabs.size());
    bool failed = false;
#pragma omp parallel for schedule(static, 1) num_threads(threads) if (threads > 1)
    for (int k = 0; k < int(slabs.size()); ++k) {
        try {
            auto& found = per_slab[std::size_t(k)];
            CGAL::box_self_intersection_d(slabs[std::size_t(k)].begin(), slabs[std::size_t(k)].end(),
                                          [&](const TriangleBox* a, const TriangleBox* b) {
                                              if (meet(a->info(), b->info()))
                                                  found.emplace_back(std::min(a->info(), b->info()), std::max(a->info(), b->info()));
                                          },
                                          cutoff);
        } catch (...) {
            failed = true;  // benign race: only ever set to true
        }
    }
    if (failed) throw Error("self-intersection test: CGAL failed");
    std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
    for (const auto& found : per_slab) pairs.insert(pairs.end(), found.begin(), found.end());
    return pairs;
}

}  // namespace

namespace validity_internal {

bool triangle_is_degenerate(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t t) {
    return CGAL::collinear(corner(vertices, triangles, t, 0), corner(vertices, triangles, t, 1), corner(vertices, triangles, t, 2));
}

// The rule CGAL applies to adjacent faces, on the indices (a triangle of a non-manifold edge,
// such as a junction of a label complex, shares its edge with several others). Sharing an edge,
// they intersect when coplanar and on the same side of it; sharing a vertex, when the edge of
// either opposite that vertex meets the other triangle; sharing nothing, when they meet.
bool triangles_meet_beyond_shared_indices(const PointMatrix& vertices, const FaceMatrix& triangles, std::int64_t a,
                                          std::int64_t b) {
    const auto point = [&](std::int64_t t, int k) { return corner(vertices, triangles, t, k); };
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
    const Kernel::Point_3 p = point(a, i), a1 = point(a, (i + 1) % 3), a2 = point(a, (i + 2) % 3);
    const Kernel::Point_3 b1 = point(b, (j + 1) % 3), b2 = point(b, (j + 2) % 3);
    // If the far corners of either triangle lie strictly on one side of the other's plane, that
    // triangle meets the plane at p alone, which is on neither opposite edge: no meeting (the
    // usual case of neighbouring faces, decided by two orientations instead of two
    // triangle–segment tests).
    const auto one_side = [](CGAL::Orientation s, CGAL::Orientation t) { return s == t && s != CGAL::COPLANAR; };
    if (one_side(CGAL::orientation(p, a1, a2, b1), CGAL::orientation(p, a1, a2, b2))) return false;
    if (one_side(CGAL::orientation(p, b1, b2, a1), CGAL::orientation(p, b1, b2, a2))) return false;
    return CGAL::do_intersect(triangle(a), Kernel::Segment_3(b1, b2)) || CGAL::do_intersect(triangle(b), Kernel::Segment_3(a1, a2));
}

}  // namespace validity_internal

TriangleSelfIntersections triangle_self_intersections(const PointMatrix& vertices, const FaceMatrix& triangles) {
    check_triangle_mesh(vertices, triangles);
    TriangleSelfIntersections result;
    std::vector<char> degenerate(std::size_t(triangles.rows()), 0);
#pragma omp parallel for schedule(static) if (triangles.rows() > 20000)
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
        degenerate[std::size_t(t)] = validity_internal::triangle_is_degenerate(vertices, triangles, t);
    // Degenerate triangles are reported as such and take part in no pair.
    std::vector<TriangleBox> boxes;
    boxes.reserve(std::size_t(triangles.rows()));
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
        if (degenerate[std::size_t(t)]) {
            result.degenerate.push_back(t);
            continue;
        }
        CGAL::Bbox_3 box;
        for (int k = 0; k < 3; ++k) box += corner(vertices, triangles, t, k).bbox();
        boxes.emplace_back(box, std::int64_t(t));
    }
    result.pairs = pairs_that_meet(boxes, [&](std::int64_t a, std::int64_t b) {
        return validity_internal::triangles_meet_beyond_shared_indices(vertices, triangles, a, b);
    });
    std::sort(result.pairs.begin(), result.pairs.end());
    result.pairs.erase(std::unique(result.pairs.begin(), result.pairs.end()), result.pairs.end());
    return result;
}

}  // namespace dsreg
