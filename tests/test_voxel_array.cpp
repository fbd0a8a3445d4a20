// A caller's array as the pipeline's input (voxel_array.hpp, grid_placement.hpp, VolumeSource::array):
// every value type, byte order and stride thresholds to the same mask; affines (LPS or RAS) give
// the grid's spacing, origin and direction cosines and back; the pipeline on an array equals the pipeline on the same mask.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/grid_placement.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/volume_io.hpp"
#include "dsreg/voxel_array.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

const Index3 kDims{7, 5, 4};

/// Value of voxel (i,j,k) of the test volumes: a few object voxels valued 3, the rest 0 or −2.
double test_value(std::int64_t i, std::int64_t j, std::int64_t k) {
    if ((i + 2 * j + 3 * k) % 5 == 0) return 3.0;
    return (i + j) % 2 ? 0.0 : -2.0;
}

/// The test volume stored as T, with the byte order swapped if `swap`, its axes laid out in
/// memory in the order `layout` (slowest first), each value followed by `gap` unused bytes.
template <typename T>
struct StoredArray {
    std::vector<std::uint8_t> bytes;
    VoxelArray array;

    StoredArray(ValueKind kind, bool swap, std::array<int, 3> layout, int gap) {
        const std::int64_t item = sizeof(T) + gap;
        std::array<std::int64_t, 3> strides{};
        std::int64_t step = item;
        for (int n = 2; n >= 0; --n) strides[layout[n]] = step, step *= kDims[layout[n]];
        bytes.assign(static_cast<std::size_t>(step), 0xAB);
        for (std::int64_t k = 0; k < kDims[2]; ++k)
            for (std::int64_t j = 0; j < kDims[1]; ++j)
                for (std::int64_t i = 0; i < kDims[0]; ++i) {
                    // unsigned types store the negative values as 0 (the cast of −2 would be undefined)
                    const double v = test_value(i, j, k);
                    const T value = static_cast<T>(kind == ValueKind::Unsigned && v < 0 ? 0.0 : v);
                    std::uint8_t* at = bytes.data() + i * strides[0] + j * strides[1] + k * strides[2];
                    std::memcpy(at, &value, sizeof(T));
                    if (swap) std::reverse(at, at + sizeof(T));
                }
        array.data = bytes.data();
        array.dims = kDims;
        array.byte_strides = strides;
        array.kind = kind;
        array.bytes = sizeof(T);
        array.big_endian = swap;  // the test machine is little-endian (checked below)
    }
};

std::vector<std::uint8_t> expected_mask(const ValueRange& range) {
    std::vector<std::uint8_t> mask;
    for (std::int64_t k = 0; k < kDims[2]; ++k)
        for (std::int64_t j = 0; j < kDims[1]; ++j)
            for (std::int64_t i = 0; i < kDims[0]; ++i) mask.push_back(range.contains(test_value(i, j, k)) ? 1 : 0);
    return mask;
}

template <typename T>
void expect_thresholds(ValueKind kind) {
    ValueRange positive, around_minus_two;
    around_minus_two.has_min = around_minus_two.has_max = true;
    around_minus_two.min = -2.5, around_minus_two.max = -1.5;
    for (const bool swap : {false, true})
        for (const std::array<int, 3> layout : {std::array<int, 3>{2, 1, 0}, {0, 1, 2}, {1, 2, 0}})
            for (const int gap : {0, 3}) {
                const StoredArray<T> stored(kind, swap, layout, gap);
                EXPECT_EQ(threshold_voxel_array(stored.array, positive), expected_mask(positive))
                    << value_type_name(stored.array) << " swap " << swap << " gap " << gap;
                if (kind != ValueKind::Unsigned)
                    EXPECT_EQ(threshold_voxel_array(stored.array, around_minus_two), expected_mask(around_minus_two));
            }
}

TEST(VoxelArray, EveryTypeByteOrderAndLayoutThresholdsLikeTheValues) {
    const std::uint16_t one = 1;
    std::uint8_t first = 0;
    std::memcpy(&first, &one, 1);
    ASSERT_EQ(first, 1) << "the test builds big-endian arrays by swapping on a little-endian machine";
    expect_thresholds<std::uint8_t>(ValueKind::Unsigned);
    expect_thresholds<std::int8_t>(ValueKind::Signed);
    expect_thresholds<std::uint16_t>(ValueKind::Unsigned);
    expect_thresholds<std::int16_t>(ValueKind::Signed);
    expect_thresholds<std::int32_t>(ValueKind::Signed);
    expect_thresholds<std::uint64_t>(ValueKind::Unsigned);
    expect_thresholds<std::int64_t>(ValueKind::Signed);
    expect_thresholds<float>(ValueKind::Float);
    expect_thresholds<double>(ValueKind::Float);
}

