// Validity of a mesh (mesh_validity.hpp): CGAL's self-intersection test on constructed cases
// whose answer is known exactly, the meaning of "shares an edge / a vertex", the fold test, and
// clean closed surfaces.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_validity.hpp"
#include "../src/validity/incremental_validity.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/normals.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

using Pairs = std::vector<std::pair<std::int64_t, std::int64_t>>;

PointMatrix points(std::initializer_list<std::array<double, 3>> rows) {
    PointMatrix p(Eigen::Index(rows.size()), 3);
    Eigen::Index i = 0;
    for (const auto& r : rows) p.row(i++) << r[0], r[1], r[2];
    return p;
}

FaceMatrix faces(std::initializer_list<std::vector<std::int32_t>> rows) {
    FaceMatrix f(Eigen::Index(rows.size()), Eigen::Index(rows.begin()->size()));
    Eigen::Index i = 0;
    for (const auto& r : rows) {
        for (std::size_t k = 0; k < r.size(); ++k) f(i, Eigen::Index(k)) = r[k];
        ++i;
    }
    return f;
}

/// The closed surface of a voxel set, with its pointels as vertices (the digital surface).
DigitalSurface voxels_surface(std::initializer_list<Index3> voxels, Connectivity connectivity = Connectivity::TwentySix) {
    return extract_digital_surface(test::make_voxels({4, 4, 4}, voxels), connectivity);
}

TEST(SelfIntersections, TrianglePiercingOneTriangleOfASquare) {
    // Square (0,1,2,3) of side 2 in z = 0 as triangles 0 = (0,1,2) (below the diagonal y = x)
    // and 1 = (0,2,3); triangle 2 crosses z = 0 at x = 1.5, y = 0.5 only: it pierces triangle 0.
    const PointMatrix p = points({{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0},
                                  {1.5, 0.5, -1}, {1.5, 0.5, 1}, {1.8, 0.2, 1}});
    const TriangleSelfIntersections found = triangle_self_intersections(p, faces({{0, 1, 2}, {0, 2, 3}, {4, 5, 6}}));
    EXPECT_EQ(found.pairs, (Pairs{{0, 2}}));
    EXPECT_TRUE(found.degenerate.empty());
}

TEST(SelfIntersections, SharedEdgeCountsOnlyWhenFoldedOntoItself) {
    // Triangles (0,1,2) and (1,0,3) share the edge 0–1.
    const FaceMatrix pair = faces({{0, 1, 2}, {1, 0, 3}});
    const PointMatrix flat = points({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}});
    const PointMatrix dihedral = points({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0.3, 1}});
    const PointMatrix folded = points({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0.5, 0}});  // on top of the first
    EXPECT_TRUE(triangle_self_intersections(flat, pair).pairs.empty());
    EXPECT_TRUE(triangle_self_intersections(dihedral, pair).pairs.empty());
    EXPECT_EQ(triangle_self_intersections(folded, pair).pairs, (Pairs{{0, 1}}));
}

TEST(SelfIntersections, SharedVertexCountsOnlyWhenTheyMeetElsewhere) {
    // Triangles (0,1,2) and (0,3,4) share vertex 0.
    const FaceMatrix pair = faces({{0, 1, 2}, {0, 3, 4}});
    const PointMatrix apart = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0.2}, {0, -1, 0.2}});
    // The second triangle passes through the first one's interior.
    const PointMatrix crossing = points({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {1, 1, -1}, {1, 1, 1}});
    EXPECT_TRUE(triangle_self_intersections(apart, pair).pairs.empty());
    EXPECT_EQ(triangle_self_intersections(crossing, pair).pairs, (Pairs{{0, 1}}));
}

