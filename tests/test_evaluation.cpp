// Evaluation against ground truth: statistics, mesh geometry, inside test, shape volumes, mesh
// evaluation on meshes with known answers, and the multigrid convergence experiment (Fig. 7).
//
// The closest-point map ξ itself is covered by tests/test_implicit_shape.cpp (ClosestPoint.*:
// exact spheres and tilted planes, closest points of polynomial shapes against independent
// surface samples), so it is not tested again here.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>

#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/evaluation_report.hpp"
#include "dsreg/normals.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double pi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Meshes with known answers

/// Icosahedron subdivided `levels` times, every vertex projected onto the sphere of `radius`
/// around `centre`; triangles counter-clockwise seen from outside.
PolygonMesh icosphere(int levels, double radius = 1.0, const Vec3& centre = Vec3::Zero()) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3& p : v) p.normalize();
    std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<int, int>, int> midpoints;
        auto midpoint = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            const auto found = midpoints.find(key);
            if (found != midpoints.end()) return found->second;
            v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
            return midpoints[key] = int(v.size()) - 1;
        };
        std::vector<std::array<int, 3>> finer;
        for (const auto& [a, b, c] : f) {
            const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            finer.insert(finer.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
        }
        f = finer;
    }
    PolygonMesh mesh;
    mesh.vertices.resize(Eigen::Index(v.size()), 3);
    for (std::size_t i = 0; i < v.size(); ++i) mesh.vertices.row(Eigen::Index(i)) = (centre + radius * v[i]).transpose();
    mesh.faces.resize(Eigen::Index(f.size()), 3);
    for (std::size_t i = 0; i < f.size(); ++i)
        for (int k = 0; k < 3; ++k) mesh.faces(Eigen::Index(i), k) = f[i][std::size_t(k)];
    return mesh;
}

/// The regular octahedron |x| + |y| + |z| = 1 (8 equilateral triangles, vertices on sphere1).
PolygonMesh octahedron() {
    PolygonMesh mesh;
    mesh.vertices.resize(6, 3);
    mesh.vertices << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
    mesh.faces.resize(8, 3);
    mesh.faces << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
    return mesh;
}

/// The box [lo, hi] with each face cut into n×n quads, counter-clockwise seen from outside.
PolygonMesh box_mesh(const Vec3& lo, const Vec3& hi, int n) {
    PolygonMesh mesh;
    std::vector<Vec3> vertices;
    std::vector<std::array<int, 4>> quads;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            // Axes u, v such that (u, v, axis) is right-handed; flip u for the lower face.
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            const int first = int(vertices.size());
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i <= n; ++i) {
                    Vec3 p;
                    p[axis] = side ? hi[axis] : lo[axis];
                    p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
                    p[w] = lo[w] + (hi[w] - lo[w]) * j / n;
                    vertices.push_back(p);
                }
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const int a = first + j * (n + 1) + i, b = a + 1, c = b + n + 1, d = a + n + 1;
                    quads.push_back(side ? std::array<int, 4>{a, b, c, d} : std::array<int, 4>{a, d, c, b});
                }
        }
    }
    mesh.vertices.resize(Eigen::Index(vertices.size()), 3);
    for (std::size_t i = 0; i < vertices.size(); ++i) mesh.vertices.row(Eigen::Index(i)) = vertices[i].transpose();
    mesh.faces.resize(Eigen::Index(quads.size()), 4);
    for (std::size_t i = 0; i < quads.size(); ++i)
        for (int k = 0; k < 4; ++k) mesh.faces(Eigen::Index(i), k) = quads[i][std::size_t(k)];
    return mesh;
}

MeshEvaluationOptions fast_options(double grid_step = 0) {
    MeshEvaluationOptions options;
    options.grid_step = grid_step;
    options.volume_cells = 16;
    return options;
}

// ---------------------------------------------------------------------------------------------
// Statistics

TEST(ErrorStats, MeanRootMeanSquareMaximumAndNearestRankPercentile) {
    std::vector<double> errors;
    for (int k = 20; k >= 1; --k) errors.push_back(k);  // 1..20, unsorted
    const ErrorStats s = error_stats(errors);
    EXPECT_EQ(s.count, 20);
    EXPECT_DOUBLE_EQ(s.mean, 10.5);
    EXPECT_DOUBLE_EQ(s.l2, std::sqrt(2870.0 / 20.0));  // Σk² = 2870
    EXPECT_DOUBLE_EQ(s.linf, 20.0);
    EXPECT_DOUBLE_EQ(s.p95, 19.0);  // ⌈0.95·20⌉ = 19th smallest
    const ErrorStats h = s.scaled(0.5);
    EXPECT_DOUBLE_EQ(h.mean, 5.25);
    EXPECT_DOUBLE_EQ(h.linf, 10.0);
    EXPECT_EQ(error_stats({}).count, 0);
    EXPECT_EQ(error_stats({3.0}).p95, 3.0);
}

