// Tests of the mesh files module: triangulation, round trips through every format, reading of
// files written by other tools, and rejection of broken files and failed writes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/mesh_io.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using dsreg::test::error_message;
using dsreg::FaceMatrix;
using dsreg::PointMatrix;
using dsreg::PolygonMesh;

// ---- helpers -----------------------------------------------------------------------------------

/// Unit cube [0,1]³ as 6 outward quads; vertex (x,y,z) has index x + 2y + 4z. Face normals are
/// the outward axis vectors; two vertex scalars, one not exactly representable as a float.
PolygonMesh make_unit_cube() {
    PolygonMesh cube;
    cube.vertices.resize(8, 3);
    for (int i = 0; i < 8; ++i) cube.vertices.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
    cube.faces.resize(6, 4);
    cube.faces << 0, 2, 3, 1,  // z = 0
        4, 5, 7, 6,            // z = 1
        0, 1, 5, 4,            // y = 0
        2, 6, 7, 3,            // y = 1
        0, 4, 6, 2,            // x = 0
        1, 3, 7, 5;            // x = 1
    cube.face_normals.resize(6, 3);
    cube.face_normals << 0, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, 0;
    Eigen::VectorXd height = 0.5 * cube.vertices.col(2).array() + 0.25;
    Eigen::VectorXd third = Eigen::VectorXd::LinSpaced(8, 0.0, 7.0) / 3.0;
    cube.vertex_scalars = {{"height", height}, {"third", third}};
    return cube;
}

/// The unit cube moved to coordinates that have no short decimal form.
PolygonMesh make_awkward_cube() {
    PolygonMesh cube = make_unit_cube();
    for (Eigen::Index v = 0; v < 8; ++v) {
        cube.vertices.row(v) = cube.vertices.row(v) / 3.0 + Eigen::RowVector3d(0.1, -1e-7, 12345.678);
    }
    return cube;
}

Eigen::Vector3d vertex(const PolygonMesh& mesh, std::int32_t index) { return mesh.vertices.row(index).transpose(); }

/// The faces as triangles (quads split by the function under test elsewhere; here by a fan, which
/// is enough for volumes and areas of planar quads).
std::vector<std::array<std::int32_t, 3>> fan_triangles(const PolygonMesh& mesh) {
    std::vector<std::array<std::int32_t, 3>> triangles;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        for (Eigen::Index k = 1; k + 1 < mesh.faces.cols(); ++k) {
            triangles.push_back({mesh.faces(f, 0), mesh.faces(f, k), mesh.faces(f, k + 1)});
        }
    }
    return triangles;
}

/// Volume enclosed by a closed mesh; positive when its faces are oriented outward.
double signed_volume(const PolygonMesh& mesh) {
    double volume = 0.0;
    for (const auto& t : fan_triangles(mesh)) {
        volume += vertex(mesh, t[0]).dot(vertex(mesh, t[1]).cross(vertex(mesh, t[2]))) / 6.0;
    }
    return volume;
}

Eigen::Vector3d triangle_area_vector(const PolygonMesh& mesh, std::int32_t a, std::int32_t b, std::int32_t c) {
    return 0.5 * (vertex(mesh, b) - vertex(mesh, a)).cross(vertex(mesh, c) - vertex(mesh, a));
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream content;
    content << in.rdbuf();
    return content.str();
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Appends numbers in a chosen byte order, to build binary PLY files by hand.
class ByteWriter {
public:
    explicit ByteWriter(bool big_endian) : big_endian_(big_endian) {}
    template <class T>
    ByteWriter& put(T value) {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        const std::uint16_t probe = 1;
        const bool host_little = *reinterpret_cast<const unsigned char*>(&probe) == 1;
        if (big_endian_ == host_little) std::reverse(bytes, bytes + sizeof(T));
        data.append(bytes, sizeof(T));
        return *this;
    }
    std::string data;

private:
    bool big_endian_;
};

class MeshIoTest : public ::testing::Test {
protected:
    void SetUp() override {
        const std::string test_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        directory_ = fs::temp_directory_path() / ("dsreg_test_mesh_io_" + std::to_string(::getpid()) + "_" + test_name);
        fs::remove_all(directory_);
        fs::create_directories(directory_);
    }
    void TearDown() override { fs::remove_all(directory_); }

    std::string path(const std::string& name) const { return (directory_ / name).string(); }

    std::vector<std::string> directory_entries() const {
        std::vector<std::string> names;
        for (const auto& entry : fs::directory_iterator(directory_)) names.push_back(entry.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }

    fs::path directory_;
};

// ---- triangulate_shorter_diagonal --------------------------------------------------------------

PolygonMesh single_quad(const std::array<Eigen::Vector3d, 4>& corners) {
    PolygonMesh mesh;
    mesh.vertices.resize(4, 3);
    for (int i = 0; i < 4; ++i) mesh.vertices.row(i) = corners[static_cast<std::size_t>(i)].transpose();
    mesh.faces.resize(1, 4);
    mesh.faces << 0, 1, 2, 3;
    return mesh;
}

TEST(TriangulateShorterDiagonal, SplitsAlongAcWhenItIsShorter) {
    // Rhombus, counter-clockwise seen from +z: |ac| = 2, |bd| = 6, area 6.
    const PolygonMesh quad = single_quad(
        {Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 3, 0)});
    const PolygonMesh result = dsreg::triangulate_shorter_diagonal(quad);
    ASSERT_EQ(result.faces.rows(), 2);
    ASSERT_EQ(result.faces.cols(), 3);
    EXPECT_EQ(result.faces.row(0), (Eigen::RowVector3i(0, 1, 2)));
    EXPECT_EQ(result.faces.row(1), (Eigen::RowVector3i(0, 2, 3)));
    double area = 0.0;
    for (Eigen::Index t = 0; t < 2; ++t) {
        const Eigen::Vector3d n =
            triangle_area_vector(result, result.faces(t, 0), result.faces(t, 1), result.faces(t, 2));
        EXPECT_GT(n.z(), 0.0) << "triangle " << t << " is flipped";
        area += n.norm();
    }
    EXPECT_NEAR(area, 6.0, 1e-12);
}

TEST(TriangulateShorterDiagonal, SplitsAlongBdWhenItIsShorter) {
    // The same rhombus starting one corner later: now |ac| = 6 and |bd| = 2.
    const PolygonMesh quad = single_quad(
        {Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 3, 0), Eigen::Vector3d(-1, 0, 0)});
    const PolygonMesh result = dsreg::triangulate_shorter_diagonal(quad);
    ASSERT_EQ(result.faces.rows(), 2);
    EXPECT_EQ(result.faces.row(0), (Eigen::RowVector3i(0, 1, 3)));
    EXPECT_EQ(result.faces.row(1), (Eigen::RowVector3i(1, 2, 3)));
    double area = 0.0;
    for (Eigen::Index t = 0; t < 2; ++t) {
        const Eigen::Vector3d n =
            triangle_area_vector(result, result.faces(t, 0), result.faces(t, 1), result.faces(t, 2));
        EXPECT_GT(n.z(), 0.0) << "triangle " << t << " is flipped";
        area += n.norm();
    }
    EXPECT_NEAR(area, 6.0, 1e-12);
}