TEST(VoxelArray, ArraysLargerThanATileGiveTheSameMaskInAnyOrder) {
    const Index3 dims{150, 70, 30};  // several tiles along every axis, partial ones at the ends
    const auto value = [](std::int64_t i, std::int64_t j, std::int64_t k) { return std::uint8_t((i * 7 + j * 3 + k) % 5 == 0); };
    std::vector<std::uint8_t> expected, c_order(std::size_t(dims[0] * dims[1] * dims[2]));
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                expected.push_back(value(i, j, k));
                c_order[std::size_t((i * dims[1] + j) * dims[2] + k)] = value(i, j, k);
            }
    VoxelArray array;
    array.data = c_order.data();
    array.dims = dims;
    array.byte_strides = {dims[1] * dims[2], dims[2], 1};
    EXPECT_EQ(threshold_voxel_array(array, ValueRange{}), expected);
    // The same values seen backwards along y: start at the last row, negative stride.
    array.data = c_order.data() + (dims[1] - 1) * dims[2];
    array.byte_strides[1] = -dims[2];
    const std::vector<std::uint8_t> mirrored = threshold_voxel_array(array, ValueRange{});
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i)
                ASSERT_EQ(mirrored[std::size_t(i + dims[0] * (j + dims[1] * k))], value(i, dims[1] - 1 - j, k));
}

TEST(VoxelArray, LabelMapsDecodeAsTheFileReadersDecodeThem) {
    // The test values −2, 0 and 3 as int16, written x fastest to a .raw file: its label map is
    // the reference for every layout, byte order and value type of the array.
    std::vector<std::int16_t> stream;
    for (std::int64_t k = 0; k < kDims[2]; ++k)
        for (std::int64_t j = 0; j < kDims[1]; ++j)
            for (std::int64_t i = 0; i < kDims[0]; ++i) stream.push_back(static_cast<std::int16_t>(test_value(i, j, k)));
    const std::filesystem::path path = std::filesystem::temp_directory_path() / "dsreg_voxel_array_labels.raw";
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(stream.data()), std::streamsize(2 * stream.size()));
    RawVolumeLayout layout;
    layout.dims = kDims;
    layout.type = RawVoxelType::Int16;
    const LabelVolume expected = read_label_volume(path.string(), &layout);
    std::filesystem::remove(path);
    ASSERT_EQ(expected.values, (std::vector<std::int64_t>{0, -2, 3}));  // compact, increasing, background first

    const auto expect_same = [&](const VoxelArray& array) {
        const LabelVolume labels = label_voxel_array(array, VolumeLimits{}.max_labels);
        EXPECT_EQ(labels.values, expected.values) << value_type_name(array);
        EXPECT_EQ(labels.labels, expected.labels) << value_type_name(array);
        EXPECT_EQ(labels.grid.dims, kDims);
    };
    for (const bool swap : {false, true})
        for (const std::array<int, 3> order : {std::array<int, 3>{2, 1, 0}, {0, 1, 2}, {1, 2, 0}})
            for (const int gap : {0, 3}) {
                expect_same(StoredArray<std::int16_t>(ValueKind::Signed, swap, order, gap).array);
                expect_same(StoredArray<std::int64_t>(ValueKind::Signed, swap, order, gap).array);
                expect_same(StoredArray<float>(ValueKind::Float, swap, order, gap).array);  // floats holding integers
            }
    // One label besides the background allowed, two present: refused, naming the array.
    StoredArray<std::int8_t> bytes(ValueKind::Signed, false, {2, 1, 0}, 0);
    bytes.array.description = "mask 7x5x4 int8";
    EXPECT_NE(test::error_message([&] { label_voxel_array(bytes.array, 1); }).find("mask 7x5x4 int8: more than 1 distinct labels"),
              std::string::npos);
    EXPECT_EQ(label_voxel_array(bytes.array, 2).values, expected.values);
}