TEST(LogLogSlope, RecoversPowerLawsAndIgnoresNonPositiveValues) {
    std::vector<double> h, y;
    for (double x = 0.2; x > 0.005; x *= 0.7) h.push_back(x), y.push_back(3.0 * x * x);
    EXPECT_NEAR(log_log_slope(h, y), 2.0, 1e-12);
    y.back() = 0.0;  // a zero error (log undefined) is left out
    EXPECT_NEAR(log_log_slope(h, y), 2.0, 1e-12);
    EXPECT_TRUE(std::isnan(log_log_slope({0.1}, {1.0})));
    EXPECT_TRUE(std::isnan(log_log_slope({0.1, 0.1}, {1.0, 2.0})));
}

TEST(GeometricSteps, SpansTheRangeWithAConstantRatio) {
    const std::vector<double> steps = geometric_steps(0.2, 0.006, 12);
    ASSERT_EQ(steps.size(), 12u);
    EXPECT_EQ(steps.front(), 0.2);
    EXPECT_EQ(steps.back(), 0.006);
    for (std::size_t i = 1; i + 1 < steps.size(); ++i)
        EXPECT_NEAR(steps[i] / steps[i - 1], steps[i + 1] / steps[i], 1e-12);
    EXPECT_EQ(geometric_steps(0.1, 0.1, 1).size(), 1u);
    EXPECT_THROW(geometric_steps(0.006, 0.2, 5), Error);
    EXPECT_THROW(geometric_steps(0.2, 0.0, 5), Error);
    EXPECT_THROW(geometric_steps(0.2, 0.1, 1), Error);
}

// ---------------------------------------------------------------------------------------------
// Mesh geometry

TEST(FaceNormals, TrianglesAndQuadsFollowTheFootnoteConvention) {
    PointMatrix v(5, 3);
    v << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 1, 1;
    FaceMatrix planar(1, 4);
    planar << 0, 1, 2, 3;
    EXPECT_TRUE(face_normals(v, planar).row(0).isApprox(Eigen::RowVector3d(0, 0, 1)));
    // A bent quad: triangle (0,1,4) has normal (0,-1,1)/√2, triangle (0,4,3) has (-1,0,1)/√2;
    // the face normal is their normalized mean (-1,-1,2)/√6.
    FaceMatrix bent(1, 4);
    bent << 0, 1, 4, 3;
    EXPECT_TRUE(face_normals(v, bent).row(0).isApprox(Eigen::RowVector3d(-1, -1, 2) / std::sqrt(6.0), 1e-14));
    FaceMatrix triangle(1, 3);
    triangle << 0, 2, 1;  // clockwise seen from +z
    EXPECT_TRUE(face_normals(v, triangle).row(0).isApprox(Eigen::RowVector3d(0, 0, -1)));
    FaceMatrix degenerate(1, 3);
    degenerate << 0, 1, 1;
    EXPECT_TRUE(face_normals(v, degenerate).row(0).isZero());
}

TEST(FacesAgainstField, CountsFacesTurnedAgainstTheirVectorAndDegenerateOnes) {
    const auto s = extract_digital_surface(test::make_ball(6, 1.8, 2.5), Connectivity::Six);
    PointMatrix u = trivial_normals(s);  // outward, as the faces
    EXPECT_EQ(count_faces_against_field(s.vertices, s.quads, u), 0);
    EXPECT_EQ(count_faces_against_field(s.vertices, s.quads, PointMatrix(-u)), s.face_count());
    u.row(3) *= -1.0;
    u.row(7) *= -1.0;
    EXPECT_EQ(count_faces_against_field(s.vertices, s.quads, u), 2);
    PointMatrix collapsed = s.vertices;  // face 0 shrunk to a point: no normal
    for (int k = 0; k < 4; ++k) collapsed.row(s.quads(0, k)) = s.vertices.row(s.quads(0, 0));
    EXPECT_GE(count_faces_against_field(collapsed, s.quads, trivial_normals(s)), 1);
    EXPECT_THROW(count_faces_against_field(s.vertices, s.quads, PointMatrix(2, 3)), Error);
}

TEST(TriangleAngles, EquilateralTrianglesHaveSixtyDegrees) {
    const PolygonMesh mesh = octahedron();
    for (double angle : triangle_min_angles(mesh.vertices, mesh.faces)) EXPECT_NEAR(angle, 60.0, 1e-12);
    const MeshEvaluation e = evaluate_mesh(mesh, make_shape("sphere1"), fast_options());
    EXPECT_NEAR(e.triangle_min_angle_min_deg, 60.0, 1e-12);
    EXPECT_NEAR(e.triangle_min_angle_mean_deg, 60.0, 1e-12);
    // A unit-square quad is split into two right isosceles triangles: 45 degrees.
    const PolygonMesh box = box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1), 3);
    for (double angle : triangle_min_angles(box.vertices, mesh_triangles(box.vertices, box.faces)))
        EXPECT_NEAR(angle, 45.0, 1e-12);
}

