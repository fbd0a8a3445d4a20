// World coordinates (dsreg/world_space.hpp) and the whole pipeline on medical images: an ellipsoid
// fixed in world space, sampled on an oblique, anisotropic grid and written by ITK's writers, is
// read back, regularized in the grid frame and mapped to LPS, RAS and voxel coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/volume_io.hpp"
#include "dsreg/world_space.hpp"
#include "medical_test_support.hpp"

using namespace dsreg;
using dsreg::test::ScratchFolder;

namespace {

// ---------------------------------------------------------------------------------------------
// The map itself

PolygonMesh unit_cube() {  // counter-clockwise seen from outside
    PolygonMesh mesh;
    mesh.vertices.resize(8, 3);
    for (int v = 0; v < 8; ++v) mesh.vertices.row(v) << (v & 1), ((v >> 1) & 1), ((v >> 2) & 1);
    mesh.faces.resize(6, 4);
    mesh.faces << 0, 2, 3, 1,  4, 5, 7, 6,  0, 1, 5, 4,  2, 6, 7, 3,  0, 4, 6, 2,  1, 3, 7, 5;
    mesh.face_normals = face_normals(mesh.vertices, mesh.faces);
    return mesh;
}

double signed_volume(const PolygonMesh& mesh) { return enclosed_volume(mesh.vertices, mesh_triangles(mesh.vertices, mesh.faces)); }

TEST(WorldSpace, MapsGridFramePointsToLpsRasAndVoxelCoordinates) {
    const VoxelGrid grid = test::oblique_grid();
    const Eigen::Vector3d index(3, -2, 5.5);
    const Eigen::Vector3d grid_point = grid.origin + grid.spacing.cwiseProduct(index);
    const Eigen::Vector3d lps = test::world_position(grid, index.x(), index.y(), index.z());
    EXPECT_LT((grid_to_space(grid, OutputSpace::Lps).apply(grid_point) - lps).norm(), 1e-12);
    EXPECT_LT((grid_to_space(grid, OutputSpace::Ras).apply(grid_point) - Eigen::Vector3d(-lps.x(), -lps.y(), lps.z())).norm(), 1e-12);
    EXPECT_LT((grid_to_space(grid, OutputSpace::Voxel).apply(grid_point) - index).norm(), 1e-12);
    EXPECT_EQ(parse_output_space("RAS"), OutputSpace::Ras);
    EXPECT_THROW(parse_output_space("ijk"), Error);
}

TEST(WorldSpace, LeftHandedMapsReverseTheFacesAndKeepThemOutward) {
    const PolygonMesh cube = unit_cube();
    ASSERT_NEAR(signed_volume(cube), 1.0, 1e-12);
    VoxelGrid grid;
    grid.direction = test::rotation(30, Eigen::Vector3d(1, 1, 0)) * Eigen::Vector3d(-1, 1, 1).asDiagonal();  // det −1
    grid.origin = Eigen::Vector3d(4, 5, 6);
    for (const OutputSpace space : {OutputSpace::Lps, OutputSpace::Ras, OutputSpace::Voxel}) {
        const PolygonMesh mapped = mesh_in_space(cube, grid, space);
        EXPECT_NEAR(signed_volume(mapped), 1.0, 1e-12) << output_space_name(space);
        // The mapped field u is the outward normal of the mapped faces.
        const PointMatrix normals = face_normals(mapped.vertices, mapped.faces);
        for (Eigen::Index f = 0; f < normals.rows(); ++f) EXPECT_NEAR(normals.row(f).dot(mapped.face_normals.row(f)), 1.0, 1e-12);
    }
    EXPECT_EQ(mesh_in_space(cube, grid, OutputSpace::Lps).coordinate_system, "LPS");
    EXPECT_EQ(mesh_in_space(cube, grid, OutputSpace::Voxel).coordinate_system, "");
}

// ---------------------------------------------------------------------------------------------
// The pipeline on an oblique anisotropic image

struct Regularized {
    BinaryVolume volume;
    DigitalSurface surface;
    PolygonMesh mesh;  ///< grid frame, field u per face
};

/// Reads `path`, extracts the surface, integral-invariant normals with the command's default
/// radius for files (5 voxels of the largest spacing, biweight), the paper's weights.
Regularized regularize_file(const std::string& path) {
    Regularized r;
    r.volume = read_volume(path);
    r.surface = extract_digital_surface(r.volume, Connectivity::TwentySix);
    const PointMatrix u = integral_invariant_normals(r.volume, r.surface, 5.0 * r.volume.grid.spacing.maxCoeff());
    const RegularizationResult result = regularize(r.surface, u, RegularizationWeights{}, SolverOptions{});
    r.mesh.vertices = result.positions;
    r.mesh.faces = r.surface.quads;
    r.mesh.face_normals = u;
    return r;
}

double mean_distance(const ImplicitShape& shape, const PointMatrix& points) {
    const std::vector<double> d = distances_to_surface(shape, points);
    double sum = 0;
    for (const double x : d) sum += x;
    return sum / double(d.size());
}

/// The grid and ellipsoid of these tests: bigger than the I/O tests' so that the ball of the
/// integral invariants (6.25 mm) is small against the ellipsoid (semi-axes 14, 11, 9 mm).
struct Scene {
    VoxelGrid grid = test::oblique_grid({52, 44, 36});
    test::WorldEllipsoid ellipsoid{test::test_ellipsoid(grid).centre, Eigen::Vector3d(14, 11, 9),
                                   test::rotation(-40, Eigen::Vector3d(3, -1, 2))};
};

/// The scene's ellipsoid written to `path` (ITK's writer for its extension), read and regularized.
Regularized regularize_scene(const Scene& scene, const std::string& path, RawVoxelType type = RawVoxelType::UInt8) {
    write_image(path, scene.grid, test::sample_ellipsoid(scene.grid, scene.ellipsoid), type);
    return regularize_file(path);
}

/// The unregularized digital surface of `r` in `space`.
PolygonMesh digital_surface_in(const Regularized& r, OutputSpace space) {
    return mesh_in_space(PolygonMesh{r.surface.vertices, r.surface.quads, {}, {}, ""}, r.volume.grid, space);
}

TEST(WorldSpacePipeline, RegularizedMeshLiesOnTheWorldEllipsoidInLpsAndRas) {
    ScratchFolder scratch("world-accuracy");
    const Scene scene;
    const Regularized r = regularize_scene(scene, scratch.path("ellipsoid.nii.gz"));
    const double voxel = r.volume.grid.spacing.minCoeff();  // the strictest reading of "0.1 voxel"

    const PolygonMesh lps = mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Lps);
    const PolygonMesh ras = mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Ras);
    const double lps_mean = mean_distance(scene.ellipsoid.shape(), lps.vertices);
    const double ras_mean = mean_distance(scene.ellipsoid.in_ras().shape(), ras.vertices);
    std::printf("ellipsoid on the oblique anisotropic grid: mean vertex distance %.4f mm (LPS), %.4f mm (RAS), %.3f of the smallest "
                "voxel size\n", lps_mean, ras_mean, lps_mean / voxel);
    EXPECT_LT(lps_mean, 0.1 * voxel);
    EXPECT_LT(ras_mean, 0.1 * voxel);
    // The digital surface itself is about a quarter of a voxel away: the regularization matters.
    const PolygonMesh digital = digital_surface_in(r, OutputSpace::Lps);
    const double digital_mean = mean_distance(scene.ellipsoid.shape(), digital.vertices);
    std::printf("digital surface: mean vertex distance %.4f mm\n", digital_mean);
    EXPECT_GT(digital_mean, 2 * lps_mean);
    // In world space the mesh encloses the ellipsoid's volume (outward faces).
    const double volume = 4.0 / 3.0 * M_PI * 14 * 11 * 9;
    EXPECT_NEAR(signed_volume(lps), volume, 0.01 * volume);
    EXPECT_NEAR(signed_volume(ras), volume, 0.01 * volume);
}