TEST(TriangulateShorterDiagonal, NonPlanarQuadKeepsOrientationAndUsesShorterDiagonal) {
    // A twisted quad: b and d are lifted, so the split changes the surface; the shorter diagonal
    // here is bd (|ac|² = 20.25 + 1, |bd|² = 1 + 1).
    const PolygonMesh quad = single_quad(
        {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0.5), Eigen::Vector3d(4.5, 1, 0), Eigen::Vector3d(1, 1, 0.5)});
    const PolygonMesh result = dsreg::triangulate_shorter_diagonal(quad);
    ASSERT_EQ(result.faces.rows(), 2);
    // Both triangles contain the diagonal (1, 3).
    for (Eigen::Index t = 0; t < 2; ++t) {
        const auto row = result.faces.row(t);
        EXPECT_TRUE((row.array() == 1).any() && (row.array() == 3).any()) << "triangle " << t << ": " << row;
    }
    // Vector area of the quad (independent of the split): ½ (c − a) × (d − b).
    const Eigen::Vector3d quad_area =
        0.5 * (vertex(quad, 2) - vertex(quad, 0)).cross(vertex(quad, 3) - vertex(quad, 1));
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (Eigen::Index t = 0; t < 2; ++t) {
        const Eigen::Vector3d n =
            triangle_area_vector(result, result.faces(t, 0), result.faces(t, 1), result.faces(t, 2));
        EXPECT_GT(n.dot(quad_area), 0.0) << "triangle " << t << " is flipped";
        total += n;
    }
    // The vector area of a closed boundary does not depend on the surface spanning it.
    EXPECT_NEAR((total - quad_area).norm(), 0.0, 1e-12);
}

TEST(TriangulateShorterDiagonal, DuplicatesFaceNormalsAndKeepsVertexScalars) {
    const PolygonMesh cube = make_unit_cube();
    const PolygonMesh result = dsreg::triangulate_shorter_diagonal(cube);
    ASSERT_EQ(result.faces.rows(), 12);
    ASSERT_EQ(result.face_normals.rows(), 12);
    for (Eigen::Index q = 0; q < 6; ++q) {
        EXPECT_EQ(result.face_normals.row(2 * q), cube.face_normals.row(q));
        EXPECT_EQ(result.face_normals.row(2 * q + 1), cube.face_normals.row(q));
        for (Eigen::Index t = 2 * q; t < 2 * q + 2; ++t) {
            const Eigen::Vector3d n =
                triangle_area_vector(result, result.faces(t, 0), result.faces(t, 1), result.faces(t, 2));
            EXPECT_NEAR(n.normalized().dot(cube.face_normals.row(q)), 1.0, 1e-12) << "triangle " << t;
        }
    }
    EXPECT_EQ(result.vertices, cube.vertices);
    ASSERT_EQ(result.vertex_scalars.size(), 2u);
    EXPECT_EQ(result.vertex_scalars[1].first, "third");
    EXPECT_EQ(result.vertex_scalars[1].second, cube.vertex_scalars[1].second);
    EXPECT_NEAR(signed_volume(result), 1.0, 1e-12);
}

TEST(TriangulateShorterDiagonal, ReturnsTriangleMeshesUnchanged) {
    const PolygonMesh triangles = dsreg::triangulate_shorter_diagonal(make_unit_cube());
    const PolygonMesh again = dsreg::triangulate_shorter_diagonal(triangles);
    EXPECT_EQ(again.faces, triangles.faces);
    EXPECT_EQ(again.face_normals, triangles.face_normals);
}

TEST(TriangulateShorterDiagonal, RejectsOutOfRangeIndices) {
    PolygonMesh cube = make_unit_cube();
    cube.faces(3, 2) = 8;
    EXPECT_CONTAINS(error_message([&] { dsreg::triangulate_shorter_diagonal(cube); }), "vertex 8");
}

// ---- round trips -------------------------------------------------------------------------------

TEST_F(MeshIoTest, ObjRoundTripKeepsQuadsAndExactPositions) {
    const PolygonMesh cube = make_awkward_cube();
    dsreg::write_mesh(path("cube.obj"), cube);
    const PolygonMesh read = dsreg::read_mesh(path("cube.obj"));
    EXPECT_EQ(read.vertices, cube.vertices);  // shortest round-trip decimal form
    EXPECT_EQ(read.faces, cube.faces);
    EXPECT_EQ(read.face_normals.rows(), 0);
    EXPECT_TRUE(read.vertex_scalars.empty());
}

TEST_F(MeshIoTest, OffRoundTripKeepsQuadsAndExactPositions) {
    const PolygonMesh cube = make_awkward_cube();
    dsreg::write_mesh(path("cube.off"), cube);
    const PolygonMesh read = dsreg::read_mesh(path("cube.off"));
    EXPECT_EQ(read.vertices, cube.vertices);
    EXPECT_EQ(read.faces, cube.faces);
    EXPECT_EQ(read.face_normals.rows(), 0);
}

TEST_F(MeshIoTest, PlyRoundTripKeepsEverything) {
    const PolygonMesh cube = make_awkward_cube();
    dsreg::write_mesh(path("cube.ply"), cube);
    const PolygonMesh read = dsreg::read_mesh(path("cube.ply"));
    EXPECT_EQ(read.vertices, cube.vertices);  // doubles, bit for bit
    EXPECT_EQ(read.faces, cube.faces);
    EXPECT_EQ(read.face_normals, cube.face_normals);
    ASSERT_EQ(read.vertex_scalars.size(), cube.vertex_scalars.size());
    for (std::size_t s = 0; s < cube.vertex_scalars.size(); ++s) {
        EXPECT_EQ(read.vertex_scalars[s].first, cube.vertex_scalars[s].first);
        // Scalars are stored as floats.
        const Eigen::VectorXd as_float = cube.vertex_scalars[s].second.cast<float>().cast<double>();
        EXPECT_EQ(read.vertex_scalars[s].second, as_float) << cube.vertex_scalars[s].first;
    }
}