TEST(EnclosedVolume, DivergenceTheoremOnClosedMeshes) {
    const PolygonMesh box = box_mesh(Vec3(-1, -2, 0), Vec3(2, 1, 0.5), 4);
    EXPECT_NEAR(enclosed_volume(box.vertices, mesh_triangles(box.vertices, box.faces)), 3.0 * 3.0 * 0.5, 1e-12);
    const PolygonMesh o = octahedron();
    EXPECT_NEAR(enclosed_volume(o.vertices, o.faces), 4.0 / 3.0, 1e-15);
    // Translation does not change it; reversing the faces negates it.
    PolygonMesh shifted = o;
    shifted.vertices.rowwise() += Eigen::RowVector3d(5, -3, 2);
    EXPECT_NEAR(enclosed_volume(shifted.vertices, shifted.faces), 4.0 / 3.0, 1e-12);
    PolygonMesh reversed = o;
    reversed.faces.col(1).swap(reversed.faces.col(2));
    EXPECT_NEAR(enclosed_volume(reversed.vertices, reversed.faces), -4.0 / 3.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Inside test

/// Grid of voxel centres (i·h + origin) covering [-extent, extent]³.
VoxelGrid centred_grid(double h, double extent, const Vec3& origin_shift = Vec3::Zero()) {
    VoxelGrid grid;
    const std::int64_t n = std::int64_t(std::ceil(extent / h));
    grid.dims = {2 * n + 1, 2 * n + 1, 2 * n + 1};
    grid.spacing = Vec3::Constant(h);
    grid.origin = Vec3::Constant(-h * double(n)) + origin_shift;
    return grid;
}

TEST(InsideTest, RaysThroughVerticesAndEdgesAreCountedOnce) {
    // Octahedron with h = 0.25: the row y = z = 0 passes through the vertices (±1,0,0); rows in
    // the planes y = 0 or z = 0 cross the edges shared by two faces. Centres exactly on the
    // surface (|x|+|y|+|z| = 1) are ambiguous and skipped.
    const PolygonMesh o = octahedron();
    for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(0.125, 0, 0), Vec3(0, 0.03, 0)}) {
        const VoxelGrid grid = centred_grid(0.25, 1.5, shift);
        const std::vector<std::uint8_t> inside = voxel_centres_inside(o.vertices, o.faces, grid);
        std::int64_t checked = 0;
        for (std::int64_t k = 0; k < grid.dims[2]; ++k)
            for (std::int64_t j = 0; j < grid.dims[1]; ++j)
                for (std::int64_t i = 0; i < grid.dims[0]; ++i) {
                    const Vec3 c = grid.voxel_center(i, j, k);
                    const double level = c.cwiseAbs().sum();
                    if (std::abs(level - 1.0) < 1e-12) continue;
                    ASSERT_EQ(inside[std::size_t(grid.linear_index(i, j, k))] != 0, level < 1.0)
                        << "voxel centre " << c.transpose();
                    ++checked;
                }
        EXPECT_GT(checked, 1000);
    }
}

TEST(InsideTest, RaysInTheFacePlanesOfABoxSeeNoCrossingTwice) {
    // Box [-1,1]³ with h = 0.5: rows at y = ±1 or z = ±1 lie in face planes and along edges.
    const PolygonMesh box = box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1), 2);
    const FaceMatrix triangles = mesh_triangles(box.vertices, box.faces);
    const VoxelGrid grid = centred_grid(0.5, 2.0);
    const std::vector<std::uint8_t> inside = voxel_centres_inside(box.vertices, triangles, grid);
    for (std::int64_t k = 0; k < grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < grid.dims[0]; ++i) {
                const Vec3 c = grid.voxel_center(i, j, k);
                const double level = c.cwiseAbs().maxCoeff();
                if (std::abs(level - 1.0) < 1e-12) continue;  // on the surface
                ASSERT_EQ(inside[std::size_t(grid.linear_index(i, j, k))] != 0, level < 1.0) << c.transpose();
            }
}

TEST(InsideTest, DigitalSurfaceClassifiesItsOwnVoxels) {
    // A random blob: its digital surface (with split pointels and edge-touching voxels) must
    // put every object voxel centre inside and every background centre outside.
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const BinaryVolume volume = test::make_volume({14, 12, 10}, [&](double x, double y, double z) {
        const double r2 = (x - 6.5) * (x - 6.5) + (y - 5.5) * (y - 5.5) + (z - 4.5) * (z - 4.5);
        return r2 < 20 && uniform(random) < 0.8;
    });
    for (Connectivity connectivity : {Connectivity::Six, Connectivity::TwentySix}) {
        const DigitalSurface surface = extract_digital_surface(volume, connectivity);
        const std::vector<std::uint8_t> inside =
            voxel_centres_inside(surface.vertices, mesh_triangles(surface.vertices, surface.quads), volume.grid);
        for (std::size_t v = 0; v < inside.size(); ++v) ASSERT_EQ(inside[v] != 0, volume.mask[v] != 0) << "voxel " << v;
    }
}

