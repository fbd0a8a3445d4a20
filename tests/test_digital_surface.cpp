#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <random>

#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

/// Index m of the edge of face g that runs from vertex `from` to vertex `to`, or −1.
int edge_of(const DigitalSurface& s, std::int64_t g, std::int32_t from, std::int32_t to) {
    for (int m = 0; m < 4; ++m)
        if (s.quads(g, m) == from && s.quads(g, (m + 1) % 4) == to) return m;
    return -1;
}

/// Every edge has exactly two faces traversing it in opposite directions, and the faces around
/// every vertex form one single cycle (a disc).
void expect_closed_manifold(const DigitalSurface& s) {
    const std::int64_t m = s.face_count();
    std::vector<std::int64_t> corners_at(std::size_t(s.vertex_count()), 0);
    for (std::int64_t f = 0; f < m; ++f)
        for (int e = 0; e < 4; ++e) {
            ++corners_at[std::size_t(s.quads(f, e))];
            const std::int64_t g = s.adjacent_face(f, e);
            ASSERT_NE(g, f);
            const int back = edge_of(s, g, s.quads(f, (e + 1) % 4), s.quads(f, e));
            ASSERT_GE(back, 0) << "face " << f << " edge " << e << ": the adjacent face does not share it reversed";
            ASSERT_EQ(s.adjacent_face(g, back), f) << "edge adjacency is not symmetric";
        }
    for (std::int64_t f = 0; f < m; ++f)
        for (int k = 0; k < 4; ++k) {
            // Walk around the vertex of corner (f,k): leave through the edge entering the corner.
            const std::int32_t v = s.quads(f, k);
            std::int64_t face = f;
            int corner = k;
            std::int64_t steps = 0;
            do {
                const int entering = (corner + 3) % 4;
                const std::int64_t g = s.adjacent_face(face, entering);
                const int back = edge_of(s, g, v, s.quads(face, entering));
                ASSERT_GE(back, 0);
                face = g;
                corner = back;
                ASSERT_EQ(s.quads(face, corner), v);
                ++steps;
                ASSERT_LE(steps, corners_at[std::size_t(v)]);
            } while (face != f || corner != k);
            EXPECT_EQ(steps, corners_at[std::size_t(v)]) << "vertex " << v << " has more than one umbrella";
        }
}

/// No two faces run along the same two vertices in the same direction (which would pinch every
/// mesh of the surface along a segment, see digital_surface.hpp).
void expect_no_pinched_edge(const DigitalSurface& s) {
    std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        for (int e = 0; e < 4; ++e) {
            const int count = ++uses[{s.quads(f, e), s.quads(f, (e + 1) % 4)}];
            ASSERT_EQ(count, 1) << "vertices " << s.quads(f, e) << " -> " << s.quads(f, (e + 1) % 4) << " on two faces";
        }
}

/// The right-hand normal of each quad equals the outward axis normal of its surfel.
void expect_outward_orientation(const DigitalSurface& s) {
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d a = s.vertices.row(s.quads(f, 0)), b = s.vertices.row(s.quads(f, 1)),
                              c = s.vertices.row(s.quads(f, 2)), d = s.vertices.row(s.quads(f, 3));
        const Eigen::Vector3d n = (c - a).cross(d - b).normalized();
        ASSERT_NEAR((n - s.surfels[std::size_t(f)].trivial_normal()).norm(), 0.0, 1e-12) << "face " << f;
    }
}

TEST(DigitalSurface, SingleVoxelIsACube) {
    const auto s = extract_digital_surface(test::make_voxels({3, 3, 3}, {{1, 1, 1}}), Connectivity::Six);
    EXPECT_EQ(s.face_count(), 6);
    EXPECT_EQ(s.vertex_count(), 8);
    EXPECT_EQ(s.component_count, 1);
    EXPECT_EQ(component_euler_characteristics(s), std::vector<std::int64_t>{2});
    expect_closed_manifold(s);
    expect_outward_orientation(s);
    // Pointels sit at half-integers for spacing 1, origin 0: the cube spans [0.5, 1.5]^3.
    EXPECT_DOUBLE_EQ(s.vertices.minCoeff(), 0.5);
    EXPECT_DOUBLE_EQ(s.vertices.maxCoeff(), 1.5);
}