TEST(VoxelArray, NonIntegerLabelsAreRefusedNamingTheValueAndTheVoxel) {
    StoredArray<double> stored(ValueKind::Float, false, {2, 1, 0}, 0);
    stored.array.description = "mask 7x5x4 float64";
    const double fraction = 2.5;  // voxel (1, 2, 3) = linear index 1 + 7 * (2 + 5 * 3) = 120
    std::memcpy(stored.bytes.data() + 1 * stored.array.byte_strides[0] + 2 * stored.array.byte_strides[1] +
                    3 * stored.array.byte_strides[2],
                &fraction, sizeof fraction);
    EXPECT_EQ(test::error_message([&] { label_voxel_array(stored.array, 100); }),
              "mask 7x5x4 float64: value 2.5 of voxel #120 is not an integer: a label map holds integer labels");
}

TEST(VoxelArray, HalfFloatsDecodeExactly) {
    // IEEE binary16 bit patterns and their values: ±0, 1, −2, 65504 (largest), 2^-24
    // (smallest subnormal), 2^-14 (smallest normal), infinity and a NaN.
    const std::vector<std::pair<std::uint16_t, double>> halves{
        {0x0000, 0.0}, {0x8000, -0.0}, {0x3c00, 1.0}, {0xc000, -2.0}, {0x7bff, 65504.0},
        {0x0001, std::ldexp(1.0, -24)}, {0x0400, std::ldexp(1.0, -14)}, {0x7c00, INFINITY}, {0x7e00, NAN}};
    std::vector<std::uint16_t> bits;
    for (const auto& h : halves) bits.push_back(h.first);
    VoxelArray array;
    array.data = reinterpret_cast<const std::uint8_t*>(bits.data());
    array.dims = {static_cast<std::int64_t>(bits.size()), 1, 1};
    array.byte_strides = {2, 0, 0};
    array.kind = ValueKind::Float;
    array.bytes = 2;
    for (const auto& [pattern, value] : halves) {
        if (std::isnan(value)) continue;
        ValueRange exactly;
        exactly.has_min = exactly.has_max = true;
        exactly.min = exactly.max = value;
        const std::vector<std::uint8_t> mask = threshold_voxel_array(array, exactly);
        for (std::size_t n = 0; n < halves.size(); ++n)
            EXPECT_EQ(mask[n], halves[n].second == value ? 1 : 0) << std::hex << pattern << " at " << n;
    }
    const auto range = voxel_array_value_range(array);
    ASSERT_TRUE(range.has_value());  // NaN left out, the infinity kept
    EXPECT_EQ(range->first, -2.0);
    EXPECT_EQ(range->second, INFINITY);
}

TEST(VoxelArray, BadArraysAreRejectedByName) {
    std::uint8_t byte = 1;
    VoxelArray array;
    array.data = &byte;
    array.dims = {1, 0, 1};
    array.description = "mask 1x0x1 uint8";
    EXPECT_THROW(
        {
            try {
                check_voxel_array(array);
            } catch (const Error& e) {
                EXPECT_STREQ(e.what(), "mask 1x0x1 uint8: every dimension must be positive (got 1x0x1)");
                throw;
            }
        },
        Error);
    array.dims = {1, 1, 1};
    array.kind = ValueKind::Float;
    array.bytes = 16;
    EXPECT_THROW(check_voxel_array(array), Error);
}

Eigen::Matrix4d oblique_mirrored_affine() {
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    Eigen::Matrix4d affine = Eigen::Matrix4d::Identity();
    affine.block<3, 3>(0, 0) = rotation * Eigen::Vector3d(-1, 1, 1).asDiagonal() * Eigen::Vector3d(0.5, 2, 1.5).asDiagonal();
    affine.block<3, 1>(0, 3) = Eigen::Vector3d(10, -20, 30);
    return affine;
}

TEST(GridPlacement, AffineSplitsIntoSpacingOriginAndDirectionAndBackInLpsAndRas) {
    const Eigen::Matrix4d affine = oblique_mirrored_affine();
    const VoxelGrid grid = grid_from_affine(kDims, affine);
    EXPECT_EQ(grid.dims, kDims);
    EXPECT_TRUE(grid.spacing.isApprox(Eigen::Vector3d(0.5, 2, 1.5), 1e-14));
    EXPECT_TRUE(grid.origin.isApprox(Eigen::Vector3d(10, -20, 30)));
    EXPECT_TRUE((grid.direction.transpose() * grid.direction).isIdentity(1e-14));
    EXPECT_LT(grid.direction.determinant(), 0);
    EXPECT_TRUE(grid_affine(grid).isApprox(affine, 1e-14));
    // The same placement given as nibabel gives it (RAS = diag(-1,-1,1) LPS) is the same grid.
    const Eigen::Matrix4d ras_affine = Eigen::Vector4d(-1, -1, 1, 1).asDiagonal() * affine;
    const VoxelGrid from_ras = grid_from_affine(kDims, ras_affine, OutputSpace::Ras);
    EXPECT_TRUE(from_ras.direction.isApprox(grid.direction, 1e-14));
    EXPECT_TRUE(from_ras.origin.isApprox(grid.origin, 1e-14));
    EXPECT_TRUE(grid_affine(grid, OutputSpace::Ras).isApprox(ras_affine, 1e-14));
    // In voxel coordinates voxel (i,j,k) is at (i,j,k).
    EXPECT_TRUE(grid_affine(grid, OutputSpace::Voxel).isApprox(Eigen::Matrix4d::Identity(), 1e-14));
}