TEST_F(MeshIoTest, PlyRoundTripOfTrianglesWithoutAttributes) {
    PolygonMesh mesh = dsreg::triangulate_shorter_diagonal(make_awkward_cube());
    mesh.face_normals.resize(0, 3);
    mesh.vertex_scalars.clear();
    dsreg::write_mesh(path("triangles.ply"), mesh);
    const PolygonMesh read = dsreg::read_mesh(path("triangles.ply"));
    EXPECT_EQ(read.vertices, mesh.vertices);
    EXPECT_EQ(read.faces, mesh.faces);
    EXPECT_EQ(read.face_normals.rows(), 0);
    EXPECT_TRUE(read.vertex_scalars.empty());
}

TEST_F(MeshIoTest, StlRoundTripGivesTwelveOutwardTrianglesOnTheCubeCorners) {
    const PolygonMesh cube = make_unit_cube();
    dsreg::write_mesh(path("cube.stl"), cube);
    EXPECT_EQ(fs::file_size(path("cube.stl")), 84u + 12u * 50u);
    const PolygonMesh read = dsreg::read_mesh(path("cube.stl"));
    ASSERT_EQ(read.faces.rows(), 12);
    ASSERT_EQ(read.faces.cols(), 3);
    // Shared corners are merged: exactly the 8 corners of the cube.
    std::set<std::array<double, 3>> corners, read_corners;
    for (Eigen::Index v = 0; v < 8; ++v)
        corners.insert({cube.vertices(v, 0), cube.vertices(v, 1), cube.vertices(v, 2)});
    for (Eigen::Index v = 0; v < read.vertices.rows(); ++v) {
        read_corners.insert({read.vertices(v, 0), read.vertices(v, 1), read.vertices(v, 2)});
    }
    EXPECT_EQ(read.vertices.rows(), 8);
    EXPECT_EQ(read_corners, corners);
    EXPECT_NEAR(signed_volume(read), 1.0, 1e-12);
    const Eigen::Vector3d center(0.5, 0.5, 0.5);
    for (Eigen::Index t = 0; t < 12; ++t) {
        const Eigen::Vector3d n = triangle_area_vector(read, read.faces(t, 0), read.faces(t, 1), read.faces(t, 2));
        const Eigen::Vector3d centroid =
            (vertex(read, read.faces(t, 0)) + vertex(read, read.faces(t, 1)) + vertex(read, read.faces(t, 2))) / 3.0;
        EXPECT_GT(n.dot(centroid - center), 0.0) << "triangle " << t << " points inward";
        EXPECT_NEAR(n.norm(), 0.5, 1e-12) << "triangle " << t;
    }
}

/// The facets of a binary STL file: 12 floats each (normal, then 3 corners).
std::vector<std::array<float, 12>> stl_facets(const std::string& bytes) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);  // tests run on little-endian hosts
    std::vector<std::array<float, 12>> facets(count);
    for (std::uint32_t t = 0; t < count; ++t) std::memcpy(facets[t].data(), bytes.data() + 84 + 50 * t, 48);
    return facets;
}

TEST_F(MeshIoTest, StlFacetNormalsAreGeometricAndZeroForDegenerateTriangles) {
    PolygonMesh mesh;
    mesh.vertices.resize(4, 3);
    mesh.vertices << 0, 0, 0, 2, 0, 0, 0, 3, 0, 4, 0, 0;  // vertex 3 lies on the line of 0 and 1
    mesh.faces.resize(2, 3);
    mesh.faces << 0, 2, 1,  // normal −z
        0, 1, 3;            // degenerate
    dsreg::write_mesh(path("normals.stl"), mesh);
    const auto facets = stl_facets(read_bytes(path("normals.stl")));
    ASSERT_EQ(facets.size(), 2u);
    EXPECT_EQ((std::array<float, 3>{facets[0][0], facets[0][1], facets[0][2]}), (std::array<float, 3>{0.f, 0.f, -1.f}));
    EXPECT_EQ((std::array<float, 3>{facets[1][0], facets[1][1], facets[1][2]}), (std::array<float, 3>{0.f, 0.f, 0.f}));
    // Corners in face order.
    EXPECT_EQ(facets[0][6], 0.f);
    EXPECT_EQ(facets[0][7], 3.f);
}

TEST_F(MeshIoTest, StlSplitsQuadsAlongTheShorterDiagonal) {
    // bd is the shorter diagonal: expect triangles (a,b,d), (b,c,d).
    PolygonMesh quad = single_quad(
        {Eigen::Vector3d(0, -3, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 3, 0), Eigen::Vector3d(-1, 0, 0)});
    dsreg::write_mesh(path("quad.stl"), quad);
    const auto facets = stl_facets(read_bytes(path("quad.stl")));
    ASSERT_EQ(facets.size(), 2u);
    const std::array<float, 9> first{0, -3, 0, 1, 0, 0, -1, 0, 0};
    const std::array<float, 9> second{1, 0, 0, 0, 3, 0, -1, 0, 0};
    EXPECT_TRUE(std::equal(first.begin(), first.end(), facets[0].begin() + 3));
    EXPECT_TRUE(std::equal(second.begin(), second.end(), facets[1].begin() + 3));
    EXPECT_EQ(facets[0][2], 1.f);  // both facets face +z
    EXPECT_EQ(facets[1][2], 1.f);
}

TEST_F(MeshIoTest, TextFormatsRoundTripArbitraryDoublesExactly) {
    std::mt19937_64 random(12345);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-300, 300);
    PolygonMesh mesh;
    mesh.vertices.resize(600, 3);
    for (Eigen::Index i = 0; i < mesh.vertices.size(); ++i)
        mesh.vertices.data()[i] = std::ldexp(mantissa(random), exponent(random));
    mesh.vertices(0, 0) = std::numeric_limits<double>::denorm_min();
    mesh.vertices(0, 1) = -std::numeric_limits<double>::max();
    mesh.vertices(0, 2) = -0.0;
    mesh.faces.resize(200, 3);
    for (Eigen::Index f = 0; f < 200; ++f) mesh.faces.row(f) << int(3 * f), int(3 * f + 1), int(3 * f + 2);
    for (const char* name : {"random.obj", "random.off", "random.ply"}) {
        dsreg::write_mesh(path(name), mesh);
        const PolygonMesh read = dsreg::read_mesh(path(name));
        EXPECT_EQ(read.vertices, mesh.vertices) << name;
        EXPECT_TRUE(std::signbit(read.vertices(0, 2))) << name;
        EXPECT_EQ(read.faces, mesh.faces) << name;
    }
}

