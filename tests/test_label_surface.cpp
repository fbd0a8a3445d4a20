// The label complex: binary input as the special case, each label's surface against its own
// binary digital surface, shared vertices, junctions and the fairness links.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <map>
#include <random>
#include <set>

#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/pipeline.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

using Key = std::array<std::int64_t, 5>;  // voxel, axis, sign

Key surfel_key(const Surfel& s) { return {s.voxel[0], s.voxel[1], s.voxel[2], s.axis, s.sign}; }

/// The surfel of face f as the label on its reversed (outer) side sees it.
Key outer_key(const Surfel& s) {
    Key key = surfel_key(s);
    key[std::size_t(s.axis)] += s.sign;
    key[4] = -s.sign;
    return key;
}

std::array<std::int64_t, 3> pointel(const DigitalSurface& s, std::int32_t v) {
    return {s.vertex_pointels(v, 0), s.vertex_pointels(v, 1), s.vertex_pointels(v, 2)};
}

/// The label's mesh is the label's own binary digital surface: the same faces, each the same
/// way round, and the same vertices (a bijection between own vertices and the binary surface's
/// vertices that maps every corner to the corner at the same pointel).
void expect_same_surface(const DigitalSurface& complex, const LabelMesh& mesh, const DigitalSurface& binary) {
    ASSERT_EQ(mesh.face_count(), binary.face_count());
    ASSERT_EQ(mesh.vertex_count(), binary.vertex_count());
    std::map<Key, std::int64_t> binary_face;
    for (std::int64_t b = 0; b < binary.face_count(); ++b) binary_face[surfel_key(binary.surfels[std::size_t(b)])] = b;
    std::vector<std::int32_t> to_binary(std::size_t(mesh.vertex_count()), -1);
    std::set<std::int64_t> faces_seen;
    for (std::int64_t local = 0; local < mesh.face_count(); ++local) {
        const Surfel& s = complex.surfels[std::size_t(mesh.faces[std::size_t(local)])];
        const auto it = binary_face.find(mesh.reversed[std::size_t(local)] ? outer_key(s) : surfel_key(s));
        ASSERT_NE(it, binary_face.end()) << "a face of the label's mesh is not a face of its indicator";
        const std::int64_t b = it->second;
        ASSERT_TRUE(faces_seen.insert(b).second);
        // Same cyclic order of pointels: find the rotation.
        int shift = -1;
        for (int r = 0; r < 4; ++r)
            if (pointel(complex, mesh.vertices[std::size_t(mesh.quads(local, 0))]) == pointel(binary, binary.quads(b, r))) shift = r;
        ASSERT_GE(shift, 0);
        for (int k = 0; k < 4; ++k) {
            const std::int32_t own = mesh.quads(local, k), other = binary.quads(b, (k + shift) % 4);
            ASSERT_EQ(pointel(complex, mesh.vertices[std::size_t(own)]), pointel(binary, other)) << "orientation differs";
            std::int32_t& mapped = to_binary[std::size_t(own)];
            if (mapped < 0) mapped = other;
            ASSERT_EQ(mapped, other) << "an own vertex stands for two vertices of the binary surface";
        }
    }
    std::set<std::int32_t> image(to_binary.begin(), to_binary.end());
    EXPECT_EQ(std::int64_t(image.size()), binary.vertex_count()) << "two own vertices stand for one of the binary surface";
    const auto own_chi = mesh.euler_characteristics();
    std::multiset<std::int64_t> chi(own_chi.begin(), own_chi.end());
    const auto binary_chi = component_euler_characteristics(binary);
    EXPECT_EQ(chi, std::multiset<std::int64_t>(binary_chi.begin(), binary_chi.end()));
    EXPECT_EQ(mesh.component_count, binary.component_count);
}

/// Every label's mesh against its indicator's surface; own vertices sit on the complex's vertex.
void expect_label_surfaces(const LabelVolume& labels, Connectivity c) {
    const DigitalSurface complex = extract_digital_surface(labels, c);
    EXPECT_EQ(count_surfels(labels), complex.face_count());  // the --max-memory count, without the surface
    const std::vector<LabelMesh> meshes = label_meshes(complex);
    const std::vector<std::int64_t> counts = labels.voxel_counts();
    std::size_t next = 0;
    for (std::uint32_t label = 1; label < labels.values.size(); ++label) {
        if (counts[label] == 0) continue;
        ASSERT_LT(next, meshes.size());
        const LabelMesh& mesh = meshes[next++];
        ASSERT_EQ(mesh.label, label);
        SCOPED_TRACE("label " + std::to_string(labels.values[label]));
        expect_same_surface(complex, mesh, extract_digital_surface(test::indicator(labels, label), c));
    }
    EXPECT_EQ(next, meshes.size());
}