TEST(InsideTest, UpdatingTheMovedTrianglesGivesTheWholeClassification) {
    // A ball's digital surface with a patch of vertices pushed in by up to 1.5 voxels, in two
    // steps: after each, updating the triangles that moved or were split again gives what
    // classifying the whole grid at the new positions gives, and every voxel that changed lies
    // on a row the update reports.
    const BinaryVolume volume = test::make_ball(16, 5.5, 7.5);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    PointMatrix at = surface.vertices;
    FaceMatrix triangles = mesh_triangles(at, surface.quads);
    VoxelCentresInside tracked(at, triangles, volume.grid);
    ASSERT_EQ(tracked.inside(), voxel_centres_inside(at, triangles, volume.grid));
    EXPECT_TRUE(tracked.update(at, triangles, {}).empty());
    std::mt19937 random(3);
    std::uniform_real_distribution<double> depth(0.0, 0.75);
    const Eigen::RowVector3d centre(7.5, 7.5, 7.5);
    const std::int64_t nx = volume.grid.dims[0];
    for (int step = 0; step < 2; ++step) {
        const std::vector<std::uint8_t> before = tracked.inside();
        PointMatrix moved = at;
        for (Eigen::Index v = 0; v < moved.rows(); ++v)
            if (moved(v, 2) > 10) moved.row(v) -= depth(random) * (moved.row(v) - centre).normalized();
        const FaceMatrix after = mesh_triangles(moved, surface.quads);
        std::vector<std::int32_t> changed;
        for (Eigen::Index t = 0; t < after.rows(); ++t) {
            bool touched = after.row(t) != triangles.row(t);
            for (int k = 0; k < 3; ++k)
                touched = touched || moved.row(after(t, k)) != at.row(after(t, k)) ||
                          moved.row(triangles(t, k)) != at.row(triangles(t, k));
            if (touched) changed.push_back(std::int32_t(t));
        }
        ASSERT_FALSE(changed.empty());
        at = moved, triangles = after;
        const std::vector<std::int64_t> rows = tracked.update(at, triangles, changed);
        const std::vector<std::uint8_t> whole = voxel_centres_inside(at, triangles, volume.grid);
        EXPECT_EQ(tracked.inside(), whole) << "step " << step;
        EXPECT_NE(whole, before) << "step " << step;  // the push took some object centres out
        EXPECT_TRUE(std::is_sorted(rows.begin(), rows.end()));
        for (std::size_t v = 0; v < whole.size(); ++v)
            if (whole[v] != before[v]) EXPECT_TRUE(std::binary_search(rows.begin(), rows.end(), std::int64_t(v) / nx)) << v;
    }
    EXPECT_THROW(tracked.update(at, triangles.topRows(3), {0}), Error);
    EXPECT_THROW(tracked.update(at, FaceMatrix(triangles.leftCols(2)), {0}), Error);
    EXPECT_THROW(tracked.update(at, triangles, {std::int32_t(triangles.rows())}), Error);
}

// ---------------------------------------------------------------------------------------------
// Ground truth of shapes

TEST(ShapeVolume, MatchesExactVolumes) {
    struct Case {
        const char* name;
        double exact;
    };
    const Case cases[] = {
        {"sphere1", 4.0 / 3.0 * pi},
        {"sphere9", 4.0 / 3.0 * pi * 729.0},
        {"ellipsoid", 4.0 / 3.0 * pi * std::sqrt(30.0 * 45.0 * 90.0)},  // semi-axes √30, √45, √90
        {"torus", 2.0 * pi * pi * 6.0 * 4.0},                              // 2π²·R·r², R = 6, r = 2
    };
    for (const Case& c : cases) {
        const double v = shape_volume(make_shape(c.name));
        EXPECT_NEAR(v / c.exact - 1.0, 0.0, 1e-6) << c.name;
    }
    // Clipped shapes: the box counts. z ≤ 0.5 in [-1,1]³ is a 2×2×1.5 block; the tilted plane
    // through the origin halves the cube by central symmetry.
    EXPECT_NEAR(shape_volume(make_plane_shape(Vec3(0, 0, 1), 0.5, 1.0)) / 6.0 - 1.0, 0.0, 1e-6);
    EXPECT_NEAR(shape_volume(make_plane_shape(Vec3(1, 2, 3), 0.0, 1.0)), 4.0, 1e-5);
    EXPECT_THROW(shape_volume(make_shape("sphere1"), 4), Error);
}

TEST(EvaluationRegion, LeavesOutOnlyPointsNearClippedBoxFaces) {
    const ImplicitShape plane = make_plane_shape(Vec3(1, 1, 1), 0.0, 1.0);
    EXPECT_TRUE(in_evaluation_region(plane, Vec3(0.7, -0.7, 0), 0.25));
    EXPECT_FALSE(in_evaluation_region(plane, Vec3(0.8, 0, 0), 0.25));
    EXPECT_FALSE(in_evaluation_region(plane, Vec3(0, 0, -0.9), 0.25));
    const ImplicitShape sphere = make_shape("sphere1");  // not clipped: everything is in
    EXPECT_TRUE(in_evaluation_region(sphere, Vec3(5, 5, 5), 0.25));
}