TEST(DigitalSurface, ObjectTouchingTheDomainBorderIsClosed) {
    const auto s = extract_digital_surface(test::make_volume({2, 3, 1}, [](double, double, double) { return true; }),
                                           Connectivity::Six);
    EXPECT_EQ(s.face_count(), 2 * (2 * 3 + 3 * 1 + 2 * 1));
    expect_closed_manifold(s);
    EXPECT_EQ(component_euler_characteristics(s), std::vector<std::int64_t>{2});
}

TEST(DigitalSurface, BallIsASphere) {
    const auto s = extract_digital_surface(test::make_ball(16, 6.3, 7.5), Connectivity::TwentySix);
    expect_closed_manifold(s);
    expect_outward_orientation(s);
    EXPECT_EQ(s.component_count, 1);
    EXPECT_EQ(component_euler_characteristics(s), std::vector<std::int64_t>{2});
}

TEST(DigitalSurface, TorusHasGenusOne) {
    const auto torus = test::make_volume({24, 24, 10}, [](double x, double y, double z) {
        const double q = std::hypot(x - 11.5, y - 11.5) - 7.0;
        return q * q + (z - 4.5) * (z - 4.5) <= 2.6 * 2.6;
    });
    for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
        const auto s = extract_digital_surface(torus, c);
        expect_closed_manifold(s);
        EXPECT_EQ(component_euler_characteristics(s), std::vector<std::int64_t>{0});
    }
}

TEST(DigitalSurface, VoxelsTouchingByAnEdge) {
    const auto volume = test::make_voxels({4, 4, 4}, {{1, 1, 1}, {2, 2, 1}});
    const auto six = extract_digital_surface(volume, Connectivity::Six);
    expect_closed_manifold(six);
    EXPECT_EQ(six.component_count, 2);  // kept apart: two cubes
    EXPECT_EQ(six.vertex_count(), 16);
    EXPECT_EQ(six.split_pointel_count, 2);
    EXPECT_EQ(component_euler_characteristics(six), (std::vector<std::int64_t>{2, 2}));

    // Joining them along the edge alone would pinch the surface there (both edges of the linel
    // between the same two vertices), so 26-connectivity keeps them apart too.
    const auto joined = extract_digital_surface(volume, Connectivity::TwentySix);
    expect_closed_manifold(joined);
    expect_no_pinched_edge(joined);
    EXPECT_EQ(joined.component_count, 2);
    EXPECT_EQ(joined.vertex_count(), 16);
    EXPECT_EQ(joined.split_pointel_count, 2);
    EXPECT_EQ(component_euler_characteristics(joined), (std::vector<std::int64_t>{2, 2}));
}

TEST(DigitalSurface, EdgeJoinedBelowAFullLayerKeepsTheConnectivityPairing) {
    // Voxels (1,1,1) and (2,2,1) touch by the z-linel at x = y = 1.5, under a full 2×2 layer at
    // z = 2: the top end pointel of the linel gets two vertices under one pairing, the bottom end
    // under the other, so no pairing pinches and each connectivity keeps its own. Joining (26)
    // splits the top end: the bottom end (1.5, 1.5, 0.5) keeps one vertex; apart (6), two.
    const auto volume =
        test::make_voxels({4, 4, 4}, {{1, 1, 1}, {2, 2, 1}, {1, 1, 2}, {2, 1, 2}, {1, 2, 2}, {2, 2, 2}});
    const auto vertices_at_bottom_end = [](const DigitalSurface& s) {
        int count = 0;
        for (std::int64_t i = 0; i < s.vertex_count(); ++i)
            count += (s.vertices.row(i) - Eigen::RowVector3d(1.5, 1.5, 0.5)).norm() == 0 ? 1 : 0;
        return count;
    };
    for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
        const auto s = extract_digital_surface(volume, c);
        expect_closed_manifold(s);
        expect_no_pinched_edge(s);
        EXPECT_EQ(s.component_count, 1);
        EXPECT_EQ(vertices_at_bottom_end(s), c == Connectivity::TwentySix ? 1 : 2);
    }
}