TEST(GridPlacement, RefusesWhatIsNoVoxelToWorldAffineOfPerpendicularAxes) {
    Eigen::Matrix4d sheared = Eigen::Matrix4d::Identity();
    sheared(0, 1) = 0.01;  // 0.57 degrees off
    EXPECT_THROW(grid_from_affine(kDims, sheared), Error);
    sheared(0, 1) = 1e-5;  // float32 rounding: accepted, and orthonormalized
    EXPECT_LT(orthonormality_error(grid_from_affine(kDims, sheared).direction), 1e-14);
    Eigen::Matrix4d projective = Eigen::Matrix4d::Identity();
    projective(3, 0) = 1;
    EXPECT_THROW(grid_from_affine(kDims, projective), Error);
    EXPECT_THROW(grid_from_affine(kDims, Eigen::Vector4d(1, 1, 0, 1).asDiagonal()), Error);
    EXPECT_THROW(grid_from_affine(kDims, Eigen::Vector4d(1, NAN, 1, 1).asDiagonal()), Error);
    EXPECT_THROW(grid_from_affine(kDims, Eigen::Matrix4d::Identity(), OutputSpace::Voxel), Error);
}

TEST(GridPlacement, AMeshOfAnAffinePlacedGridGoesToTheWorldWithFacesOutward) {
    // A unit cube's faces, outward in the grid frame; mirrored and rotated into the world.
    PolygonMesh cube;
    cube.vertices.resize(8, 3);
    for (int v = 0; v < 8; ++v) cube.vertices.row(v) << (v & 1), ((v >> 1) & 1), ((v >> 2) & 1);
    cube.faces.resize(6, 4);
    cube.faces << 0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5;
    cube.face_normals.resize(6, 3);
    cube.face_normals << 0, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, -1, 0, 0, 1, 0, 0;
    const VoxelGrid grid = grid_from_affine(kDims, oblique_mirrored_affine());
    const PolygonMesh world = mesh_in_space(cube, grid, OutputSpace::Lps);
    for (int f = 0; f < 6; ++f) {
        const auto corner = [&](int n) { return Eigen::Vector3d(world.vertices.row(world.faces(f, n))); };
        const Eigen::Vector3d right_hand = (corner(1) - corner(0)).cross(corner(2) - corner(0)).normalized();
        EXPECT_TRUE(right_hand.isApprox(world.face_normals.row(f).transpose(), 1e-12)) << "face " << f;
        const Eigen::Vector3d centre = world.vertices.colwise().mean();
        EXPECT_GT(right_hand.dot(corner(0) - centre), 0) << "face " << f << " points inward";
    }
    // Grid-frame point p = origin + spacing ⊙ index is at affine · index in the world.
    const Eigen::Vector3d index(0.25, -1.5, 2);
    const Eigen::Vector3d p = grid.origin + grid.spacing.cwiseProduct(index);
    const Eigen::Vector4d expected = oblique_mirrored_affine() * index.homogeneous();
    EXPECT_TRUE(grid_to_space(grid, OutputSpace::Lps).apply(p).isApprox(expected.head<3>(), 1e-12));
}

TEST(ArraySource, PipelineOnAnArrayEqualsThePipelineOnItsMask) {
    const BinaryVolume ball = test::make_ball(14, 4.6, 6.7);
    std::vector<float> values(ball.mask.begin(), ball.mask.end());
    for (float& v : values) v = v ? 0.75f : -1.0f;
    VolumeSource source;
    source.array = VoxelArray{reinterpret_cast<const std::uint8_t*>(values.data()), ball.grid.dims, {4, 4 * 14, 4 * 14 * 14},
                              ValueKind::Float, 4, false, "array"};
    source.spacing = Eigen::Vector3d(0.5, 0.5, 0.5);
    LoadedVolume loaded;
    loaded.volume = ball;
    loaded.volume.grid.spacing = *source.spacing;
    loaded.h = 0.5;
    const PipelineResult from_array = run_pipeline(source, PipelineOptions{});
    const PipelineResult from_mask = run_pipeline(loaded, PipelineOptions{});
    EXPECT_EQ(from_array.surface.quads, from_mask.surface.quads);
    EXPECT_TRUE(from_array.regularization.positions.isApprox(from_mask.regularization.positions, 1e-12));
    EXPECT_EQ(from_array.stage_seconds.front().first, "read");
}