TEST(SolidExactNormals, BoxWallFacesGetTheWallNormal) {
    const ImplicitShape plane = make_plane_shape(Vec3(1, 1.5, 2), 0.05, 1.0);
    const BinaryVolume volume = digitize(plane, 0.1);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix u = solid_exact_normals(plane, surface);
    const Vec3 n = Vec3(1, 1.5, 2).normalized();
    const PointMatrix centres = surfel_centers(surface);
    std::int64_t walls = 0, planar = 0;
    for (Eigen::Index f = 0; f < surface.face_count(); ++f) {
        const Vec3 c = centres.row(f).transpose(), normal = u.row(f).transpose();
        if (normal.isApprox(n, 1e-12)) {
            ++planar;
            EXPECT_LT(std::abs(n.dot(c) - 0.05), 0.1) << "plane normal on a face far from the plane";
        } else {
            ++walls;
            const int axis = surface.surfels[std::size_t(f)].axis;
            EXPECT_EQ(normal, surface.surfels[std::size_t(f)].trivial_normal());
            EXPECT_NEAR(std::abs(c[axis]), 1.05, 1e-9) << "wall normal on a face off the box faces";
        }
    }
    EXPECT_GT(walls, 0);
    EXPECT_GT(planar, 0);
    // Without clipping it is exactly exact_normals().
    const ImplicitShape sphere = make_shape("sphere1");
    const DigitalSurface ball = extract_digital_surface(digitize(sphere, 0.2), Connectivity::TwentySix);
    EXPECT_EQ(solid_exact_normals(sphere, ball), exact_normals(sphere, ball));
}

// ---------------------------------------------------------------------------------------------
// Evaluation of meshes with known answers

TEST(EvaluateMesh, ExactSphereTriangulation) {
    const ImplicitShape sphere = make_shape("sphere1");
    double previous_mean = 1e9, previous_max = 1e9, previous_volume_error = 1e9;
    for (int level = 1; level <= 4; ++level) {
        const MeshEvaluation e = evaluate_mesh(icosphere(level), sphere, fast_options());
        EXPECT_LT(e.vertex_distance.linf, 1e-15) << "vertices lie on the sphere";
        EXPECT_EQ(e.faces_degenerate, 0);
        // Flat facets: the normal error is below the angle subtended by a facet, and about
        // halves with each subdivision (the edge length halves).
        EXPECT_LT(e.normal_angle_deg.linf, 40.0 / (1 << level));
        EXPECT_LT(e.normal_angle_deg.mean, 0.55 * previous_mean);
        EXPECT_LT(e.normal_angle_deg.linf, 0.65 * previous_max);
        // The inscribed polyhedron is smaller; its deficit shrinks like the edge length squared.
        EXPECT_LT(e.relative_volume_error, 0.0);
        EXPECT_LT(std::abs(e.relative_volume_error), 0.3 * previous_volume_error);
        previous_mean = e.normal_angle_deg.mean;
        previous_max = e.normal_angle_deg.linf;
        previous_volume_error = std::abs(e.relative_volume_error);
    }
}

TEST(EvaluateMesh, OctahedronOnTheUnitSphere) {
    const MeshEvaluation e = evaluate_mesh(octahedron(), make_shape("sphere1"), fast_options());
    EXPECT_EQ(e.vertices_evaluated, 6);
    EXPECT_LT(e.vertex_distance.linf, 1e-15);
    // Each face normal (±1,±1,±1)/√3 is radial at its centroid: the true normal there.
    EXPECT_LT(e.normal_angle_deg.linf, 1e-6);
    EXPECT_NEAR(e.relative_volume_error, 1.0 / pi - 1.0, 1e-6);  // (4/3) / (4π/3) − 1
}

TEST(EvaluateMesh, ScaledAndShiftedSpheresAreAtTheKnownDistance) {
    const ImplicitShape sphere = make_shape("sphere1");
    // Radius 1.05: every vertex is 0.05 away; the volume grows by 1.05³.
    const MeshEvaluation unit = evaluate_mesh(icosphere(3), sphere, fast_options());
    const MeshEvaluation scaled = evaluate_mesh(icosphere(3, 1.05), sphere, fast_options());
    EXPECT_NEAR(scaled.vertex_distance.mean, 0.05, 1e-14);
    EXPECT_NEAR(scaled.vertex_distance.linf, 0.05, 1e-14);
    EXPECT_NEAR(scaled.relative_volume_error, std::pow(1.05, 3) * (1 + unit.relative_volume_error) - 1, 1e-6);
    // Shifted by s along x: | |v + s·e_x| − 1 | ≤ s (triangle inequality), with equality at the
    // vertex (1,0,0) of the icosphere, and ≈ s·|v_x|, whose mean over the sphere is s/2.
    const double s = 0.01;
    const MeshEvaluation shifted = evaluate_mesh(icosphere(4, 1.0, Vec3(s, 0, 0)), sphere, fast_options());
    EXPECT_LE(shifted.vertex_distance.linf, s + 1e-15);
    EXPECT_NEAR(shifted.vertex_distance.linf, s, 1e-15);
    EXPECT_NEAR(shifted.vertex_distance.mean, 0.5 * s, 0.02 * s);
}

TEST(EvaluateMesh, FineSphereMeshOnACoarseGridClassifiesEveryVoxel) {
    // h = 0.3: no voxel centre is closer than 0.005 to the unit sphere, more than the sagitta
    // (< 0.002) of the level-4 icosphere, so every centre must be classified right.
    const MeshEvaluation e = evaluate_mesh(icosphere(4), make_shape("sphere1"), fast_options(0.3));
    ASSERT_TRUE(e.has_voxel_classification);
    EXPECT_EQ(e.voxels.correct, e.voxels.total);
    EXPECT_EQ(e.voxels.total, 11 * 11 * 11);  // i from floor(-1.05/0.3)−1 = −5 to 5
    // Shifted by a voxel, it must misclassify some.
    const MeshEvaluation moved = evaluate_mesh(icosphere(4, 1.0, Vec3(0.3, 0, 0)), make_shape("sphere1"), fast_options(0.3));
    EXPECT_LT(moved.voxels.share(), 0.99);
}