TEST(SelfIntersections, SharedVertexWithCornersInOrAcrossThePlane) {
    // Triangle 0 = (0,1,2) in z = 0 and triangle 1 = (0,3,4) sharing vertex 0. Far corners
    // strictly on one side of the other's plane decide "apart" at once; corners in the plane or on
    // both sides need the full test, which must still tell touching at 0 from meeting elsewhere.
    const FaceMatrix pair = faces({{0, 1, 2}, {0, 3, 4}});
    const auto meets = [&](std::array<double, 3> c3, std::array<double, 3> c4) {
        const PointMatrix p = points({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, c3, c4});
        return !triangle_self_intersections(p, pair).pairs.empty();
    };
    EXPECT_FALSE(meets({-1, 0, 0}, {0, -1, 0}));        // coplanar, on the other side of vertex 0
    EXPECT_TRUE(meets({1, 0.2, 0}, {0.2, 1, 0}));        // coplanar, inside triangle 0
    EXPECT_FALSE(meets({-1, -1, 0}, {-1, -2, 1}));       // one corner in the plane outside, one above
    EXPECT_TRUE(meets({0.5, 0.5, 0}, {-1, -2, 1}));      // one corner in the plane inside triangle 0
    EXPECT_FALSE(meets({-1, 0.5, -1}, {-1, 0.5, 1}));    // across the plane, beside triangle 0
    EXPECT_TRUE(meets({0.5, 0.5, -1}, {0.5, 0.5, 1}));   // across the plane, through triangle 0
    EXPECT_FALSE(meets({1, 1, 0.5}, {0.5, 2, 0.5}));     // above, strictly on one side
    EXPECT_TRUE(meets({3, 0, 1}, {3, 0, -1}));           // triangle 0's edge 1–2 passes through triangle 1
}

TEST(SelfIntersections, TouchingAtCoincidentVerticesOfDistinctIndicesCounts) {
    // Vertices 0 and 3 are at the same place: the two triangles touch there without sharing it.
    const PointMatrix p = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {-1, 0, 0.5}, {0, -1, 0.5}});
    EXPECT_EQ(triangle_self_intersections(p, faces({{0, 1, 2}, {3, 4, 5}})).pairs, (Pairs{{0, 1}}));
    // The same triangles sharing the index: no intersection.
    EXPECT_TRUE(triangle_self_intersections(p, faces({{0, 1, 2}, {0, 4, 5}})).pairs.empty());
}

TEST(SelfIntersections, DegenerateTriangleIsReported) {
    const PointMatrix p = points({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}});
    const TriangleSelfIntersections found = triangle_self_intersections(p, faces({{3, 4, 5}, {0, 1, 2}}));
    EXPECT_EQ(found.degenerate, (std::vector<std::int64_t>{1}));
    EXPECT_TRUE(found.pairs.empty());
}

TEST(SelfIntersections, NonManifoldEdgeIsSharedByIndexAsAnyOther) {
    // Three triangles on the edge 0–1 (a junction of a label complex): the third cannot join the
    // edge structure, yet meets the first two only along the edge they share by index.
    const PointMatrix p = points({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0.1}, {0.5, 0, 1}, {0.3, 0.5, 0},
                                  {0.5, 0.2, -1}, {0.5, 0.5, 0.5}, {0.2, 0.6, -0.5}, {0.8, 0.6, 0.5}});
    EXPECT_TRUE(triangle_self_intersections(p, faces({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}})).pairs.empty());
    // A third triangle folded onto the first (coplanar, same side of the edge) overlaps it.
    EXPECT_EQ(triangle_self_intersections(p, faces({{0, 1, 2}, {1, 0, 3}, {0, 1, 5}})).pairs, (Pairs{{0, 2}}));
    // A third triangle on the edge that crosses a fourth one sharing only vertex 0 with it.
    EXPECT_EQ(triangle_self_intersections(p, faces({{0, 1, 2}, {1, 0, 3}, {0, 1, 6}, {0, 8, 9}})).pairs,
              (Pairs{{0, 3}}));
}