TEST_F(MeshIoTest, ExtensionIsCaseInsensitive) {
    const PolygonMesh cube = make_unit_cube();
    for (const char* name : {"CUBE.OBJ", "cube.Off", "cube.PLY", "cube.Stl"}) {
        dsreg::write_mesh(path(name), cube);
        EXPECT_GT(dsreg::read_mesh(path(name)).faces.rows(), 0) << name;
    }
}

TEST_F(MeshIoTest, EmptyMeshRoundTrips) {
    const PolygonMesh empty;
    for (const char* name : {"empty.obj", "empty.off", "empty.ply", "empty.stl"}) {
        dsreg::write_mesh(path(name), empty);
        const PolygonMesh read = dsreg::read_mesh(path(name));
        EXPECT_EQ(read.vertices.rows(), 0) << name;
        EXPECT_EQ(read.faces.rows(), 0) << name;
    }
}

// ---- reading files from other tools -----------------------------------------------------------

TEST_F(MeshIoTest, ObjReaderHandlesReferenceFormsNegativeIndicesAndIgnoredStatements) {
    // A square pyramid: the base quad points down (−z), the sides up and out.
    write_bytes(path("pyramid.obj"),
                "# exported by some tool\r\n"
                "mtllib pyramid.mtl\n"
                "o pyramid\n"
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                "v +0.5 0.5 1.0 1.0   # apex, with a w coordinate\n"
                "vt 0 0\nvn 0 0 1\n"
                "g base\nusemtl stone\ns off\n"
                "f 1/1 4/1/1 3//1 2\n"
                "g sides\ns 1\n"
                "f -5 -4 -1\n"
                "f 2/1 3/1 5/1\n"
                "  f 3 4 5  \n"
                "f 4//1 1//1 5//1\n"
                "l 1 2\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("pyramid.obj"));
    ASSERT_EQ(mesh.vertices.rows(), 5);
    EXPECT_EQ(mesh.vertices.row(4), Eigen::RowVector3d(0.5, 0.5, 1.0));
    // Triangles and a quad: the quad is split (equal diagonals: along ac) and the order kept.
    FaceMatrix expected(6, 3);
    expected << 0, 3, 2, 0, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
    EXPECT_EQ(mesh.faces, expected);
    EXPECT_NEAR(signed_volume(mesh), 1.0 / 3.0, 1e-12);
}

TEST_F(MeshIoTest, OffReaderHandlesCommentsCountsOnTheKeywordLineAndFaceColours) {
    write_bytes(path("pyramid.off"),
                "# a pyramid\n"
                "OFF 5 5 0   # counts on the keyword line\n"
                "\n"
                "0 0 0\n1 0 0  # comment after a vertex\n1 1 0\n0 1 0\n0.5 0.5 1\n"
                "# faces\n"
                "4 0 3 2 1  255 0 0\n"
                "3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4 0.5 0.5 0.5 1\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("pyramid.off"));
    ASSERT_EQ(mesh.vertices.rows(), 5);
    ASSERT_EQ(mesh.faces.rows(), 6);
    EXPECT_EQ(mesh.faces.cols(), 3);
    EXPECT_NEAR(signed_volume(mesh), 1.0 / 3.0, 1e-12);
}

TEST_F(MeshIoTest, OffReaderAcceptsColouredVariant) {
    write_bytes(path("quad.off"),
                "COFF\n4 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 9 9 9 255\n4 0 1 2 3\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("quad.off"));
    EXPECT_EQ(mesh.vertices.row(2), Eigen::RowVector3d(1, 1, 0));
    EXPECT_EQ(mesh.faces, (FaceMatrix(1, 4) << 0, 1, 2, 3).finished());
}

TEST_F(MeshIoTest, AsciiPlyReaderSkipsUnknownElementsAndProperties) {
    write_bytes(path("ascii.ply"),
                "ply\r\n"
                "format ascii 1.0\r\n"
                "comment made by hand\r\n"
                "obj_info nothing\r\n"
                "element vertex 4\r\n"
                "property float x\r\nproperty float y\r\nproperty double z\r\n"
                "property list uchar int neighbours\r\n"
                "property uchar red\r\n"
                "element edge 2\r\n"
                "property list uchar uint vertex_pair\r\nproperty int crease\r\n"
                "element face 2\r\n"
                "property int flags\r\n"
                "property list uint ushort vertex_index\r\n"
                "property float nx\r\n"  // incomplete normal: skipped
                "end_header\r\n"
                "0 0 0 2 1 3 10\r\n"
                "1 0 0 0 20\r\n"
                "1 1 0 1 0 30\r\n"
                "0 1 0 3 0 1 2 40\r\n"
                "2 0 1 7\r\n2 1 2 8\r\n"
                "5 3 0 1 2 0.5\r\n"
                "6 3 0 2 3 0.5\r\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("ascii.ply"));
    PointMatrix expected_vertices(4, 3);
    expected_vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
    EXPECT_EQ(mesh.vertices, expected_vertices);
    EXPECT_EQ(mesh.faces, (FaceMatrix(2, 3) << 0, 1, 2, 0, 2, 3).finished());
    EXPECT_EQ(mesh.face_normals.rows(), 0);
    ASSERT_EQ(mesh.vertex_scalars.size(), 1u);
    EXPECT_EQ(mesh.vertex_scalars[0].first, "red");
    EXPECT_EQ(mesh.vertex_scalars[0].second, Eigen::Vector4d(10, 20, 30, 40));
}

/// A binary PLY of a unit square pyramid with a quad base, written with other types than dsreg
/// uses, an element to skip, and face normals.
std::string hand_made_binary_ply(bool big_endian) {
    std::string header = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                         " 1.0\n"
                         "element vertex 5\n"
                         "property float x\nproperty float y\nproperty float z\nproperty char q\n"
                         "element material 1\n"
                         "property list uchar float colour\nproperty ushort id\n"
                         "element face 5\n"
                         "property list ushort uint vertex_indices\n"
                         "property double nx\nproperty double ny\nproperty double nz\n"
                         "property list int uchar tags\n"
                         "end_header\n";
    ByteWriter bytes(big_endian);
    const float positions[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
    for (int v = 0; v < 5; ++v)
        bytes.put(positions[v][0]).put(positions[v][1]).put(positions[v][2]).put(std::int8_t(-v));
    bytes.put(std::uint8_t(3)).put(0.25f).put(0.5f).put(1.0f).put(std::uint16_t(7));
    const std::vector<std::vector<std::uint32_t>> faces = {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
    for (std::size_t f = 0; f < faces.size(); ++f) {
        bytes.put(std::uint16_t(faces[f].size()));
        for (std::uint32_t index : faces[f]) bytes.put(index);
        bytes.put(double(f)).put(-double(f)).put(0.5);
        bytes.put(std::int32_t(2)).put(std::uint8_t(1)).put(std::uint8_t(2));
    }
    return header + bytes.data;
}

TEST_F(MeshIoTest, BinaryPlyReaderHandlesBothByteOrdersAndMixedFaces) {
    for (const bool big_endian : {false, true}) {
        SCOPED_TRACE(big_endian ? "big endian" : "little endian");
        write_bytes(path("pyramid.ply"), hand_made_binary_ply(big_endian));
        const PolygonMesh mesh = dsreg::read_mesh(path("pyramid.ply"));
        ASSERT_EQ(mesh.vertices.rows(), 5);
        EXPECT_EQ(mesh.vertices.row(4), Eigen::RowVector3d(0.5, 0.5, 1));
        ASSERT_EQ(mesh.vertex_scalars.size(), 1u);
        EXPECT_EQ(mesh.vertex_scalars[0].first, "q");
        EXPECT_EQ(mesh.vertex_scalars[0].second(3), -3.0);
        FaceMatrix expected_faces(6, 3);
        expected_faces << 0, 3, 2, 0, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4;
        EXPECT_EQ(mesh.faces, expected_faces);
        ASSERT_EQ(mesh.face_normals.rows(), 6);
        EXPECT_EQ(mesh.face_normals.row(0), Eigen::RowVector3d(0, 0, 0.5));  // the quad's normal, twice
        EXPECT_EQ(mesh.face_normals.row(1), Eigen::RowVector3d(0, 0, 0.5));
        EXPECT_EQ(mesh.face_normals.row(5), Eigen::RowVector3d(4, -4, 0.5));
        EXPECT_NEAR(signed_volume(mesh), 1.0 / 3.0, 1e-12);
    }
}

TEST_F(MeshIoTest, AsciiStlReaderMergesSharedCorners) {
    // A tetrahedron with outward facets; keywords in mixed case, a second solid.
    write_bytes(
        path("tetra.stl"),
        "solid tetra made by hand\n"
        "facet normal 0 0 -1\n outer loop\n  vertex 0 0 0\n  vertex 0 1 0\n  vertex 1 0 0\n endloop\nendfacet\n"
        "facet normal 0 -1 0\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 0 1\n endloop\nendfacet\n"
        "endsolid tetra made by hand\n"
        "SOLID second\n"
        "FACET NORMAL -1 0 0\n OUTER LOOP\n  VERTEX 0 0 0\n  VERTEX 0 0 1\n  VERTEX 0 1 0\n ENDLOOP\nENDFACET\n"
        "facet normal 1 1 1\n outer loop\n  vertex 1 0 0\n  vertex 0 1 0\n  vertex 0 0 1e0\n endloop\nendfacet\n"
        "ENDSOLID second\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("tetra.stl"));
    EXPECT_EQ(mesh.vertices.rows(), 4);
    EXPECT_EQ(mesh.faces.rows(), 4);
    EXPECT_NEAR(signed_volume(mesh), 1.0 / 6.0, 1e-15);
}

TEST_F(MeshIoTest, BinaryStlWhoseHeaderStartsWithSolidIsStillBinary) {
    dsreg::write_mesh(path("cube.stl"), make_unit_cube());
    std::string bytes = read_bytes(path("cube.stl"));
    bytes.replace(0, 11, "solid cube ");
    write_bytes(path("cube.stl"), bytes);
    const PolygonMesh mesh = dsreg::read_mesh(path("cube.stl"));
    EXPECT_EQ(mesh.faces.rows(), 12);
    EXPECT_NEAR(signed_volume(mesh), 1.0, 1e-12);
}

// ---- broken files ------------------------------------------------------------------------------

TEST_F(MeshIoTest, ObjOutOfRangeIndexIsReportedWithLine) {
    write_bytes(path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 57\n");
    const std::string message = error_message([&] { dsreg::read_mesh(path("bad.obj")); });
    EXPECT_CONTAINS(message, path("bad.obj") + ":5:");
    EXPECT_CONTAINS(message, "vertex 57");
    EXPECT_CONTAINS(message, "only 3 vertices");
}

TEST_F(MeshIoTest, ObjIndicesOutOfRangeInOtherFormsAreRejected) {
    for (const char* face :
         {"f 1 2 -4", "f 1 2 0", "f 1 2 4/1/1", "f 1 2 3//x", "f 1 2 3/", "f 1 2 3/1/1/1", "f 1 2 z"}) {
        write_bytes(path("bad.obj"), std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\n") + face + "\n");
        EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("bad.obj")); }), path("bad.obj") + ":4:") << face;
    }
}

TEST_F(MeshIoTest, ObjFaceUsingAVertexDefinedLaterIsRejected) {
    write_bytes(path("later.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("later.obj")); }), "vertex 3 but only 2 vertices");
}

TEST_F(MeshIoTest, ObjPolygonsOtherThanTrianglesAndQuadsAreRejected) {
    write_bytes(path("pentagon.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf 1 2 3 4 5\n");
    std::string message = error_message([&] { dsreg::read_mesh(path("pentagon.obj")); });
    EXPECT_CONTAINS(message, path("pentagon.obj") + ":6:");
    EXPECT_CONTAINS(message, "5 vertices");
    write_bytes(path("edge.obj"), "v 0 0 0\nv 1 0 0\nf 1 2\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("edge.obj")); }), "2 vertices");
}

TEST_F(MeshIoTest, GarbageTokensAreRejected) {
    write_bytes(path("garbage.obj"), "v 0 0 0\nv 1 abc 0\n");
    std::string message = error_message([&] { dsreg::read_mesh(path("garbage.obj")); });
    EXPECT_CONTAINS(message, path("garbage.obj") + ":2:");
    EXPECT_CONTAINS(message, "'abc'");

    write_bytes(path("statement.obj"), "v 0 0 0\nvertex 1 0 0\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("statement.obj")); }), "unknown OBJ statement 'vertex'");

    write_bytes(path("nan.obj"), "v 0 0 nan\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("nan.obj")); }), "non-finite");

    write_bytes(path("garbage.off"), "OFF\n3 1 0\n0 0 0\n1 0x1 0\n0 1 0\n3 0 1 2\n");
    message = error_message([&] { dsreg::read_mesh(path("garbage.off")); });
    EXPECT_CONTAINS(message, path("garbage.off") + ":4:");
    EXPECT_CONTAINS(message, "'0x1'");

    write_bytes(path("garbage.ply"),
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n0 1 zero\n3 0 1 2\n");
    message = error_message([&] { dsreg::read_mesh(path("garbage.ply")); });
    EXPECT_CONTAINS(message, path("garbage.ply") + ":12:");
    EXPECT_CONTAINS(message, "'zero'");

    write_bytes(path("garbage.stl"),
                "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 oops\n");
    message = error_message([&] { dsreg::read_mesh(path("garbage.stl")); });
    EXPECT_CONTAINS(message, path("garbage.stl") + ":6:");
    EXPECT_CONTAINS(message, "'oops'");

    write_bytes(path("random.stl"), "this is not an stl file");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("random.stl")); }), path("random.stl"));
}

TEST_F(MeshIoTest, OffOutOfRangeIndexAndShortFileAreRejected) {
    write_bytes(path("bad.off"), "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    std::string message = error_message([&] { dsreg::read_mesh(path("bad.off")); });
    EXPECT_CONTAINS(message, path("bad.off") + ":6:");
    EXPECT_CONTAINS(message, "vertex 3 but only 3 vertices");

    // Long enough for the counts, but the second face is missing.
    write_bytes(path("short.off"), "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# a long comment, a long comment\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("short.off")); }), "1 of 2 faces");

    // Counts that cannot fit in the file are rejected before anything is allocated.
    write_bytes(path("lying.off"), "OFF\n2000000000 1 0\n0 0 0\n");
    std::string lying = error_message([&] { dsreg::read_mesh(path("lying.off")); });
    EXPECT_CONTAINS(lying, path("lying.off") + ":2:");
    EXPECT_CONTAINS(lying, "2000000000 vertices");
    write_bytes(path("lying.off"), "OFF\n1000000000000 1 0\n0 0 0\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("lying.off")); }), "too many vertices");
}

TEST_F(MeshIoTest, PlyOutOfRangeIndexIsRejected) {
    write_bytes(path("bad.ply"),
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n");
    const std::string message = error_message([&] { dsreg::read_mesh(path("bad.ply")); });
    EXPECT_CONTAINS(message, path("bad.ply"));
    EXPECT_CONTAINS(message, "vertex -1 but only 3 vertices");
}

TEST_F(MeshIoTest, TruncatedBinaryPlyIsRejected) {
    dsreg::write_mesh(path("cube.ply"), make_unit_cube());
    const std::uintmax_t size = fs::file_size(path("cube.ply"));
    for (const std::uintmax_t cut : {std::uintmax_t(1), std::uintmax_t(20), std::uintmax_t(200)}) {
        fs::resize_file(path("cube.ply"), size - cut);
        const std::string message = error_message([&] { dsreg::read_mesh(path("cube.ply")); });
        EXPECT_CONTAINS(message, path("cube.ply")) << "cut " << cut;
        EXPECT_CONTAINS(message, "truncated") << "cut " << cut;
    }
}

TEST_F(MeshIoTest, TruncatedBinaryStlIsRejected) {
    dsreg::write_mesh(path("cube.stl"), make_unit_cube());
    fs::resize_file(path("cube.stl"), fs::file_size(path("cube.stl")) - 10);
    std::string message = error_message([&] { dsreg::read_mesh(path("cube.stl")); });
    EXPECT_CONTAINS(message, path("cube.stl"));
    EXPECT_CONTAINS(message, "truncated");
    fs::resize_file(path("cube.stl"), 50);
    message = error_message([&] { dsreg::read_mesh(path("cube.stl")); });
    EXPECT_CONTAINS(message, path("cube.stl"));
}

TEST_F(MeshIoTest, PlyHeaderCountsThatCannotFitAreRejectedBeforeAllocating) {
    const std::string vertex_properties = "property double x\nproperty double y\nproperty double z\n";
    const std::string face_property = "property list uchar int vertex_indices\n";
    const std::string tail(1000, '\0');
    const std::vector<std::string> headers = {
        "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n" + vertex_properties + "end_header\n",
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\n" + vertex_properties + "element face 1000000000000\n" +
            face_property + "end_header\n",
        "ply\nformat ascii 1.0\nelement vertex 1000000000000\n" + vertex_properties + "end_header\n",
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + vertex_properties +
            "element junk 18446744073709551615\nproperty uchar a\nend_header\n",
    };
    for (const std::string& header : headers) {
        write_bytes(path("lying.ply"), header + tail);
        const std::string message = error_message([&] { dsreg::read_mesh(path("lying.ply")); });
        EXPECT_CONTAINS(message, path("lying.ply"));
        EXPECT_CONTAINS(message, "cannot hold");
    }
}

TEST_F(MeshIoTest, MalformedPlyHeadersAreRejected) {
    const std::string vertex = "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"plyx\n", "not a PLY file"},
        {"ply\nformat ascii 1.0\n" + vertex, "no end_header"},
        {"ply\nformat ascii 2.0\n" + vertex + "end_header\n", "format"},
        {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
         "no property 'z'"},
        {"ply\nformat ascii 1.0\n" + vertex + "property quad w\nend_header\n", "unknown PLY type 'quad'"},
        {"ply\nformat ascii 1.0\n" + vertex + "element face 0\nproperty list float int vertex_indices\nend_header\n",
         "integer"},
        {"ply\nformat ascii 1.0\n" + vertex + "element face 0\nproperty list uchar float vertex_indices\nend_header\n",
         "integers"},
        {"ply\nformat ascii 1.0\n" + vertex + "element face 0\nproperty int flags\nend_header\n", "vertex_indices"},
        {"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
         "no 'vertex' element"},
        {"ply\nformat ascii 1.0\n" + vertex + "end_header\n1 2 3\n", "after the last element"},
        {"ply\nformat ascii 1.0\n" + vertex +
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n5 0 0 0 0 0\n",
         "5 vertices"},
    };
    for (const auto& [content, expected] : cases) {
        write_bytes(path("bad.ply"), content);
        const std::string message = error_message([&] { dsreg::read_mesh(path("bad.ply")); });
        EXPECT_CONTAINS(message, path("bad.ply"));
        EXPECT_CONTAINS(message, expected);
    }
}

TEST_F(MeshIoTest, UnknownExtensionIsRejectedListingTheSupportedOnes) {
    for (const char* name : {"mesh.xyz", "mesh"}) {
        const std::string write_message = error_message([&] { dsreg::write_mesh(path(name), make_unit_cube()); });
        EXPECT_CONTAINS(write_message, path(name));
        for (const char* extension : {".obj", ".off", ".ply", ".stl", ".vtk", ".vtp"}) EXPECT_CONTAINS(write_message, extension);
        EXPECT_FALSE(fs::exists(path(name)));
    }
    write_bytes(path("mesh.xyz"), "v 0 0 0\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("mesh.xyz")); }), ".stl");
}

TEST_F(MeshIoTest, MissingFileIsRejectedByName) {
    for (const char* name : {"missing.obj", "missing.off", "missing.ply", "missing.stl"}) {
        EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path(name)); }), path(name));
    }
    fs::create_directory(path("folder.ply"));
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("folder.ply")); }),
                    path("folder.ply") + ": is a directory");
}

// ---- failed writes -----------------------------------------------------------------------------

TEST_F(MeshIoTest, WritingIntoAMissingDirectoryFailsAndCreatesNothing) {
    const std::string target = path("no/such/dir/cube.ply");
    EXPECT_CONTAINS(error_message([&] { dsreg::write_mesh(target, make_unit_cube()); }), target);
    EXPECT_FALSE(fs::exists(path("no")));
    EXPECT_TRUE(directory_entries().empty());
}

TEST_F(MeshIoTest, InvalidMeshIsRejectedAndTheExistingFileIsUntouched) {
    PolygonMesh out_of_range = make_unit_cube();
    out_of_range.faces(4, 1) = 8;
    PolygonMesh negative = make_unit_cube();
    negative.faces(0, 0) = -1;
    PolygonMesh not_finite = make_unit_cube();
    not_finite.vertices(2, 1) = std::numeric_limits<double>::quiet_NaN();
    PolygonMesh wrong_normals = make_unit_cube();
    wrong_normals.face_normals.conservativeResize(5, 3);
    PolygonMesh wrong_scalar = make_unit_cube();
    wrong_scalar.vertex_scalars[0].second.resize(3);
    PolygonMesh pentagons = make_unit_cube();
    pentagons.faces.conservativeResize(6, 5);
    const std::vector<std::pair<PolygonMesh, std::string>> invalid = {
        {out_of_range, "face 4 refers to vertex 8"}, {negative, "vertex -1"},    {not_finite, "vertex 2"},
        {wrong_normals, "5 face normals"},           {wrong_scalar, "'height'"}, {pentagons, "5 vertices"}};
    for (const char* name : {"cube.obj", "cube.off", "cube.ply", "cube.stl"}) {
        dsreg::write_mesh(path(name), make_unit_cube());
        const std::string before = read_bytes(path(name));
        for (const auto& [mesh, expected] : invalid) {
            const std::string message = error_message([&] { dsreg::write_mesh(path(name), mesh); });
            EXPECT_CONTAINS(message, path(name));
            EXPECT_CONTAINS(message, expected);
            EXPECT_EQ(read_bytes(path(name)), before) << name;
        }
    }
    EXPECT_EQ(directory_entries(), (std::vector<std::string>{"cube.obj", "cube.off", "cube.ply", "cube.stl"}));
}

TEST_F(MeshIoTest, PlyRejectsVertexScalarNamesItCannotStore) {
    dsreg::write_mesh(path("cube.ply"), make_unit_cube());
    const std::string before = read_bytes(path("cube.ply"));
    for (const char* name : {"two words", "", "x", "third"}) {
        PolygonMesh cube = make_unit_cube();
        cube.vertex_scalars.emplace_back(name, Eigen::VectorXd::Zero(8));
        EXPECT_CONTAINS(error_message([&] { dsreg::write_mesh(path("cube.ply"), cube); }), path("cube.ply"));
        EXPECT_EQ(read_bytes(path("cube.ply")), before) << name;
    }
    EXPECT_EQ(directory_entries(), std::vector<std::string>{"cube.ply"});
}

TEST_F(MeshIoTest, WriteFailingMidwayLeavesTheExistingFileUntouched) {
    // The writers rely on write_file_atomically: a failure after some bytes were written must not
    // reach the destination.
    dsreg::write_mesh(path("cube.off"), make_unit_cube());
    const std::string before = read_bytes(path("cube.off"));
    const auto write_half_then_fail = [](std::ostream& out) {
        out << "OFF\n8 6 0\n0 0 0\n";
        throw dsreg::Error("simulated failure");
    };
    EXPECT_THROW(dsreg::write_file_atomically(path("cube.off"), write_half_then_fail), dsreg::Error);
    EXPECT_EQ(read_bytes(path("cube.off")), before);
    EXPECT_EQ(directory_entries(), std::vector<std::string>{"cube.off"});
    EXPECT_EQ(dsreg::read_mesh(path("cube.off")).faces, make_unit_cube().faces);
}

}  // namespace

// ---- 3D Slicer's model formats: VTK legacy and XML PolyData ------------------------------------

namespace {

void expect_same_mesh(const PolygonMesh& read, const PolygonMesh& written) {
    EXPECT_EQ(read.vertices, written.vertices);
    EXPECT_EQ(read.faces, written.faces);
    EXPECT_EQ(read.face_normals, written.face_normals);
    ASSERT_EQ(read.vertex_scalars.size(), written.vertex_scalars.size());
    for (std::size_t s = 0; s < written.vertex_scalars.size(); ++s) {
        EXPECT_EQ(read.vertex_scalars[s].first, written.vertex_scalars[s].first);
        EXPECT_EQ(read.vertex_scalars[s].second, written.vertex_scalars[s].second);
    }
    EXPECT_EQ(read.coordinate_system, written.coordinate_system);
}

}  // namespace

TEST_F(MeshIoTest, VtkAndVtpRoundTripEverythingExactly) {
    PolygonMesh cube = make_awkward_cube();
    cube.coordinate_system = "LPS";
    for (const char* name : {"cube.vtk", "cube.vtp"}) {
        SCOPED_TRACE(name);
        dsreg::write_mesh(path(name), cube);
        expect_same_mesh(dsreg::read_mesh(path(name)), cube);
        PolygonMesh triangles = dsreg::triangulate_shorter_diagonal(cube);
        triangles.vertex_scalars.clear();
        triangles.face_normals.resize(0, 3);
        triangles.coordinate_system = "RAS";
        dsreg::write_mesh(path(name), triangles);
        expect_same_mesh(dsreg::read_mesh(path(name)), triangles);
    }
}

TEST_F(MeshIoTest, EveryFormatRecordsTheCoordinateSystemWhereSlicerLooksForIt) {
    PolygonMesh cube = make_unit_cube();
    for (const char* space : {"LPS", "RAS", ""}) {
        cube.coordinate_system = space;
        for (const char* name : {"c.obj", "c.off", "c.ply", "c.stl", "c.vtk", "c.vtp"}) {
            SCOPED_TRACE(std::string(name) + " " + space);
            dsreg::write_mesh(path(name), cube);
            EXPECT_EQ(dsreg::read_mesh(path(name)).coordinate_system, space);
            const std::string bytes = read_bytes(path(name));
            const std::string tag = std::string("SPACE=") + space;
            if (std::string(name) == "c.vtp")
                EXPECT_EQ(bytes.find("Name=\"SPACE\"") != std::string::npos, *space != '\0');
            else
                EXPECT_EQ(bytes.find(tag) != std::string::npos, *space != '\0');
        }
    }
    // Where exactly: the second line of .vtk, the 80-byte header of .stl, a PLY comment, the first OBJ comment.
    cube.coordinate_system = "LPS";
    dsreg::write_mesh(path("c.vtk"), cube);
    std::istringstream vtk(read_bytes(path("c.vtk")));
    std::string line;
    std::getline(vtk, line);
    std::getline(vtk, line);
    EXPECT_CONTAINS(line, "SPACE=LPS");
    dsreg::write_mesh(path("c.stl"), cube);
    EXPECT_CONTAINS(read_bytes(path("c.stl")).substr(0, 80), "SPACE=LPS");
    dsreg::write_mesh(path("c.ply"), cube);
    EXPECT_CONTAINS(read_bytes(path("c.ply")), "\ncomment SPACE=LPS\n");
    dsreg::write_mesh(path("c.obj"), cube);
    EXPECT_EQ(read_bytes(path("c.obj")).rfind("# ", 0), 0u);
    EXPECT_CONTAINS(read_bytes(path("c.obj")).substr(0, read_bytes(path("c.obj")).find('\n')), "SPACE=LPS");
}

TEST_F(MeshIoTest, VtkReaderTakesAsciiFilesAndTheVersion51Layout) {
    // As VTK 9's vtkPolyDataWriter writes by default: version 5.1, OFFSETS and CONNECTIVITY.
    write_bytes(path("v51.vtk"), "# vtk DataFile Version 5.1\nvtk output SPACE=RAS\nASCII\nDATASET POLYDATA\n"
                                 "POINTS 4 float\n0 0 0 1 0 0 0 1 0\n1 1 0\n"
                                 "METADATA\nINFORMATION 0\n\n"
                                 "POLYGONS 3 6\nOFFSETS vtktypeint64\n0 3 6\nCONNECTIVITY vtktypeint64\n0 1 2 1 3 2\n"
                                 "POINT_DATA 4\nNORMALS Normals float\n0 0 1 0 0 1 0 0 1 0 0 1\n"
                                 "SCALARS level double 1\nLOOKUP_TABLE default\n1 2 3 4\n");
    const PolygonMesh mesh = dsreg::read_mesh(path("v51.vtk"));
    EXPECT_EQ(mesh.vertices.rows(), 4);
    EXPECT_EQ(mesh.faces.rows(), 2);
    EXPECT_EQ(mesh.faces(1, 1), 3);
    EXPECT_EQ(mesh.coordinate_system, "RAS");
    ASSERT_EQ(mesh.vertex_scalars.size(), 1u);
    EXPECT_EQ(mesh.vertex_scalars[0].second[3], 4.0);
    // The 4.2 layout in ASCII, with line cells skipped.
    write_bytes(path("v42.vtk"), "# vtk DataFile Version 4.2\n3D Slicer output. SPACE=LPS\nASCII\nDATASET POLYDATA\n"
                                 "POINTS 3 double\n0 0 0\n1 0 0\n0 1 0\nLINES 1 3\n2 0 1\nPOLYGONS 1 4\n3 0 1 2\n"
                                 "CELL_DATA 2\nNORMALS u double\n0 0 1 0 0 1\n");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("v42.vtk")); }), "CELL_DATA count differs");
}

