// Block-wise reading of the medical formats (read_volume_box, read_volume_grid of NIfTI, NRRD,
// MetaImage, HDF5, VTK): a box equals the crop of the whole volume, at corners and edges, with
// the file's world geometry; truncated files are refused naming the file; the images ITK reads
// whole (TIFF) and DICOM series are refused; and a block-wise run of an oblique, anisotropic
// NIfTI file gives the faces of the whole-volume run within the streaming bound, and the mesh of
// the same voxels as a .raw file, placed in the NIfTI's world frame.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/volume_io.hpp"
#include "dsreg/world_space.hpp"
#include "medical_test_support.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

using test::ScratchFolder;
using test::error_of;

/// The formats whose boxes are read: dsreg's decoders (stored and compressed payloads) and ITK's
/// slab reader (HDF5, VTK).
const char* const kBoxFormats[] = {"a.nii", "a.nii.gz", "a.hdr", "a.nrrd", "a.mha", "a.h5", "a.vtk"};

/// Labels 0, 1 (inside the ellipsoid) and 2 (inside and x ≥ 6), so that a threshold at 2 differs
/// from the mask.
std::vector<double> two_labels(const VoxelGrid& grid) {
    std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1);
    for (std::size_t n = 0; n < labels.size(); ++n)
        if (labels[n] > 0 && std::int64_t(n) % grid.dims[0] >= 6) labels[n] = 2;
    return labels;
}

std::string box_text(const VoxelBox& box) {
    std::string text;
    for (int a = 0; a < 3; ++a) text += std::to_string(box.lo[a]) + ".." + std::to_string(box.hi[a]) + (a < 2 ? " " : "");
    return text;
}

void expect_same_geometry(const VoxelGrid& read, const VoxelGrid& expected, const std::string& name) {
    EXPECT_EQ(read.dims, expected.dims) << name;
    EXPECT_LT((read.spacing - expected.spacing).norm(), 1e-12) << name;
    EXPECT_LT((read.origin - expected.origin).norm(), 1e-9) << name;
    EXPECT_LT((read.direction - expected.direction).norm(), 1e-12) << name;
}

TEST(MedicalBlocks, ReadingABoxEqualsCroppingTheWholeVolumeWithItsGeometry) {
    ScratchFolder scratch("medical-boxes");
    const VoxelGrid grid = test::oblique_grid({13, 11, 9});
    const std::vector<double> labels = two_labels(grid);
    const VoxelBox all{{0, 0, 0}, grid.dims};
    const VoxelBox boxes[] = {
        {{0, 0, 0}, {4, 3, 2}},     // first corner
        {{9, 8, 7}, {13, 11, 9}},   // last corner
        {{0, 5, 0}, {13, 6, 9}},    // a slab of y through every slice
        {{12, 0, 3}, {13, 11, 4}},  // a column on the x = max face, one slice
        all,
    };
    ValueRange two;
    two.has_min = true;
    two.min = 2;
    for (const char* name : kBoxFormats) {
        SCOPED_TRACE(name);
        const std::string path = scratch.path(name);
        write_image(path, grid, labels, RawVoxelType::UInt16);
        VolumeFileInfo whole_info, header_info;
        const BinaryVolume whole = read_volume(path, {}, nullptr, {}, &whole_info);
        const VoxelGrid header = read_volume_grid(path, nullptr, {}, &header_info);
        expect_same_geometry(header, whole.grid, name);
        EXPECT_EQ(read_volume_dims(path), grid.dims);
        EXPECT_EQ(header_info.world_geometry, whole_info.world_geometry);
        EXPECT_EQ(header_info.format, whole_info.format);
        const BinaryVolume whole_two = read_volume(path, two);
        for (const VoxelBox& box : boxes) {
            const BinaryVolume part = read_volume_box(path, box);
            EXPECT_EQ(part.mask, crop_volume(whole, all, box).mask) << box_text(box);
            EXPECT_EQ(read_volume_box(path, box, two).mask, crop_volume(whole_two, all, box).mask) << box_text(box);
            VoxelGrid placed = whole.grid;
            placed.dims = box.size();
            placed.origin = whole.grid.voxel_center(box.lo[0], box.lo[1], box.lo[2]);
            expect_same_geometry(part.grid, placed, name);
        }
        EXPECT_THROW(read_volume_box(path, VoxelBox{{0, 0, 0}, {14, 11, 9}}), Error);
    }
}


TEST(MedicalBlocks, TruncatedFilesAreRefusedNamingTheFile) {
    ScratchFolder scratch("medical-box-truncated");
    const VoxelGrid grid = test::oblique_grid({13, 11, 9});
    const std::vector<double> labels = two_labels(grid);
    for (const char* name : kBoxFormats) {
        if (std::string(name) == "a.hdr") continue;  // its payload is the .img: truncated below
        SCOPED_TRACE(name);
        const std::string path = scratch.path(std::string("cut-") + name);
        write_image(path, grid, labels, RawVoxelType::UInt16);
        std::filesystem::resize_file(path, std::filesystem::file_size(path) * 2 / 3);
        const VoxelBox last_slice{{0, 0, 8}, {13, 11, 9}};
        const std::string message = error_of([&] { read_volume_box(path, last_slice); });
        EXPECT_NE(message.find(path), std::string::npos) << message;
    }
    const std::string hdr = scratch.path("cut.hdr"), img = scratch.path("cut.img");
    write_image(hdr, grid, labels, RawVoxelType::UInt16);
    std::filesystem::resize_file(img, std::filesystem::file_size(img) - 2);
    const std::string message = error_of([&] { read_volume_box(hdr, VoxelBox{{0, 0, 0}, {2, 2, 2}}); });
    EXPECT_NE(message.find("truncated"), std::string::npos) << message;
    EXPECT_NE(message.find(img), std::string::npos) << message;
    EXPECT_NE(error_of([&] { read_volume_grid(hdr); }).find(img), std::string::npos);
}