TEST(WorldSpacePipeline, VoxelSpaceGivesIndexCoordinates) {
    ScratchFolder scratch("world-voxel");
    const Scene scene;
    const Regularized r = regularize_scene(scene, scratch.path("ellipsoid.nrrd"));
    // The digital surface's vertices, the voxel corners, land at half-integers.
    const PolygonMesh corners = digital_surface_in(r, OutputSpace::Voxel);
    for (Eigen::Index v = 0; v < corners.vertices.rows(); ++v)
        for (int a = 0; a < 3; ++a) ASSERT_NEAR(corners.vertices(v, a) - std::floor(corners.vertices(v, a)), 0.5, 1e-9);
    // The file's own index-to-world transform takes the voxel-space mesh onto the LPS mesh.
    const PolygonMesh voxel = mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Voxel);
    const PolygonMesh lps = mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Lps);
    for (Eigen::Index v = 0; v < voxel.vertices.rows(); ++v) {
        const Eigen::Vector3d index = voxel.vertices.row(v).transpose();
        ASSERT_LT((test::world_position(scene.grid, index.x(), index.y(), index.z()) - lps.vertices.row(v).transpose()).norm(), 1e-9);
    }
}

TEST(WorldSpacePipeline, LeftHandedNiftiKeepsOutwardFaces) {
    ScratchFolder scratch("world-left");
    Scene scene;
    // The same box of space with i running the other way: voxel 0 is the former last one along i.
    scene.grid.origin = test::world_position(scene.grid, double(scene.grid.dims[0] - 1), 0, 0);
    scene.grid.direction = scene.grid.direction * Eigen::Vector3d(-1, 1, 1).asDiagonal();
    ASSERT_LT(scene.grid.direction.determinant(), 0);
    const Regularized r = regularize_scene(scene, scratch.path("left.nii"), RawVoxelType::Int16);
    ASSERT_LT(r.volume.grid.direction.determinant(), 0);
    const double volume = 4.0 / 3.0 * M_PI * 14 * 11 * 9;
    for (const OutputSpace space : {OutputSpace::Lps, OutputSpace::Ras}) {
        const PolygonMesh mesh = mesh_in_space(r.mesh, r.volume.grid, space);
        EXPECT_NEAR(signed_volume(mesh), volume, 0.01 * volume) << output_space_name(space);
        EXPECT_EQ(count_faces_against_field(mesh.vertices, mesh.faces, mesh.face_normals), 0) << output_space_name(space);
    }
    EXPECT_LT(mean_distance(scene.ellipsoid.shape(), mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Lps).vertices),
              0.1 * r.volume.grid.spacing.minCoeff());
}