void expect_equal_surfaces(const DigitalSurface& a, const DigitalSurface& b) {
    ASSERT_EQ(a.face_count(), b.face_count());
    for (std::size_t f = 0; f < a.surfels.size(); ++f) ASSERT_EQ(surfel_key(a.surfels[f]), surfel_key(b.surfels[f]));
    EXPECT_EQ(a.quads, b.quads);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.vertex_pointels, b.vertex_pointels);
    EXPECT_EQ(a.adjacent_face, b.adjacent_face);
    EXPECT_EQ(a.face_component, b.face_component);
    EXPECT_EQ(a.split_pointel_count, b.split_pointel_count);
}

TEST(LabelSurface, BinaryVolumeIsTheSpecialCase) {
    std::mt19937 rng(11);
    for (int trial = 0; trial < 12; ++trial) {
        std::bernoulli_distribution coin(0.3 + 0.04 * trial);
        const BinaryVolume volume = test::make_volume({7, 6, 5}, [&](double, double, double) { return coin(rng); });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
            const DigitalSurface binary = extract_digital_surface(volume, c);
            const DigitalSurface labels = extract_digital_surface(label_volume_from_mask(volume), c);
            expect_equal_surfaces(binary, labels);
            EXPECT_EQ(labels.label_values, (std::vector<std::int64_t>{0, 1}));
            // The joint regularization's links are the quad links, in the same order (the edge
            // pass itself: fairness_links(surface) takes the quad links at once for two regions).
            const VertexLinks quad_links = vertex_links(binary.quads, binary.vertex_count());
            const VertexLinks links = fairness_links(labels, complex_edges(labels));
            EXPECT_EQ(links.offsets, quad_links.offsets);
            EXPECT_EQ(links.neighbors, quad_links.neighbors);
            EXPECT_EQ(find_junctions(labels, complex_edges(labels)).vertex_count, 0);
            const auto meshes = label_meshes(labels);
            ASSERT_EQ(meshes.size(), 1u);
            EXPECT_EQ(meshes[0].quads, binary.quads);  // the label's surface is the complex itself
            EXPECT_EQ(meshes[0].pinch_vertices, 0);
        }
    }
}

TEST(LabelSurface, RandomLabelMapsGiveEachLabelItsOwnSurface) {
    std::mt19937 rng(5);
    for (int trial = 0; trial < 16; ++trial) {
        std::uniform_int_distribution<int> value(0, 2 + trial % 4);
        const LabelVolume labels = test::make_labels({6, 5, 5}, [&](std::int64_t, std::int64_t, std::int64_t) {
            return std::int64_t(10 * value(rng));  // values 0, 10, 20, ... : indices are compacted
        });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) expect_label_surfaces(labels, c);
    }
}

TEST(LabelSurface, FacesBetweenTwoLabelsAreStoredOnceAndShared) {
    // Two boxes side by side: the faces between them belong to both surfaces, with the same
    // vertices, read in opposite directions.
    const LabelVolume labels = test::make_labels({6, 4, 4}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        if (j < 1 || j > 2 || k < 1 || k > 2 || i < 1 || i > 4) return 0;
        return i <= 2 ? 3 : 7;
    });
    const DigitalSurface complex = extract_digital_surface(labels, Connectivity::TwentySix);
    EXPECT_EQ(complex.label_values, (std::vector<std::int64_t>{0, 3, 7}));
    std::int64_t shared = 0;
    for (const FaceLabels& l : complex.face_labels) shared += l.outer != 0;
    EXPECT_EQ(shared, 4);                              // the 2×2 wall
    EXPECT_EQ(complex.face_count(), 2 * (4 * 2 + 4 * 2 + 2 * 2) + 4);  // the 40 faces of the union box, and the wall once
    const auto meshes = label_meshes(complex);
    ASSERT_EQ(meshes.size(), 2u);
    std::set<std::int32_t> a(meshes[0].vertices.begin(), meshes[0].vertices.end());
    std::set<std::int32_t> b(meshes[1].vertices.begin(), meshes[1].vertices.end());
    std::vector<std::int32_t> common;
    std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common));
    EXPECT_EQ(common.size(), 9u);  // the 3×3 pointels of the wall
    for (const LabelMesh& mesh : meshes) {
        EXPECT_EQ(mesh.euler_characteristics(), std::vector<std::int64_t>{2});
        EXPECT_EQ(mesh.face_count(), 2 * (2 * 2 + 2 * 2 + 2 * 2));
    }
    expect_label_surfaces(labels, Connectivity::TwentySix);
}