TEST(MedicalBlocks, ImagesItkReadsWholeAndDicomSeriesAreRefused) {
    ScratchFolder scratch("medical-box-refused");
    const VoxelGrid grid = test::oblique_grid({13, 11, 9});
    const std::string tiff = scratch.path("a.tif");
    write_image(tiff, grid, two_labels(grid), RawVoxelType::UInt8);
    EXPECT_EQ(read_volume_dims(tiff), grid.dims);  // the header alone is fine
    const std::string message = error_of([&] { read_volume_box(tiff, VoxelBox{{0, 0, 0}, {2, 2, 2}}); });
    EXPECT_NE(message.find(tiff), std::string::npos) << message;
    EXPECT_NE(message.find("ITK reads"), std::string::npos) << message;
    const std::string series = scratch.folder();  // a folder reads as a DICOM series
    EXPECT_NE(error_of([&] { read_volume_grid(series); }).find("DICOM series"), std::string::npos);
    EXPECT_NE(error_of([&] { read_volume_box(series, VoxelBox{{0, 0, 0}, {2, 2, 2}}); }).find("DICOM series"), std::string::npos);
}

TEST(MedicalBlocks, BlockwiseRunOfAnObliqueNiftiIsTheWholeRunsAndTheRawFilesInWorld) {
    ScratchFolder scratch("medical-blockwise");
    const VoxelGrid grid = test::oblique_grid({40, 36, 30});
    const std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1);
    VolumeSource nifti;
    nifti.input_path = scratch.path("ellipsoid.nii.gz");
    write_image(nifti.input_path, grid, labels, RawVoxelType::UInt8);
    VolumeSource raw;  // the same voxels, with the same spacing and no world placement
    raw.input_path = scratch.path("ellipsoid.raw");
    {
        std::ofstream out(raw.input_path, std::ios::binary);
        for (double label : labels) out.put(char(label > 0 ? 1 : 0));
    }
    raw.raw_layout = RawVolumeLayout{grid.dims, RawVoxelType::UInt8, false, 0};
    raw.spacing = grid.spacing;

    PipelineOptions blocks;
    blocks.validity = ValidityMode::Off;
    blocks.max_error_voxels = 1e-7;
    blocks.blocks.block_size = {16, 16, 12};
    blocks.blocks.halo = 6;
    PipelineOptions whole_options = plan_block_run(nifti, blocks, "--block-size").options;  // what blocks do, whole
    whole_options.blocks = BlockOptions{};
    whole_options.solver = SolverKind::Cholmod;
    const PipelineResult whole = run_pipeline(nifti, whole_options);
    const PipelineResult streamed = run_pipeline(nifti, blocks);
    const PipelineResult streamed_raw = run_pipeline(raw, blocks);

    // The whole run's faces and geometry, its positions within the reported bound.
    ASSERT_EQ(streamed.surface.quads, whole.surface.quads);
    EXPECT_EQ(streamed.object_voxels, whole.object_voxels);
    expect_same_geometry(streamed.grid, whole.grid, "grid");
    EXPECT_TRUE(streamed.file.world_geometry);
    const double error = (streamed.regularization.positions - whole.regularization.positions).norm();
    EXPECT_LE(error, streamed.regularization.solve.error_bound);

    // The .raw file's mesh, moved by the NIfTI's origin in the grid frame, and so in LPS world by
    // the geometry the whole read gives (NIfTI stores the direction in float32 quaternions).
    const VoxelGrid file = read_volume(nifti.input_path).grid;
    EXPECT_LT((file.direction - grid.direction).norm(), 1e-6);
    expect_same_geometry(streamed.grid, file, "grid");
    ASSERT_EQ(streamed_raw.surface.quads, streamed.surface.quads);
    ASSERT_EQ(streamed_raw.regularization.positions.rows(), streamed.regularization.positions.rows());
    const AffineMap to_world = grid_to_space(streamed.grid, OutputSpace::Lps);
    const PointMatrix world = map_points(to_world, streamed.regularization.positions);
    for (Eigen::Index v = 0; v < world.rows(); ++v) {
        const Eigen::Vector3d from_raw = streamed_raw.regularization.positions.row(v).transpose();
        ASSERT_LT((streamed.regularization.positions.row(v).transpose() - file.origin - from_raw).norm(), 1e-9) << v;
        ASSERT_LT((world.row(v).transpose() - (file.origin + file.direction * from_raw)).norm(), 1e-9) << v;
    }
}

}  // namespace
}  // namespace dsreg