TEST(DigitalSurface, VoxelsTouchingByACorner) {
    const auto volume = test::make_voxels({4, 4, 4}, {{1, 1, 1}, {2, 2, 2}});
    for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
        const auto s = extract_digital_surface(volume, c);
        expect_closed_manifold(s);
        EXPECT_EQ(s.vertex_count(), 16);  // the shared pointel gets one vertex per umbrella
        EXPECT_EQ(s.split_pointel_count, 1);
        EXPECT_EQ(s.component_count, 2);
    }
}

TEST(DigitalSurface, CavityIsASecondComponentFacingInwards) {
    const auto shell = test::make_volume({7, 7, 7}, [](double x, double y, double z) {
        return x >= 1 && x <= 5 && y >= 1 && y <= 5 && z >= 1 && z <= 5 && !(x == 3 && y == 3 && z == 3);
    });
    const auto s = extract_digital_surface(shell, Connectivity::Six);
    expect_closed_manifold(s);
    expect_outward_orientation(s);
    EXPECT_EQ(s.component_count, 2);
    EXPECT_EQ(s.face_count(), 6 * 25 + 6);
}

TEST(DigitalSurface, RandomVolumesAreClosedManifolds) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 20; ++trial) {
        std::bernoulli_distribution coin(0.3 + 0.02 * trial);
        const auto volume = test::make_volume({7, 6, 5}, [&](double, double, double) { return coin(rng); });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
            const auto s = extract_digital_surface(volume, c);
            expect_closed_manifold(s);
            expect_no_pinched_edge(s);
            expect_outward_orientation(s);
            for (std::int64_t chi : component_euler_characteristics(s)) {
                EXPECT_LE(chi, 2);
                EXPECT_EQ(chi % 2, 0);  // closed orientable surfaces
            }
        }
    }
}

TEST(DigitalSurface, EmptyObjectIsAnError) {
    EXPECT_THROW(extract_digital_surface(test::make_voxels({3, 3, 3}, {}), Connectivity::Six), Error);
}

TEST(DigitalSurface, LinksFollowQuadEdges) {
    const auto s = extract_digital_surface(test::make_voxels({3, 3, 3}, {{1, 1, 1}}), Connectivity::Six);
    const VertexLinks links = vertex_links(s.quads, s.vertex_count());
    for (std::int64_t i = 0; i < s.vertex_count(); ++i) {
        ASSERT_EQ(links.size(i), 3);  // a cube corner has three edges
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            EXPECT_DOUBLE_EQ((s.vertices.row(i) - s.vertices.row(links.neighbors[std::size_t(q)])).norm(), 1.0);
    }
}

TEST(DigitalSurface, CornersListEachFaceAtEachOfItsVerticesOnce) {
    // Two voxels touching along an edge (26-connectivity: split pointels), so that vertices have
    // three to six faces.
    const auto s = extract_digital_surface(test::make_voxels({4, 4, 4}, {{1, 1, 1}, {2, 2, 1}, {1, 2, 2}}), Connectivity::TwentySix);
    const VertexCorners corners = vertex_corners(s.quads, s.vertex_count());
    ASSERT_EQ(corners.offsets.size(), std::size_t(s.vertex_count() + 1));
    EXPECT_EQ(corners.codes.size(), std::size_t(4 * s.face_count()));
    std::vector<int> seen(std::size_t(4 * s.face_count()), 0);
    for (std::int64_t v = 0; v < s.vertex_count(); ++v) {
        std::vector<std::int32_t> faces;
        corners.for_each_face(v, [&](std::int32_t f) { faces.push_back(f); });
        EXPECT_TRUE(std::is_sorted(faces.begin(), faces.end()));
        EXPECT_GE(faces.size(), 3u);
        for (std::int64_t q = corners.offsets[std::size_t(v)]; q < corners.offsets[std::size_t(v + 1)]; ++q) {
            const std::int32_t code = corners.codes[std::size_t(q)];
            EXPECT_EQ(s.quads(code / 4, code % 4), v);  // v is that corner of that face
            ++seen[std::size_t(code)];
        }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(seen.size()));  // every corner once
}

}  // namespace
}  // namespace dsreg