TEST_F(MeshIoTest, HostileVtkAndVtpFilesAreRejected) {
    const std::vector<std::pair<std::string, std::string>> files = {
        {"image.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\n"},
        {"huge.vtk", "# vtk DataFile Version 4.2\nx\nBINARY\nDATASET POLYDATA\nPOINTS 2000000000 double\nabc"},
        {"strips.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                       "TRIANGLE_STRIPS 1 4\n3 0 1 2\n"},
        {"index.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                      "POLYGONS 1 4\n3 0 1 9\n"},
        {"pentagon.vtk", "# vtk DataFile Version 4.2\nx\nASCII\nDATASET POLYDATA\nPOINTS 5 float\n0 0 0 1 0 0 0 1 0 1 1 0 2 2 0\n"
                         "POLYGONS 1 6\n5 0 1 2 3 4\n"},
        {"grid.vtp", "<?xml version=\"1.0\"?><VTKFile type=\"UnstructuredGrid\"></VTKFile>"},
        {"lying.vtp", "<VTKFile type=\"PolyData\" header_type=\"UInt64\"><PolyData><Piece NumberOfPoints=\"1\" NumberOfPolys=\"0\">"
                      "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">//////////8=</DataArray>"
                      "</Points></Piece></PolyData></VTKFile>"},
        {"noclose.vtp", "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"1\""},
    };
    for (const auto& [name, bytes] : files) {
        SCOPED_TRACE(name);
        write_bytes(path(name), bytes);
        EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path(name)); }), path(name) + ": ");
    }
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("image.vtk")); }), "not POLYDATA");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("huge.vtk")); }), "cannot hold that many");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("strips.vtk")); }), "triangle strips");
    EXPECT_CONTAINS(error_message([&] { dsreg::read_mesh(path("lying.vtp")); }), "more than the file can hold");
}