TEST(SelfIntersections, SheetsMeetingAtAJunctionVertexOnlyTouchWhereTheyShare) {
    // Eight quads around vertex 6, a junction of a 100-label map where four sheets meet (taken
    // from the repaired mesh of bench/labels_bench.sh's blobs, positions rounded to 1e-6): no two
    // of them meet beyond what they share by index, yet CGAL's rule for faces sharing a vertex,
    // which assumes a manifold neighbourhood, reported two pairs here, and the repair, holding
    // every vertex at its target, could not clear them.
    const PointMatrix p = points({{71.386939, 99.522667, 73.627443}, {70.464995, 99.324892, 73.84026}, {71.522982, 100.469877, 73.567405},
                                  {70.640493, 100.450341, 73.747126}, {72.290327, 100.550556, 73.287738}, {72.5, 101.5, 73.5},
                                  {71.5, 101.5, 73.5}, {72.5, 102.5, 73.5}, {71.5, 102.5, 73.5}, {70.519932, 100.294542, 74.439841},
                                  {71.385475, 100.551611, 74.248734}, {70.5, 101.5, 73.5}, {71.5, 101.5, 74.5},
                                  {70.61792, 101.493865, 74.612204}, {72.331064, 101.590957, 74.475525}, {70.5, 102.5, 73.5},
                                  {71.429289, 102.5, 74.429289}});
    const FaceMatrix quads = faces({{1, 0, 2, 3}, {6, 5, 7, 8}, {3, 11, 6, 2}, {9, 10, 12, 13}, {6, 12, 14, 5}, {2, 6, 5, 4},
                                    {6, 8, 16, 12}, {11, 15, 8, 6}});
    const FaceMatrix triangles = mesh_triangles(p, quads);
    for (Eigen::Index a = 0; a < triangles.rows(); ++a)
        for (Eigen::Index b = a + 1; b < triangles.rows(); ++b) {
            FaceMatrix pair(2, 3);
            pair << triangles.row(a), triangles.row(b);
            ASSERT_TRUE(triangle_self_intersections(p, pair).pairs.empty()) << "triangles " << a << " and " << b;
        }
    EXPECT_TRUE(triangle_self_intersections(p, triangles).pairs.empty());
    EXPECT_TRUE(check_mesh_validity(p, quads).valid());
}