TEST(WorldSpacePipeline, TheSameMaskInFourFormatsGivesTheSameMesh) {
    ScratchFolder scratch("world-formats");
    const Scene scene;
    const std::vector<double> labels = test::sample_ellipsoid(scene.grid, scene.ellipsoid, 2);
    // NIfTI stores the geometry in float32: the other files get the geometry as read back from
    // the NIfTI file, so that all four describe exactly the same image.
    write_image(scratch.path("e.nii.gz"), scene.grid, labels, RawVoxelType::UInt8);
    const VoxelGrid stored = read_volume(scratch.path("e.nii.gz")).grid;
    write_image(scratch.path("e.nrrd"), stored, labels, RawVoxelType::UInt8);
    write_image(scratch.path("e.mha"), stored, labels, RawVoxelType::Int16);
    const std::string dicom = scratch.path("dicom");
    std::filesystem::create_directories(dicom);
    write_dicom_series(dicom, stored, labels, RawVoxelType::Int16);

    const PolygonMesh reference = mesh_in_space(regularize_file(scratch.path("e.nii.gz")).mesh, stored, OutputSpace::Lps);
    for (const std::string& input : {scratch.path("e.nrrd"), scratch.path("e.mha"), dicom}) {
        SCOPED_TRACE(input);
        const Regularized r = regularize_file(input);
        const PolygonMesh mesh = mesh_in_space(r.mesh, r.volume.grid, OutputSpace::Lps);
        ASSERT_EQ(mesh.vertices.rows(), reference.vertices.rows());
        ASSERT_EQ(mesh.faces, reference.faces);
        EXPECT_LT((mesh.vertices - reference.vertices).cwiseAbs().maxCoeff(), 1e-9);
    }
}

}  // namespace