TEST(LabelSurface, NestedLabelIsACavityOfItsHost) {
    const LabelVolume labels = test::make_labels({9, 9, 9}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        const auto in = [&](std::int64_t lo, std::int64_t hi) { return i >= lo && i <= hi && j >= lo && j <= hi && k >= lo && k <= hi; };
        return in(3, 5) ? 2 : in(1, 7) ? 1 : 0;
    });
    for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
        const DigitalSurface complex = extract_digital_surface(labels, c);
        const auto meshes = label_meshes(complex);
        ASSERT_EQ(meshes.size(), 2u);
        EXPECT_EQ(meshes[0].component_count, 2);  // the host: outside and the cavity
        EXPECT_EQ(meshes[0].euler_characteristics(), (std::vector<std::int64_t>{2, 2}));
        EXPECT_EQ(meshes[1].component_count, 1);
        // The inner label shares every vertex with its host.
        std::set<std::int32_t> host(meshes[0].vertices.begin(), meshes[0].vertices.end());
        for (std::int32_t v : meshes[1].vertices) EXPECT_TRUE(host.count(v));
        EXPECT_EQ(find_junctions(complex, complex_edges(complex)).vertex_count, 0);
        // No junction: the complex is a union of closed oriented sheets, and its links are the quad links.
        const VertexLinks quad_links = vertex_links(complex.quads, complex.vertex_count());
        EXPECT_EQ(fairness_links(complex).neighbors, quad_links.neighbors);
        expect_label_surfaces(labels, c);
    }
}

TEST(LabelSurface, OneVoxelLabelAndLabelsOnTheBorder) {
    // Label 1 fills the whole grid but one voxel of label 2 on the border: both closed.
    const LabelVolume labels = test::make_labels({4, 3, 3}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        return i == 0 && j == 1 && k == 1 ? 2 : 1;
    });
    const DigitalSurface complex = extract_digital_surface(labels, Connectivity::TwentySix);
    const auto meshes = label_meshes(complex);
    ASSERT_EQ(meshes.size(), 2u);
    EXPECT_EQ(meshes[1].face_count(), 6);
    EXPECT_EQ(meshes[1].vertex_count(), 8);
    EXPECT_EQ(meshes[1].euler_characteristics(), std::vector<std::int64_t>{2});
    EXPECT_EQ(meshes[0].euler_characteristics(), std::vector<std::int64_t>{2});  // a box with a dent
    expect_label_surfaces(labels, Connectivity::Six);
    expect_label_surfaces(labels, Connectivity::TwentySix);
}

TEST(LabelSurface, TwoLabelsTouchingOnlyAlongAnEdgeOrAtACorner) {
    for (const Index3 second : {Index3{2, 2, 1}, Index3{2, 2, 2}}) {
        const LabelVolume labels = test::make_labels({4, 4, 4}, [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
            if (i == 1 && j == 1 && k == 1) return 1;
            return i == second[0] && j == second[1] && k == second[2] ? 2 : 0;
        });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
            const DigitalSurface complex = extract_digital_surface(labels, c);
            // Different labels never join: two cubes, no shared vertex, whatever the connectivity.
            EXPECT_EQ(complex.vertex_count(), 16);
            EXPECT_EQ(complex.component_count, 2);
            const auto meshes = label_meshes(complex);
            ASSERT_EQ(meshes.size(), 2u);
            for (const LabelMesh& mesh : meshes) EXPECT_EQ(mesh.euler_characteristics(), std::vector<std::int64_t>{2});
            expect_label_surfaces(labels, c);
        }
    }
}

TEST(LabelSurface, OneLabelAcrossAnEdgeOfTwoOthers) {
    // Around the linel along z at (2,2): voxels (1,1)=1 (2,2)=1 on one diagonal, (2,1) and (1,2)
    // of labels 2 and 3 (or both 2) on the other.
    for (const std::int64_t other : {3, 2}) {
        const LabelVolume labels = test::make_labels({4, 4, 3}, [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
            if (k != 1) return 0;
            if ((i == 1 && j == 1) || (i == 2 && j == 2)) return 1;
            if (i == 2 && j == 1) return 2;
            return i == 1 && j == 2 ? other : 0;
        });
        for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
            SCOPED_TRACE("other label " + std::to_string(other) + ", connectivity " + std::to_string(int(c)));
            const DigitalSurface complex = extract_digital_surface(labels, c);
            expect_label_surfaces(labels, c);
            const auto meshes = label_meshes(complex);
            // Label 1's two voxels touch by this edge only: joining them (26) would pinch its
            // surface along the linel, so they are kept apart whatever the connectivity. Its two
            // umbrellas at the linel's ends are joined by the other labels' umbrellas: two pinch
            // vertices, two components.
            EXPECT_EQ(meshes[0].pinch_vertices, 2);
            EXPECT_EQ(meshes[0].component_count, 2);
        }
    }
}