TEST(ClassifyVoxelCentres, CountsTheObjectAndTheVoxelsNextToTheSurfaceApart) {
    // A 4×4×4 block of object voxels (indices 2…5) in an 8³ grid.
    const BinaryVolume volume = test::make_volume({8, 8, 8}, [](double x, double y, double z) {
        return x >= 2 && x <= 5 && y >= 2 && y <= 5 && z >= 2 && z <= 5;
    });
    // Its exact boundary: every centre agrees.
    const VoxelClassification exact = classify_voxel_centres(box_mesh(Vec3(1.5, 1.5, 1.5), Vec3(5.5, 5.5, 5.5), 4), volume);
    EXPECT_EQ(exact.correct, 512);
    EXPECT_EQ(exact.object_correct, 64);
    EXPECT_EQ(exact.object_total, 64);
    // Next to the surface: the 56 outer object voxels and the 6·16 background voxels facing them.
    EXPECT_EQ(exact.boundary_total, 56 + 96);
    EXPECT_EQ(exact.boundary_correct, 56 + 96);
    // Shrunk to the 2×2×2 core: the 56 outer object voxels fall outside.
    const VoxelClassification shrunk = classify_voxel_centres(box_mesh(Vec3(2.5, 2.5, 2.5), Vec3(4.5, 4.5, 4.5), 2), volume);
    EXPECT_EQ(shrunk.correct, 512 - 56);
    EXPECT_EQ(shrunk.object_correct, 8);
    EXPECT_EQ(shrunk.boundary_correct, 96);
    EXPECT_NEAR(shrunk.boundary_share(), 96.0 / 152.0, 1e-15);
    // Grown by a voxel: the 96 background voxels next to the surface fall inside (and 56 more at
    // the edges and corners of the grown box, which are not next to the surface).
    const VoxelClassification grown = classify_voxel_centres(box_mesh(Vec3(0.5, 0.5, 0.5), Vec3(6.5, 6.5, 6.5), 6), volume);
    EXPECT_EQ(grown.object_correct, 64);
    EXPECT_EQ(grown.boundary_correct, 56);
    EXPECT_EQ(grown.correct, 512 - (216 - 64));
}

TEST(EvaluateMesh, BoxAgainstAPlaneClippedBlockLeavesOutTheWalls) {
    // The solid z ≤ 0.5 clipped by [-1,1]³ is the block [-1,1]²×[-1,0.5]. Its box mesh: the only
    // part of F = 0 is the top face; the other faces lie on the box walls and are left out.
    const ImplicitShape block = make_plane_shape(Vec3(0, 0, 1), 0.5, 1.0);
    const PolygonMesh mesh = box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 0.5), 8);
    MeshEvaluationOptions options = fast_options(0.3);
    options.wall_margin = 0.2;
    const MeshEvaluation e = evaluate_mesh(mesh, block, options);
    EXPECT_GT(e.vertices_evaluated, 0);
    EXPECT_GT(e.vertices_outside_region, 0);
    EXPECT_EQ(e.vertices_evaluated, 7 * 7);  // top-face vertices with |x|, |y| ≤ 0.8: x = −0.75 … 0.75
    EXPECT_EQ(e.vertex_distance.linf, 0.0);
    EXPECT_EQ(e.faces_evaluated, 6 * 6);
    EXPECT_LT(e.normal_angle_deg.linf, 1e-12);
    EXPECT_NEAR(e.relative_volume_error, 0.0, 1e-6);  // accuracy of shape_volume()
    EXPECT_EQ(e.voxels.correct, e.voxels.total);  // no voxel centre on a face at h = 0.3
    // Side quads are 0.25 × 0.1875 rectangles: their triangles' smallest angle is atan(0.75).
    EXPECT_NEAR(e.triangle_min_angle_min_deg, std::atan(0.75) * 180 / pi, 1e-9);
}

TEST(EvaluateMesh, RejectsEmptyAndMalformedMeshes) {
    EXPECT_THROW(evaluate_mesh(PolygonMesh{}, make_shape("sphere1"), fast_options()), Error);
    PolygonMesh bad = octahedron();
    bad.faces(0, 0) = 99;
    EXPECT_THROW(evaluate_mesh(bad, make_shape("sphere1"), fast_options()), Error);
}

// ---------------------------------------------------------------------------------------------
// The `dsreg eval` job (evaluation_report.hpp)

EvaluationRequest sphere_request(double h) {
    EvaluationRequest request;
    request.truth.shape = "sphere1";
    request.h = h;
    request.volume_cells = 16;
    return request;
}

