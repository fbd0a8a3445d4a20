// Value histograms of volume files and their main modes (dsreg/value_histogram.hpp), and the
// pipeline's warning when the object takes most of the volume.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "dsreg/pipeline.hpp"
#include "dsreg/value_histogram.hpp"
#include "dsreg/volume_io.hpp"
#include "medical_test_support.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

using namespace dsreg;

namespace {

TEST(ValueHistogram, CountsEveryIntegerValueOnce) {
    test::ScratchFolder scratch("histogram");
    VoxelGrid grid;
    grid.dims = {10, 10, 10};
    std::vector<double> values(1000, 40.0);
    for (std::size_t n = 0; n < 120; ++n) values[n] = 200;
    for (std::size_t n = 120; n < 130; ++n) values[n] = -3;
    write_image(scratch.path("v.nrrd"), grid, values, RawVoxelType::Int16);
    const ValueHistogram h = read_value_histogram(scratch.path("v.nrrd"));
    EXPECT_EQ(h.count, 1000);
    EXPECT_EQ(h.min, -3);
    EXPECT_EQ(h.max, 200);
    EXPECT_TRUE(h.integral);
    ASSERT_EQ(h.bins.size(), 204u);  // one bin per value from -3 to 200
    EXPECT_EQ(h.bins[0], 10);
    EXPECT_EQ(h.bins[43], 870);
    EXPECT_EQ(h.bins[203], 120);
    const std::vector<HistogramMode> modes = histogram_modes(h);
    ASSERT_EQ(modes.size(), 3u);
    EXPECT_EQ(modes[0].low, 40);
    EXPECT_EQ(modes[0].high, 40);
    EXPECT_NEAR(modes[0].fraction, 0.87, 1e-12);
    EXPECT_EQ(modes[1].low, 200);
    EXPECT_EQ(modes[2].low, -3);
    EXPECT_EQ(describe_modes(modes, true), "40 (87%), 200 (12%), -3 (1%)");
}

TEST(ValueHistogram, IntegersCountedInThePassOverTheRangeEqualASecondPass) {
    // Integers in an order that lowers the minimum and raises the maximum several times: the
    // counts kept while the range grows are those of a second pass over fixed bins; beyond the
    // limit of values they are given up.
    std::vector<double> values;
    for (int n = 0; n < 500; ++n) values.push_back(double((n * 37) % 90) - double(n % 7 == 0 ? 40 : 0));
    ValueHistogram one_pass;
    one_pass.exact_limit = 256;
    for (double v : values) one_pass.add(v);
    ValueHistogram two_passes;
    for (double v : values) two_passes.add(v);
    ASSERT_TRUE(two_passes.exact_counts.empty());  // no limit given: nothing counted
    two_passes.bins.assign(std::size_t(two_passes.max - two_passes.min + 1), 0);
    for (double v : values) two_passes.add(v);
    EXPECT_EQ(one_pass.min, two_passes.min);
    EXPECT_EQ(one_pass.max, two_passes.max);
    EXPECT_EQ(one_pass.exact_counts, two_passes.bins);
    ValueHistogram narrow;
    narrow.exact_limit = 50;  // the values span 130
    for (double v : values) narrow.add(v);
    EXPECT_TRUE(narrow.exact_counts.empty());
    ValueHistogram fractional;
    fractional.exact_limit = 256;
    for (double v : {1.0, 2.0, 2.5}) fractional.add(v);
    EXPECT_TRUE(fractional.exact_counts.empty());
}

TEST(ValueHistogram, ModesAreDisjointAndHoldEveryVoxelBetweenMinima) {
    ValueHistogram h;
    h.min = 0;
    h.max = 255;
    h.bin_width = 1;
    h.bins.assign(256, 0);
    // Two bumps: around 30 (wide) and around 180 (narrow), with a valley between them.
    for (int v = 0; v < 256; ++v)
        h.bins[std::size_t(v)] = std::int64_t(1000 * std::exp(-std::pow((v - 30) / 20.0, 2)) + 300 * std::exp(-std::pow((v - 180) / 8.0, 2)));
    for (const std::int64_t b : h.bins) h.count += b;
    const std::vector<HistogramMode> modes = histogram_modes(h);
    ASSERT_EQ(modes.size(), 2u);
    EXPECT_LT(modes[0].high, modes[1].low);  // disjoint, in value order here
    EXPECT_NEAR(modes[0].fraction + modes[1].fraction, 1.0, 0.01);
    EXPECT_GT(modes[0].fraction, modes[1].fraction);
}

TEST(ValueHistogram, FloatValuesGetEqualBins) {
    test::ScratchFolder scratch("histogram-float");
    VoxelGrid grid;
    grid.dims = {8, 8, 8};
    std::vector<double> values;
    for (int n = 0; n < 512; ++n) values.push_back(n < 256 ? 0.25 + n * 1e-4 : 7.5);
    write_image(scratch.path("f.nii"), grid, values, RawVoxelType::Float32);
    const ValueHistogram h = read_value_histogram(scratch.path("f.nii"), nullptr, {}, 64);
    EXPECT_FALSE(h.integral);
    EXPECT_EQ(h.bins.size(), 64u);
    std::int64_t total = 0;
    for (const std::int64_t b : h.bins) total += b;
    EXPECT_EQ(total, 512);
    EXPECT_EQ(h.bins.back(), 256);  // 7.5 is the maximum: the last bin, closed
}

TEST(ValueHistogram, PipelineWarnsWhenTheObjectTakesMostOfTheVolume) {
    test::ScratchFolder scratch("histogram-warning");
    VoxelGrid grid;
    grid.dims = {12, 12, 12};
    std::vector<double> values(std::size_t(grid.voxel_count()), 40.0);  // a "scanner cylinder" of value 40
    for (std::int64_t k = 4; k < 8; ++k)
        for (std::int64_t j = 4; j < 8; ++j)
            for (std::int64_t i = 4; i < 8; ++i) values[std::size_t(grid.linear_index(i, j, k))] = 200;
    write_image(scratch.path("ct.mha"), grid, values, RawVoxelType::UInt8);
    VolumeSource source;
    source.input_path = scratch.path("ct.mha");
    const LoadedVolume everything = load_volume(source);
    ASSERT_EQ(everything.warnings.size(), 1u);
    EXPECT_NE(everything.warnings[0].find("takes 100% of the volume"), std::string::npos) << everything.warnings[0];
    EXPECT_NE(everything.warnings[0].find("40 (96%), 200 (4%)"), std::string::npos) << everything.warnings[0];
    source.label = 200;
    const LoadedVolume object = load_volume(source);
    EXPECT_TRUE(object.warnings.empty());
    EXPECT_EQ(object.volume.object_voxel_count(), 64);
    source.min_value = 100;
    EXPECT_THROW(load_volume(source), Error);  // --label with --min
}

TEST(ValueHistogram, LobsterModesSeparateTheCylinderFromTheLobster) {
    const std::string path = std::string(DSREG_SHARED_DATA_DIR) + "/lobster.vol";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
    const ValueHistogram h = read_value_histogram(path);
    const std::vector<HistogramMode> modes = histogram_modes(h);
    ASSERT_GE(modes.size(), 3u);
    // The CT's surroundings (0), the scanner's cylinder, and the lobster's brighter values.
    double previous_high = -1;
    std::vector<HistogramMode> by_value = modes;
    std::sort(by_value.begin(), by_value.end(), [](const HistogramMode& a, const HistogramMode& b) { return a.low < b.low; });
    for (const HistogramMode& mode : by_value) {
        EXPECT_GT(mode.low, previous_high);
        previous_high = mode.high;
    }
    EXPECT_EQ(by_value.front().low, 0);
    EXPECT_GE(by_value.back().low, 100);  // the lobster: above the cylinder's values
}

}  // namespace
