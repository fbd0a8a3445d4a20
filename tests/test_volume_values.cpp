// read_volume_values: the voxel values (not a thresholded mask) of every volume format, through
// the same readers as read_volume. Round trips against the writers, hand-made raw files of
// every type, agreement with the thresholding readers, and the same errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

namespace dsreg {
namespace {

namespace fs = std::filesystem;

const Index3 kDims{5, 4, 3};

class VolumeValues : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("dsreg-values-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                            "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

/// 60 distinct values 0 … 59·step + offset, x fastest.
template <typename T>
std::vector<T> pattern(T step, T offset) {
    std::vector<T> values;
    for (std::int64_t i = 0; i < kDims[0] * kDims[1] * kDims[2]; ++i) values.push_back(static_cast<T>(offset + T(i) * step));
    return values;
}

template <typename T>
void expect_values(const ScalarVolume& volume, const std::vector<T>& values) {
    EXPECT_EQ(volume.grid.dims, kDims);
    EXPECT_EQ(volume.grid.spacing, Eigen::Vector3d(1, 1, 1));
    EXPECT_EQ(volume.grid.origin, Eigen::Vector3d(0, 0, 0));
    ASSERT_EQ(volume.values.size(), values.size());
    for (std::size_t i = 0; i < values.size(); ++i)
        ASSERT_EQ(volume.values[i], static_cast<float>(static_cast<double>(values[i]))) << "voxel #" << i;
}

TEST_F(VolumeValues, VolVersionsTwoAndThreeRoundTrip) {
    const std::vector<std::uint8_t> values = pattern<std::uint8_t>(4, 7);  // up to 243
    for (const int version : {2, 3}) {
        const std::string file = path("v" + std::to_string(version) + ".vol");
        write_vol(file, kDims, values, version);
        SCOPED_TRACE(file);
        expect_values(read_volume_values(file), values);
    }
}

TEST_F(VolumeValues, LongvolRoundTripsWithFloatRounding) {
    std::vector<std::uint64_t> values = pattern<std::uint64_t>(1000, 3);
    values[5] = (std::uint64_t(1) << 40) + 1;  // above 2^24: rounded to the nearest float
    write_longvol(path("a.longvol"), kDims, values);
    const ScalarVolume volume = read_volume_values(path("a.longvol"));
    expect_values(volume, values);
    EXPECT_EQ(volume.value(0, 1, 0), std::ldexp(1.0f, 40));
}

TEST_F(VolumeValues, Pgm3dBinaryAndAsciiRoundTrip) {
    for (const std::uint16_t step : {std::uint16_t(3), std::uint16_t(1000)}) {  // 1-byte and 2-byte binary samples
        const std::vector<std::uint16_t> values = pattern<std::uint16_t>(step, 1);
        for (const bool binary : {true, false}) {
            const std::string file = path(std::string(binary ? "b" : "a") + std::to_string(step) + ".pgm3d");
            write_pgm3d(file, kDims, values, binary);
            SCOPED_TRACE(file);
            expect_values(read_volume_values(file), values);
        }
    }
}

template <typename T>
void write_raw(const std::string& file, const std::vector<T>& values, bool big_endian, std::size_t header_bytes) {
    std::string bytes(header_bytes, 'H');
    for (const T v : values) {
        char raw[sizeof(T)];
        std::memcpy(raw, &v, sizeof(T));  // the machine is little-endian (x86-64, as the CI)
        if (big_endian) std::reverse(raw, raw + sizeof(T));
        bytes.append(raw, sizeof(T));
    }
    std::ofstream(file, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

template <typename T>
void check_raw(const std::string& file, RawVoxelType type, const std::vector<T>& values) {
    for (const bool big_endian : {false, true}) {
        SCOPED_TRACE(file + (big_endian ? " big-endian" : " little-endian"));
        write_raw(file, values, big_endian, 16);
        RawVolumeLayout layout;
        layout.dims = kDims;
        layout.type = type;
        layout.big_endian = big_endian;
        layout.header_bytes = 16;
        expect_values(read_volume_values(file, &layout), values);
    }
}

TEST_F(VolumeValues, RawVolumesOfEveryTypeKeepSignsAndFractions) {
    check_raw(path("u8.raw"), RawVoxelType::UInt8, pattern<std::uint8_t>(4, 1));
    check_raw(path("i8.raw"), RawVoxelType::Int8, pattern<std::int8_t>(2, -60));
    check_raw(path("u16.raw"), RawVoxelType::UInt16, pattern<std::uint16_t>(1000, 5));
    check_raw(path("i16.raw"), RawVoxelType::Int16, pattern<std::int16_t>(-500, 1200));
    check_raw(path("u32.raw"), RawVoxelType::UInt32, pattern<std::uint32_t>(70000, 9));
    check_raw(path("i32.raw"), RawVoxelType::Int32, pattern<std::int32_t>(-70000, 12));
    check_raw(path("u64.raw"), RawVoxelType::UInt64, pattern<std::uint64_t>(123456, 2));
    check_raw(path("i64.raw"), RawVoxelType::Int64, pattern<std::int64_t>(-123456, 2));
    check_raw(path("f32.raw"), RawVoxelType::Float32, pattern<float>(-0.375f, 2.5f));
    check_raw(path("f64.raw"), RawVoxelType::Float64, pattern<double>(0.125, -3.0));
}

TEST_F(VolumeValues, ThresholdOfTheValuesIsTheMaskOfReadVolume) {
    const std::vector<std::uint16_t> values = pattern<std::uint16_t>(17, 0);
    write_pgm3d(path("t.pgm3d"), kDims, values, true);
    const ScalarVolume volume = read_volume_values(path("t.pgm3d"));
    for (const ValueRange& range : {ValueRange{}, ValueRange{true, 300.0, true, 700.0}}) {
        const BinaryVolume mask = read_volume(path("t.pgm3d"), range);
        ASSERT_EQ(mask.mask.size(), volume.values.size());
        for (std::size_t i = 0; i < volume.values.size(); ++i) EXPECT_EQ(mask.mask[i] != 0, range.contains(volume.values[i])) << i;
    }
}

/// The value reader shares the checks of the mask reader: same errors for the same files.
TEST_F(VolumeValues, BrokenFilesGiveTheSameErrorsAsReadVolume) {
    const std::vector<std::uint8_t> values = pattern<std::uint8_t>(1, 0);
    write_vol(path("ok.vol"), kDims, values, 2);
    std::string bytes;
    {
        std::ifstream in(path("ok.vol"), std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    std::ofstream(path("truncated.vol"), std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() - 3));
    std::ofstream(path("bad.pgm3d"), std::ios::binary) << "P2-3D\n2 1 1\n9\n3 12\n";  // 12 > maxval 9
    std::ofstream(path("x.unknown")) << "?";
    for (const std::string name : {"truncated.vol", "bad.pgm3d", "x.unknown", "missing.vol"}) {
        std::string mask_error, value_error;
        try {
            read_volume(path(name));
        } catch (const Error& e) {
            mask_error = e.what();
        }
        try {
            read_volume_values(path(name));
        } catch (const Error& e) {
            value_error = e.what();
        }
        EXPECT_FALSE(value_error.empty()) << name;
        EXPECT_EQ(value_error, mask_error) << name;
    }
    EXPECT_THROW(read_volume_values(path("ok.vol") + ".raw"), Error);  // .raw without a layout
}

TEST_F(VolumeValues, LimitsApplyToValuesToo) {
    write_vol(path("big.vol"), kDims, pattern<std::uint8_t>(1, 0), 3);
    VolumeLimits limits;
    limits.max_voxels = 10;
    EXPECT_THROW(read_volume_values(path("big.vol"), nullptr, limits), Error);
}

TEST(VolumeValuesSharedData, BunnyValuesThresholdToTheBunnyMask) {
    const std::string file = std::string(DSREG_SHARED_DATA_DIR) + "/bunny-64.vol";
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found";
    const ScalarVolume values = read_volume_values(file);
    const BinaryVolume mask = read_volume(file);
    ASSERT_EQ(values.values.size(), mask.mask.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < mask.mask.size(); ++i) mismatches += (values.values[i] > 0) != (mask.mask[i] != 0) ? 1 : 0;
    EXPECT_EQ(mismatches, 0u);
}

}  // namespace
}  // namespace dsreg