TEST(SelfIntersections, RejectsBadInput) {
    const PointMatrix p = points({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    EXPECT_THROW(triangle_self_intersections(p, faces({{0, 1, 3}})), Error);
    EXPECT_THROW(triangle_self_intersections(p, faces({{0, 1, 2, 0}})), Error);
    PointMatrix bad = p;
    bad(1, 2) = std::nan("");
    EXPECT_THROW(triangle_self_intersections(bad, faces({{0, 1, 2}})), Error);
}

TEST(MeshValidity, DigitalCubeAndSphereAreValid) {
    // Flat unit squares split in two: coplanar neighbours share edges and are not intersections.
    const DigitalSurface cube = voxels_surface({{1, 1, 1}, {2, 1, 1}, {1, 2, 1}, {2, 2, 1}});
    const MeshValidity v = check_mesh_validity(cube.vertices, cube.quads, trivial_normals(cube));
    EXPECT_TRUE(v.valid());
    EXPECT_EQ(v.triangles, 2 * cube.face_count());

    // A smooth closed sphere: the digital ball's vertices pushed onto the sphere of radius 6.
    const BinaryVolume ball = test::make_ball(16, 6, 7.5);
    const DigitalSurface surface = extract_digital_surface(ball, Connectivity::TwentySix);
    PointMatrix on_sphere = surface.vertices;
    const Eigen::RowVector3d centre(7.5, 7.5, 7.5);
    for (Eigen::Index i = 0; i < on_sphere.rows(); ++i)
        on_sphere.row(i) = centre + 6.0 * (on_sphere.row(i) - centre).normalized();
    const PointMatrix outward = face_normals(on_sphere, surface.quads);
    const MeshValidity sphere = check_mesh_validity(on_sphere, surface.quads, outward);
    EXPECT_TRUE(sphere.valid()) << sphere.intersecting_pairs << " pairs, " << sphere.folded_faces << " folded";
    EXPECT_EQ(sphere.faces, surface.face_count());
}

TEST(SelfIntersections, ClosedSurfaceInAnyTriangleOrderIsClean) {
    // A closed sphere whose triangles come in random order is clean: no pair depends on the order
    // in which the triangles are given (nor on which of two triangles comes first).
    const DigitalSurface surface = extract_digital_surface(test::make_ball(12, 4, 5.5), Connectivity::TwentySix);
    PointMatrix on_sphere = surface.vertices;
    for (Eigen::Index i = 0; i < on_sphere.rows(); ++i)
        on_sphere.row(i) = Eigen::RowVector3d(5.5, 5.5, 5.5) + 4.0 * (on_sphere.row(i) - Eigen::RowVector3d(5.5, 5.5, 5.5)).normalized();
    const FaceMatrix triangles = mesh_triangles(on_sphere, surface.quads);
    std::vector<Eigen::Index> order(std::size_t(triangles.rows()));
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937(3));
    FaceMatrix shuffled(triangles.rows(), 3);
    for (std::size_t t = 0; t < order.size(); ++t) shuffled.row(Eigen::Index(t)) = triangles.row(order[t]);
    const TriangleSelfIntersections found = triangle_self_intersections(on_sphere, shuffled);
    EXPECT_TRUE(found.pairs.empty()) << found.pairs.size() << " pairs";
    EXPECT_TRUE(found.degenerate.empty());
}

TEST(SelfIntersections, SplittingTheWorkOverThreadsFindsTheSamePairs) {
    // Two spheres of radius 24 (about 30000 triangles each), the second moved by 5 along x: large
    // enough for the test to be split in slabs, one per thread.
    const DigitalSurface surface = extract_digital_surface(test::make_ball(52, 24, 25.5), Connectivity::TwentySix);
    const Eigen::RowVector3d centre(25.5, 25.5, 25.5);
    PointMatrix sphere = surface.vertices;
    for (Eigen::Index i = 0; i < sphere.rows(); ++i) sphere.row(i) = centre + 24.0 * (sphere.row(i) - centre).normalized();
    PointMatrix both(2 * sphere.rows(), 3);
    both << sphere, (sphere.rowwise() + Eigen::RowVector3d(5, 0, 0));
    FaceMatrix quads(2 * surface.face_count(), 4);
    quads << surface.quads, (surface.quads.array() + std::int32_t(sphere.rows())).matrix();
    const FaceMatrix triangles = mesh_triangles(both, quads);
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const TriangleSelfIntersections one = triangle_self_intersections(both, triangles);
    omp_set_num_threads(std::max(threads, 2));
    const TriangleSelfIntersections two = triangle_self_intersections(both, triangles);
    omp_set_num_threads(threads);
    EXPECT_GT(one.pairs.size(), 100u);
    EXPECT_EQ(one.pairs, two.pairs);
    EXPECT_EQ(one.degenerate, two.degenerate);
}

/// Moves random batches of vertices of `surface` (some far enough to fold faces and make the
/// surface cut through itself, some onto a neighbour: degenerate triangles, some back to where they
/// were), flips the field on some faces, and checks after each step that the incremental check,
/// which tests only what moved, reports what the check of the whole mesh reports. Returns the
/// number of invalid states seen.
int incremental_against_whole(const DigitalSurface& surface, unsigned seed) {
    PointMatrix x = surface.vertices;
    PointMatrix field = trivial_normals(surface);
    validity_internal::IncrementalValidity tracker(x, surface.quads, field);
    std::mt19937 random(seed);
    std::uniform_int_distribution<std::int32_t> vertex(0, std::int32_t(x.rows()) - 1);
    std::uniform_int_distribution<std::int32_t> face(0, std::int32_t(surface.face_count()) - 1);
    std::normal_distribution<double> step(0.0, 0.6);
    int invalid = 0;
    for (int batch = 0; batch < 40; ++batch) {
        std::vector<std::int32_t> moved, refield;
        const int count = batch % 3 == 0 ? 150 : 4;
        for (int k = 0; k < count; ++k) {
            const std::int32_t v = vertex(random);
            moved.push_back(v);
            for (int d = 0; d < 3; ++d) x(v, d) += step(random);
        }
        if (batch % 5 == 4)
            for (const std::int32_t v : moved) x.row(v) = surface.vertices.row(v);
        if (batch % 7 == 6) {
            const std::int32_t f = face(random);
            moved.push_back(surface.quads(f, 0));
            x.row(surface.quads(f, 0)) = x.row(surface.quads(f, 1));
        }
        if (batch % 4 == 1)
            for (int k = 0; k < 3; ++k) {
                const std::int32_t f = face(random);
                field.row(f) *= -1;
                refield.push_back(f);
            }
        tracker.update(x, moved, refield, field);
        const MeshValidity incremental = tracker.validity(), whole = check_mesh_validity(x, surface.quads, field);
        EXPECT_EQ(incremental.intersecting_pairs, whole.intersecting_pairs) << "batch " << batch;
        EXPECT_EQ(incremental.degenerate_triangles, whole.degenerate_triangles) << "batch " << batch;
        EXPECT_EQ(incremental.intersecting_faces, whole.intersecting_faces) << "batch " << batch;
        EXPECT_EQ(incremental.folded, whole.folded) << "batch " << batch;
        invalid += whole.valid() ? 0 : 1;
    }
    return invalid;
}

TEST(IncrementalValidity, ReportsWhatTheWholeCheckReportsAfterEveryMove) {
    const DigitalSurface ball = extract_digital_surface(test::make_ball(14, 5, 6.5), Connectivity::TwentySix);
    EXPECT_GT(incremental_against_whole(ball, 7), 30);
    // A label complex: junction edges shared by three faces and more.
    const DigitalSurface labels = extract_digital_surface(test::sectors_and_small_parts(), Connectivity::TwentySix);
    EXPECT_GT(incremental_against_whole(labels, 11), 30);
}

TEST(MeshValidity, OverlappingCubesIntersectOnExactlyTheFacesThatCross) {
    // Unit cubes A = [−½,½]³ (the voxel at the origin; faces 0–5) and B = A + (½,½,½) (faces
    // 6–11): A's far faces (x, y or z = ½) cross B's near faces (x, y or z = 0); no other pair meets.
    const DigitalSurface one = voxels_surface({{0, 0, 0}});
    PointMatrix p(2 * one.vertex_count(), 3);
    p << one.vertices, (one.vertices.rowwise() + Eigen::RowVector3d(0.5, 0.5, 0.5));
    FaceMatrix quads(2 * one.face_count(), 4);
    quads << one.quads, (one.quads.array() + std::int32_t(one.vertex_count())).matrix();
    std::vector<std::int32_t> expected;
    for (Eigen::Index f = 0; f < one.face_count(); ++f) {
        if (one.surfels[std::size_t(f)].sign > 0) expected.push_back(std::int32_t(f));   // A's far faces
        if (one.surfels[std::size_t(f)].sign < 0) expected.push_back(std::int32_t(f + one.face_count()));  // B's near faces
    }
    std::sort(expected.begin(), expected.end());
    const MeshValidity v = check_mesh_validity(p, quads);
    EXPECT_FALSE(v.valid());
    EXPECT_EQ(v.intersecting_faces, expected);
    EXPECT_EQ(v.folded_faces, 0);  // no field given: no fold test
}

TEST(MeshValidity, EdgeTouchingVoxelsTouchThemselves) {
    // Two voxels sharing only an edge, kept apart (6-connectivity): their digital surface has two
    // vertices per pointel of that edge (digital_surface.hpp), at the same places, so the surface
    // touches itself there.
    const DigitalSurface s = voxels_surface({{1, 1, 1}, {2, 2, 1}}, Connectivity::Six);
    ASSERT_GT(s.split_pointel_count, 0);
    const MeshValidity v = check_mesh_validity(s.vertices, s.quads, trivial_normals(s));
    EXPECT_GT(v.intersecting_pairs, 0);
    EXPECT_EQ(v.folded_faces, 0);
    EXPECT_FALSE(v.valid());
}

TEST(MeshValidity, FoldTestLooksAtBothSplitsOfAQuad) {
    // Quad (0,1,2,3) folded along its longer diagonal 1–3 only: vertex 2 lies on the far side of
    // the line 1–3, so abd = (0,1,3) faces +z but bcd = (1,2,3) faces −z, while the split along
    // the shorter diagonal 0–2 gives two triangles facing +z.
    const PointMatrix p = points({{0, 0, 0}, {2, 0, 0}, {0.7, 0.7, 0}, {0, 2, 0}});
    const FaceMatrix quad = faces({{0, 1, 2, 3}});
    const PointMatrix up = points({{0, 0, 1}});
    ASSERT_TRUE(triangle_self_intersections(p, mesh_triangles(p, quad)).pairs.empty());
    ASSERT_EQ(mesh_triangles(p, quad), faces({{0, 1, 2}, {0, 2, 3}}));  // the shorter diagonal, 0–2
    EXPECT_EQ(faces_folded_against_field(p, quad, up), (std::vector<std::int32_t>{0}));
}

TEST(MeshValidity, FoldTestLooksAtEachTriangleOfTheSplit) {
    // Quad (0,1,2,3), shorter diagonal 0–2: triangle (0,1,2) faces +z, vertex 3 is pulled across
    // the diagonal so that (0,2,3) faces (0.5,−0.5,−0.6). Their mean normal still has a positive
    // z, so the mean-normal count misses the fold.
    const PointMatrix p = points({{0, 0, 0}, {3, 0, 0}, {1, 1, 0}, {1.2, 0.6, 0.5}});
    const FaceMatrix quad = faces({{0, 1, 2, 3}});
    const PointMatrix up = points({{0, 0, 1}});
    ASSERT_EQ(count_faces_against_field(p, quad, up), 0);
    EXPECT_EQ(faces_folded_against_field(p, quad, up), (std::vector<std::int32_t>{0}));
    EXPECT_EQ(faces_folded_against_field(p, quad, PointMatrix(-up)), (std::vector<std::int32_t>{0}));
    const PointMatrix flat = points({{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}});
    EXPECT_TRUE(faces_folded_against_field(flat, quad, up).empty());
    EXPECT_EQ(check_mesh_validity(flat, quad, PointMatrix(-up)).folded, (std::vector<std::int32_t>{0}));
    EXPECT_THROW(faces_folded_against_field(flat, quad, PointMatrix(2, 3)), Error);
}

TEST(MeshValidity, FoldedCornersAreTheApexesOfTheTurnedTriangles) {
    const auto corners = [](const PointMatrix& p) {
        return std::array<Eigen::Vector3d, 4>{p.row(0).transpose(), p.row(1).transpose(), p.row(2).transpose(),
                                              p.row(3).transpose()};
    };
    const Eigen::Vector3d up(0, 0, 1);
    const PointMatrix square = points({{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}});
    EXPECT_EQ(folded_corners(corners(square), up), (std::array<bool, 4>{false, false, false, false}));
    EXPECT_EQ(folded_corners(corners(square), -up), (std::array<bool, 4>{true, true, true, true}));  // turned over
    // Vertex 2 beyond the diagonal 1–3 (a reflex corner): only corner 2 is folded.
    const PointMatrix reflex = points({{0, 0, 0}, {2, 0, 0}, {0.7, 0.7, 0}, {0, 2, 0}});
    EXPECT_EQ(folded_corners(corners(reflex), up), (std::array<bool, 4>{false, false, true, false}));
    // Vertex 3 lifted across the diagonal 0–2: triangle (2,3,0) faces (0.5,−0.5,−0.6), the others +z.
    const PointMatrix lifted = points({{0, 0, 0}, {3, 0, 0}, {1, 1, 0}, {1.2, 0.6, 0.5}});
    EXPECT_EQ(folded_corners(corners(lifted), up), (std::array<bool, 4>{false, false, false, true}));
    // Vertex 2 on the diagonal 1–3: no area at that corner counts as folded, as in the check.
    const PointMatrix flat_corner = points({{0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {0, 2, 0}});
    EXPECT_EQ(folded_corners(corners(flat_corner), up), (std::array<bool, 4>{false, false, true, false}));
    // The check calls a quad folded exactly when one of its corners is.
    for (const PointMatrix* p : {&square, &reflex, &lifted, &flat_corner}) {
        const std::array<bool, 4> folded = folded_corners(corners(*p), up);
        const bool any = std::find(folded.begin(), folded.end(), true) != folded.end();
        EXPECT_EQ(faces_folded_against_field(*p, faces({{0, 1, 2, 3}}), points({{0, 0, 1}})).size(), any ? 1u : 0u);
    }
}

}  // namespace
}  // namespace dsreg