TEST(LabelSurface, JunctionTurnsAreTheCornersOfAnInterfaceRectangle) {
    // Two boxes of labels 1 and 2 side by side (x), background around: the interface is a 3×3
    // square of faces whose border is a junction curve (labels 1, 2, 0) turning at its four
    // corners. Only there does a face (the interface's corner face) have both edges at a vertex
    // on junction edges; the background-facing faces along the curve have one junction edge
    // each, and the edges of the boxes are manifold edges.
    const LabelVolume labels = test::make_labels({6, 5, 5}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        if (j < 1 || j > 3 || k < 1 || k > 3 || i < 1 || i > 4) return 0;
        return i <= 2 ? 1 : 2;
    });
    for (Connectivity c : {Connectivity::Six, Connectivity::TwentySix}) {
        const DigitalSurface complex = extract_digital_surface(labels, c);
        const std::vector<char> turn = junction_turn_vertices(complex, complex_edges(complex));
        std::set<std::array<std::int64_t, 3>> turns, corners;
        std::int64_t low = INT64_MAX, high = INT64_MIN;
        for (std::int32_t v = 0; v < complex.vertex_count(); ++v) {
            if (turn[std::size_t(v)]) turns.insert(pointel(complex, v));
            low = std::min<std::int64_t>(low, complex.vertex_pointels(v, 1));
            high = std::max<std::int64_t>(high, complex.vertex_pointels(v, 1));
        }
        std::int64_t interface_x = -1;
        for (std::int64_t f = 0; f < complex.face_count(); ++f)
            if (complex.face_labels[std::size_t(f)].outer != 0)
                interface_x = complex.vertex_pointels(complex.quads(f, 0), 0);
        ASSERT_GE(interface_x, 0);
        for (const std::int64_t y : {low, high})
            for (const std::int64_t z : {low, high}) corners.insert({interface_x, y, z});  // the boxes span y and z alike
        EXPECT_EQ(turns, corners);
        // One label: no junction, no turn.
        const DigitalSurface binary = extract_digital_surface(test::indicator(labels, 1), c);
        const std::vector<char> none = junction_turn_vertices(binary, complex_edges(binary));
        EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
    }
}

TEST(LabelSurface, JunctionTurnTargetsPointOutOfTheChordAtTheTurnsOnly) {
    // The interface rectangle of two boxes (as above), on an anisotropic grid: its four corners are
    // the turns, each linked to its two neighbours on the curve; the target is `share` times the
    // corner's offset from their chord's middle, half the face diagonal, pointing out of the
    // rectangle. Every other vertex gets none, and a binary surface no targets at all.
    LabelVolume labels = test::make_labels({6, 5, 5}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        if (j < 1 || j > 3 || k < 1 || k > 3 || i < 1 || i > 4) return 0;
        return i <= 2 ? 1 : 2;
    });
    labels.grid.spacing = {0.5, 0.75, 1.25};
    const DigitalSurface complex = extract_digital_surface(labels, Connectivity::TwentySix);
    const ComplexEdges edges = complex_edges(complex);
    const VertexLinks links = fairness_links(complex, edges);
    const std::vector<char> turn = junction_turn_vertices(complex, edges);
    const double share = 0.55;
    const PointMatrix targets = junction_turn_targets(complex, edges, links, share);
    ASSERT_EQ(targets.rows(), complex.vertex_count());
    Eigen::RowVector3d centre = Eigen::RowVector3d::Zero();
    for (std::int32_t v = 0; v < complex.vertex_count(); ++v)
        if (turn[std::size_t(v)]) centre += 0.25 * complex.vertices.row(v);
    std::int64_t with_target = 0;
    for (std::int32_t v = 0; v < complex.vertex_count(); ++v) {
        if (!turn[std::size_t(v)]) {
            EXPECT_TRUE(targets.row(v).isZero(0.0)) << "vertex at " << complex.vertex_pointels.row(v);
            continue;
        }
        ++with_target;
        ASSERT_EQ(links.size(v), 2);
        const Eigen::RowVector3d t = targets.row(v), out = complex.vertices.row(v) - centre;
        EXPECT_EQ(t[0], 0.0);  // in the interface plane x = const
        EXPECT_NEAR(t[1], std::copysign(share * 0.5 * 0.75, out[1]), 1e-12);
        EXPECT_NEAR(t[2], std::copysign(share * 0.5 * 1.25, out[2]), 1e-12);
    }
    EXPECT_EQ(with_target, 4);
    const DigitalSurface binary = extract_digital_surface(test::indicator(labels, 1), Connectivity::TwentySix);
    EXPECT_EQ(junction_turn_targets(binary, complex_edges(binary), fairness_links(binary), share).rows(), 0);
}