TEST(RunEvaluation, VoxelCoordinatesMapTheMeshBackToTheShapesFrame) {
    const double h = 0.1;
    const PolygonMesh mesh = icosphere(3);
    const VoxelGrid grid = digitize(make_shape("sphere1"), h).grid;
    PolygonMesh in_voxels = mesh;  // the same mesh in the digitization's voxel frame
    for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
        in_voxels.vertices.row(i) = (mesh.vertices.row(i) - grid.voxel_center(0, 0, 0).transpose()).cwiseQuotient(grid.spacing.transpose());

    EvaluationRequest request = sphere_request(h);
    const EvaluationRun direct = run_evaluation(mesh, "m", request);
    request.voxel_coordinates = true;
    const EvaluationRun mapped = run_evaluation(in_voxels, "m", request);
    EXPECT_NEAR(mapped.evaluation.vertex_distance.linf, direct.evaluation.vertex_distance.linf, 1e-12);
    EXPECT_NEAR(mapped.evaluation.normal_angle_deg.mean, direct.evaluation.normal_angle_deg.mean, 1e-9);
    EXPECT_EQ(mapped.evaluation.voxels.correct, direct.evaluation.voxels.correct);
    EXPECT_LT(direct.evaluation.vertex_distance.linf, 0.01);  // the icosphere lies on the unit sphere
}

TEST(RunEvaluation, FoldedFacesAreCountedAgainstTheMeshsOwnField) {
    PolygonMesh mesh = icosphere(2);
    const EvaluationRequest request = sphere_request(0.2);
    const nlohmann::json without = evaluation_report(run_evaluation(mesh, "m", request), "m");
    EXPECT_TRUE(without["validity"]["folded_faces"].is_null());
    EXPECT_EQ(without["validity"]["intersecting_pairs"], 0);

    mesh.face_normals = face_normals(mesh.vertices, mesh.faces);
    EXPECT_EQ(run_evaluation(mesh, "m", request).validity.folded_faces, 0);
    mesh.face_normals = -mesh.face_normals;
    const EvaluationRun against = run_evaluation(mesh, "m", request);
    EXPECT_EQ(against.validity.folded_faces, mesh.faces.rows());
    EXPECT_EQ(evaluation_report(against, "m")["validity"]["folded_faces"], mesh.faces.rows());
}

TEST(RunEvaluation, VolumeExcludesTheShapesFlagsAndShapeFlagsNeedAShape) {
    EvaluationRequest request = sphere_request(0.1);
    request.volume = "v.vol";
    EXPECT_THROW(check_evaluation_request(request), Error);  // --volume with --shape and --h
    EvaluationRequest no_truth;
    EXPECT_THROW(check_evaluation_request(no_truth), Error);
    EvaluationRequest range = sphere_request(0.1);
    range.min_value = 1.0;
    EXPECT_THROW(check_evaluation_request(range), Error);
    EXPECT_TRUE(check_evaluation_request(sphere_request(0.1)).has_value());
}

// ---------------------------------------------------------------------------------------------
// The multigrid convergence experiment (Fig. 7) on a tilted plane and on sphere1

struct ExperimentCase {
    const char* name;
    ImplicitShape shape;
    double wall_margin;
};

std::vector<ExperimentCase> experiment_cases() {
    return {{"tilted plane", make_plane_shape(Vec3(1, std::sqrt(2.0), std::sqrt(3.0)), 0.01, 1.0), 0.25},
            {"sphere1", make_shape("sphere1"), 0.0}};
}

/// The claims over 4 grid steps h = 0.2 … 0.05 (Fig. 7, α = 1e-5·h², β = 1, γ = 0):
/// the digital surface is within √3/2·h of ∂X, p* is closer to ∂X than p at every h (L2 and
/// L∞), and the p and p* errors decrease at least like h^0.9.
void expect_paper_claims(const ExperimentCase& c, ConvergenceOptions options) {
    const std::vector<double> steps = geometric_steps(0.2, 0.05, 4);
    options.wall_margin = c.wall_margin;
    std::vector<ConvergenceStep> results;
    for (double h : steps) {
        const ConvergenceStep s = run_convergence_step(c.shape, h, options);
        SCOPED_TRACE(std::string(c.name) + " at h = " + std::to_string(h));
        EXPECT_GT(s.vertices_evaluated, 50);
        EXPECT_LT(s.relative_residual, 1e-6);
        // Gauss digitization: the digital surface is within √3/2·h of ∂X (paper §2, [11]).
        EXPECT_LE(s.p.linf, std::sqrt(3.0) / 2.0 * h);
        // The paper's claim (Fig. 7, last row): p* is closer to ∂X than p.
        EXPECT_LT(s.pstar.l2, s.p.l2);
        EXPECT_LT(s.pstar.linf, s.p.linf);
        results.push_back(s);
    }
    const ConvergenceSlopes slopes = convergence_slopes(results);
    EXPECT_GE(slopes.p.l2, 0.9) << c.name;
    EXPECT_GE(slopes.p.linf, 0.9) << c.name;
    EXPECT_GE(slopes.pstar.l2, 0.9) << c.name;
    EXPECT_GE(slopes.pstar.linf, 0.9) << c.name;
}

TEST(Convergence, DigitalAndRegularizedSurfacesConvergeInOhAndRegularizedIsCloser) {
    for (const ExperimentCase& c : experiment_cases()) expect_paper_claims(c, ConvergenceOptions{});  // exact normals
}

ConvergenceOptions integral_invariant_input() {
    ConvergenceOptions options;
    options.normals = InputNormalField::IntegralInvariant;
    options.radius_k = 1.0;  // r = h^(1/3): 0.58 (2.9 voxels) at h = 0.2, 0.37 (7.4 voxels) at h = 0.05
    return options;
}