TEST(ArraySource, ALabelMapArrayIsPlacedAsItsMaskAndKeepsItsLabels) {
    const std::vector<std::int16_t> values = [] {
        std::vector<std::int16_t> v(6 * 5 * 4, 0);
        for (std::size_t n = 0; n < v.size(); ++n) v[n] = static_cast<std::int16_t>(n % 3 == 0 ? 9 : n % 7 == 0 ? 4 : 0);
        return v;
    }();
    VolumeSource source;
    source.array = VoxelArray{reinterpret_cast<const std::uint8_t*>(values.data()), {6, 5, 4}, {2, 12, 60},
                              ValueKind::Signed, 2, false, "mask 6x5x4 int16"};
    source.affine = oblique_mirrored_affine();
    source.multi_label = true;
    const LoadedVolume loaded = load_volume(source);
    ASSERT_TRUE(loaded.labels.has_value());
    EXPECT_EQ(loaded.labels->values, (std::vector<std::int64_t>{0, 4, 9}));
    const VoxelGrid placed = grid_from_affine({6, 5, 4}, oblique_mirrored_affine(), OutputSpace::Lps);
    EXPECT_EQ(loaded.labels->grid.spacing, placed.spacing);
    EXPECT_EQ(loaded.labels->grid.origin, placed.origin);
    EXPECT_EQ(loaded.labels->grid.direction, placed.direction);
    EXPECT_EQ(loaded.volume.grid.direction, placed.direction);
    for (std::size_t n = 0; n < values.size(); ++n) ASSERT_EQ(loaded.labels->values[loaded.labels->labels[n]], values[n]);
    EXPECT_EQ(loaded.file.format, "array");
    EXPECT_TRUE(loaded.file.world_geometry);
    source.labels = {9};
    EXPECT_EQ(load_volume(source).labels->values, (std::vector<std::int64_t>{0, 9}));
    const std::vector<std::int16_t> zeros(values.size(), 0);
    source.array->data = reinterpret_cast<const std::uint8_t*>(zeros.data());
    source.labels.clear();
    EXPECT_EQ(test::error_message([&] { load_volume(source); }),
              "mask 6x5x4 int16: no voxel has a label (with --multi-label every non-zero value is one); its values range "
              "from 0 to 0");
}

TEST(ArraySource, EmptyObjectAndPlacementErrorsNameTheProblem) {
    const std::vector<std::int16_t> values(4 * 4 * 4, 5);
    VolumeSource source;
    source.array = VoxelArray{reinterpret_cast<const std::uint8_t*>(values.data()), {4, 4, 4}, {2, 8, 32},
                              ValueKind::Signed, 2, false, "mask 4x4x4 int16"};
    source.min_value = 6;
    const auto message = [&] {
        try {
            load_volume(source);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message(), "mask 4x4x4 int16: the object is empty: no voxel has value >= 6; its values range from 5 to 5 "
                         "(choose the object's values with --label, --min and --max)");
    source.min_value.reset();
    source.spacing = Eigen::Vector3d(1, NAN, 1);
    EXPECT_EQ(message(), "--spacing: every voxel size must be positive and finite");
    source.affine = Eigen::Matrix4d::Identity();
    EXPECT_EQ(message(), "affine gives the spacing and the origin: do not give them too");
    source.spacing.reset();
    source.input_path = "x.vol";
    EXPECT_EQ(message(), "give either an array, a volume file or --shape, not several");
    source.array.reset();
    EXPECT_EQ(message(), "affine and origin apply to arrays only");
}

TEST(FileErrors, MissingFilesAreFileErrorsWithTheirErrno) {
    try {
        load_volume(VolumeSource{"/nonexistent/volume.vol"});
        FAIL() << "no error";
    } catch (const FileError& e) {
        EXPECT_EQ(e.error_number(), ENOENT);
        EXPECT_STREQ(e.what(), "/nonexistent/volume.vol: cannot open: no such file");
    }
}

}  // namespace
}  // namespace dsreg