TEST(LabelSurface, JunctionCurveIsSmoothedAlongItsLengthOnly) {
    // Three labels meeting along the line x = y = 4 (pointels), z through the whole grid.
    const LabelVolume labels = test::make_labels({8, 8, 6}, [](std::int64_t i, std::int64_t j, std::int64_t) -> std::int64_t {
        return j < 4 ? (i < 4 ? 1 : 2) : 3;
    });
    const DigitalSurface complex = extract_digital_surface(labels, Connectivity::TwentySix);
    expect_label_surfaces(labels, Connectivity::TwentySix);
    const ComplexEdges edges = complex_edges(complex);
    const Junctions junctions = find_junctions(complex, edges);
    const VertexLinks links = fairness_links(complex);
    const VertexLinks quad_links = vertex_links(complex.quads, complex.vertex_count());
    std::map<std::array<std::int64_t, 3>, std::int32_t> at;
    for (std::int32_t v = 0; v < complex.vertex_count(); ++v) at[pointel(complex, v)] = v;
    for (std::int64_t z = 0; z <= 6; ++z) {
        const std::int32_t v = at.at({4, 4, z});
        ASSERT_TRUE(junctions.vertex[std::size_t(v)]);
        if (z == 0 || z == 6) {
            // Where the curve meets the border, four regions meet (the background too): a junction point.
            EXPECT_EQ(junctions.edges_at_vertex[std::size_t(v)], 4);
            EXPECT_EQ(links.size(v), 0);
            continue;
        }
        EXPECT_EQ(junctions.edges_at_vertex[std::size_t(v)], 2);
        std::multiset<std::int32_t> link(links.neighbors.begin() + links.offsets[std::size_t(v)],
                                          links.neighbors.begin() + links.offsets[std::size_t(v) + 1]);
        EXPECT_EQ(link, (std::multiset<std::int32_t>{at.at({4, 4, z - 1}), at.at({4, 4, z + 1})}));
    }
    // Inside the sheets, the links are the quad links.
    for (std::int32_t v = 0; v < complex.vertex_count(); ++v) {
        if (junctions.vertex[std::size_t(v)]) continue;
        std::multiset<std::int32_t> link(links.neighbors.begin() + links.offsets[std::size_t(v)],
                                          links.neighbors.begin() + links.offsets[std::size_t(v) + 1]);
        std::multiset<std::int32_t> quad(quad_links.neighbors.begin() + quad_links.offsets[std::size_t(v)],
                                          quad_links.neighbors.begin() + quad_links.offsets[std::size_t(v) + 1]);
        EXPECT_EQ(link, quad) << "vertex at " << complex.vertex_pointels.row(v);
    }
    // The junction edges: 6 along the curve, the curves on the border faces of the grid.
    std::int64_t along_z = 0;
    for (std::int64_t c = 0; c < edges.count(); ++c) {
        if (!edges.junction[std::size_t(c)]) continue;
        const auto p = pointel(complex, edges.ends[std::size_t(c)][0]), q = pointel(complex, edges.ends[std::size_t(c)][1]);
        along_z += p[0] == 4 && p[1] == 4 && q[0] == 4 && q[1] == 4;
        EXPECT_EQ(edges.face_count[std::size_t(c)], 3);
    }
    EXPECT_EQ(along_z, 6);
}

TEST(LabelSurface, EmptyLabelMapIsAnError) {
    EXPECT_THROW(extract_digital_surface(test::make_labels({3, 3, 3}, [](std::int64_t, std::int64_t, std::int64_t) { return std::int64_t(0); }),
                                         Connectivity::Six),
                 Error);
}

}  // namespace
}  // namespace dsreg