TEST(Convergence, IntegralInvariantInputOnTheSphere) { expect_paper_claims(experiment_cases()[1], integral_invariant_input()); }

// The plane is clipped by [-1,1]³: its II input must not see the box walls (the balls of faces
// within r of a wall would be truncated, and with α = 1e-5·h² the biased normals there make the
// whole plane part drift along its normal, farther from ∂X than the digital surface; see
// integral_invariant_input in src/evaluation/convergence.cpp and docs/convergence.md).
TEST(Convergence, IntegralInvariantInputOnTheTiltedPlane) {
    expect_paper_claims(experiment_cases()[0], integral_invariant_input());
}

TEST(Convergence, IntegralInvariantFieldAndOptionChecks) {
    ConvergenceOptions options;
    options.normals = InputNormalField::IntegralInvariant;
    const ConvergenceStep s = run_convergence_step(make_shape("sphere1"), 0.1, options);
    EXPECT_NEAR(s.radius, 3.0 * std::cbrt(0.1), 1e-15);
    EXPECT_NEAR(s.alpha, 1e-5 * 0.01, 1e-20);
    EXPECT_LT(s.pstar.l2, s.p.l2);
    options.radius_k = 0;
    EXPECT_THROW(run_convergence_step(make_shape("sphere1"), 0.1, options), Error);
    ConvergenceOptions margin;
    margin.wall_margin = 5.0;  // nothing left in [-1,1]³
    EXPECT_THROW(run_convergence_step(make_plane_shape(Vec3(1, 1, 1), 0, 1), 0.2, margin), Error);
}

// ---------------------------------------------------------------------------------------------
// Plots

TEST(Plot, SvgHasOnePathPerCurveAndTheSlopesInTheLegend) {
    std::vector<ConvergenceStep> steps;
    for (double h : geometric_steps(0.2, 0.02, 5)) {
        ConvergenceStep s;
        s.h = h;
        s.normal = {0.1 * h, 0.3 * h};
        s.p = {0.4 * h, 0.8 * h};
        s.pstar = {0.01 * h * h, 0.03 * h * h};
        s.ratio = {s.pstar.l2 / s.p.l2, s.pstar.linf / s.p.linf};
        steps.push_back(s);
    }
    const std::string svg = convergence_plot_svg("test <plot> & more", steps);
    EXPECT_EQ(svg.rfind("<svg", 0), 0u);
    EXPECT_NE(svg.find("</svg>"), std::string::npos);
    EXPECT_NE(svg.find("test &lt;plot&gt; &amp; more"), std::string::npos);
    std::size_t paths = 0;
    for (std::size_t at = svg.find("<path"); at != std::string::npos; at = svg.find("<path", at + 1)) ++paths;
    EXPECT_EQ(paths, 8u);  // 4 panels × (L2, L∞)
    EXPECT_NE(svg.find("slope 1.00"), std::string::npos);
    EXPECT_NE(svg.find("slope 2.00"), std::string::npos);
}

TEST(Plot, EachAxisWritesItsTicksInOneFormatAndTheLegendAvoidsTheCurves) {
    // y from 5e-4 to 2e-2 has the ticks 10⁻³ and 10⁻²: both as powers of ten, not "0.01" next to
    // "10⁻³". x from 0.05 to 0.2 has the ticks 0.05, 0.1, 0.2: plain decimals.
    PlotPanel panel;
    panel.title = "t";
    panel.y_label = "y";
    panel.reference_slope_one = false;
    panel.curves = {PlotCurve{"rising", {0.05, 0.1, 0.2}, {5e-4, 3e-3, 2e-2}}};
    const std::string svg = log_log_plot_svg("title", "h", {panel}, 1);
    EXPECT_NE(svg.find(">10<tspan dy=\"-6\" font-size=\"9\">\u22122</tspan>"), std::string::npos);
    EXPECT_NE(svg.find(">10<tspan dy=\"-6\" font-size=\"9\">\u22123</tspan>"), std::string::npos);
    EXPECT_EQ(svg.find(">0.01<"), std::string::npos);
    EXPECT_NE(svg.find(">0.05<"), std::string::npos);
    EXPECT_NE(svg.find(">0.1<"), std::string::npos);
    EXPECT_NE(svg.find(">0.2<"), std::string::npos);
    // The curve rises from bottom-left to top-right: the legend box goes to the top-left corner
    // (left_ + 5 = 77, top_ + 4 = 72, title height 34 included). A falling curve sends it to the
    // top-right corner (right_ − 5 − 150 = 229).
    EXPECT_NE(svg.find("<rect x=\"77.00\" y=\"72.00\" width=\"150.00\""), std::string::npos);
    panel.curves = {PlotCurve{"falling", {0.05, 0.1, 0.2}, {2e-2, 3e-3, 5e-4}}};
    const std::string falling = log_log_plot_svg("title", "h", {panel}, 1);
    EXPECT_NE(falling.find("<rect x=\"229.00\" y=\"72.00\" width=\"150.00\""), std::string::npos);
}

}  // namespace
}  // namespace dsreg
