// Tests of the volume readers and writers (dsreg/volume_io.hpp): round trips through every
// writer/reader pair, readers against hand-made files (so that a symmetric writer/reader bug
// cannot hide), rejection of every kind of broken file, and the real DGtal files of
// ../shared/data when present.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "dsreg/error.hpp"
#include "dsreg/volume.hpp"
#include "dsreg/volume_io.hpp"
// White-box test of the chunked decoder; everything else goes through the public API.
#include "../src/volume/volume_io_internal.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

namespace fs = std::filesystem;
using dsreg::BinaryVolume;
using dsreg::Index3;
using dsreg::RawVolumeLayout;
using dsreg::RawVoxelType;
using dsreg::ValueRange;

namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

ValueRange range_min(double min) {
    ValueRange r;
    r.has_min = true;
    r.min = min;
    return r;
}
ValueRange range_max(double max) {
    ValueRange r;
    r.has_max = true;
    r.max = max;
    return r;
}
ValueRange range_between(double min, double max) {
    ValueRange r = range_min(min);
    r.has_max = true;
    r.max = max;
    return r;
}

std::string describe(const ValueRange& r) {
    std::ostringstream text;
    text << "range{" << (r.has_min ? "min=" + std::to_string(r.min) : "value>0") << (r.has_max ? " max=" + std::to_string(r.max) : "")
         << "}";
    return text.str();
}

std::int64_t voxel_count(const Index3& dims) { return dims[0] * dims[1] * dims[2]; }

/// The mask a correct reader must produce: the threshold of the written values, voxel by voxel.
template <typename T>
std::vector<std::uint8_t> expected_mask(const std::vector<T>& values, const ValueRange& range) {
    std::vector<std::uint8_t> mask;
    for (const T v : values) mask.push_back(range.contains(static_cast<double>(v)) ? 1 : 0);
    return mask;
}

template <typename T>
void expect_volume_matches(const BinaryVolume& volume, const Index3& dims, const std::vector<T>& values, const ValueRange& range) {
    SCOPED_TRACE(describe(range));
    EXPECT_EQ(volume.grid.dims, dims);
    EXPECT_EQ(volume.grid.spacing, Eigen::Vector3d(1, 1, 1));
    EXPECT_EQ(volume.grid.origin, Eigen::Vector3d(0, 0, 0));
    const std::vector<std::uint8_t> expected = expected_mask(values, range);
    ASSERT_EQ(volume.mask.size(), expected.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < expected.size(); ++i)
        if (volume.mask[i] != expected[i] && mismatches++ < 5) ADD_FAILURE() << "voxel #" << i << ": mask " << int(volume.mask[i]);
    EXPECT_EQ(mismatches, 0u);
    // The pattern must exercise both sides of the threshold, or the comparison proves little.
    const auto inside = std::count(expected.begin(), expected.end(), 1);
    EXPECT_GT(inside, 0);
    EXPECT_LT(inside, static_cast<std::ptrdiff_t>(expected.size()));
}

/// Runs `read` and checks that it throws dsreg::Error whose message names `path` and contains `fragment`.
void expect_error(const std::function<void()>& read, const std::string& path, const std::string& fragment) {
    try {
        read();
        ADD_FAILURE() << "no dsreg::Error thrown; expected one containing '" << fragment << "'";
    } catch (const dsreg::Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(path), std::string::npos) << "message does not name the file: " << message;
        EXPECT_NE(message.find(fragment), std::string::npos) << "message lacks '" << fragment << "': " << message;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
    }
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    ASSERT_TRUE(out.good()) << path;
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream content;
    content << in.rdbuf();
    return content.str();
}

/// zlib's one-shot compress(), as DGtal's version 3 payloads are made (independent of our writer).
std::string zlib_compress(const std::string& data) {
    uLongf size = compressBound(static_cast<uLong>(data.size()));
    std::string out(size, '\0');
    const int code = compress(reinterpret_cast<Bytef*>(&out[0]), &size, reinterpret_cast<const Bytef*>(data.data()),
                              static_cast<uLong>(data.size()));
    EXPECT_EQ(code, Z_OK);
    out.resize(size);
    return out;
}

/// zlib's one-shot uncompress() of exactly `size` bytes (independent of our reader).
std::string zlib_uncompress(const std::string& data, std::size_t size) {
    std::string out(size, '\0');
    uLongf out_size = static_cast<uLongf>(size);
    const int code = uncompress(reinterpret_cast<Bytef*>(&out[0]), &out_size, reinterpret_cast<const Bytef*>(data.data()),
                                static_cast<uLong>(data.size()));
    EXPECT_EQ(code, Z_OK);
    EXPECT_EQ(out_size, size);
    return out;
}

/// A DGtal-style header with the given dimension texts and version text.
std::string vol_header(const std::string& x, const std::string& y, const std::string& z, const std::string& version) {
    return "Center-X: 0\nCenter-Y: 0\nCenter-Z: 0\nX: " + x + "\nY: " + y + "\nZ: " + z +
           "\nVoxel-Size: 1\nAlpha-Color: 0\nVoxel-Endian: 0\nInt-Endian: 0123\nVersion: " + version + "\n.\n";
}

/// Byte encoding of integer or floating-point values, in the requested byte order.
template <typename T>
std::string encode_values(const std::vector<T>& values, bool big_endian) {
    std::string out;
    for (const T v : values) {
        std::uint64_t bits = 0;
        if constexpr (std::is_floating_point_v<T>) {
            using Bits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
            Bits b;
            std::memcpy(&b, &v, sizeof b);
            bits = b;
        } else {
            bits = static_cast<std::uint64_t>(static_cast<std::make_unsigned_t<T>>(v));
        }
        for (std::size_t i = 0; i < sizeof(T); ++i) {
            const std::size_t shift = big_endian ? 8 * (sizeof(T) - 1 - i) : 8 * i;
            out.push_back(static_cast<char>((bits >> shift) & 0xff));
        }
    }
    return out;
}

/// 5x4x3: small, non-cubic, so a swapped axis changes the result.
const Index3 kDims{5, 4, 3};

/// Values depending on (i, j, k) differently along each axis, in [0, modulus).
std::vector<int> base_pattern(const Index3& dims, int modulus) {
    std::vector<int> values;
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) values.push_back(static_cast<int>((i * 37 + j * 11 + k * 5 + i * j * k) % modulus));
    return values;
}

class VolumeIoTest : public ::testing::Test {
protected:
    void SetUp() override {
        const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        dir_ = fs::temp_directory_path() / ("dsreg_volume_io_" + std::to_string(::getpid()) + "_" + name);
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

// ---------------------------------------------------------------------------------------------
// Round trips through our writers

TEST_F(VolumeIoTest, VolRoundTripBothVersions) {
    std::vector<std::uint8_t> values;
    for (const int v : base_pattern(kDims, 256)) values.push_back(static_cast<std::uint8_t>(v * 7 % 256));
    const std::vector<ValueRange> ranges = {ValueRange{}, range_min(100), range_max(50), range_between(30, 200)};
    for (const int version : {2, 3}) {
        SCOPED_TRACE("version " + std::to_string(version));
        const std::string file = path("pattern_v" + std::to_string(version) + ".vol");
        dsreg::write_vol(file, kDims, values, version);
        for (const ValueRange& range : ranges) expect_volume_matches(dsreg::read_vol(file, range), kDims, values, range);
    }
}

TEST_F(VolumeIoTest, LongvolRoundTripBothVersions) {
    std::vector<std::uint64_t> values;
    for (const int v : base_pattern(kDims, 61)) values.push_back(static_cast<std::uint64_t>(v) * 1000000000039ull);
    values[7] = 0x0102030405060708ull;  // every byte distinct: a byte-order bug changes its value
    const double big = 1e13;
    const std::vector<ValueRange> ranges = {ValueRange{}, range_min(big), range_max(big), range_between(1e12, 4e13),
                                            range_between(double(0x0102030405060708ull), double(0x0102030405060708ull))};
    for (const int version : {2, 3}) {
        SCOPED_TRACE("version " + std::to_string(version));
        const std::string file = path("pattern_v" + std::to_string(version) + ".longvol");
        dsreg::write_longvol(file, kDims, values, version);
        for (const ValueRange& range : ranges) {
            if (range.has_min && range.min == double(0x0102030405060708ull)) {
                // Only voxel 7 has that value.
                const BinaryVolume v = dsreg::read_longvol(file, range);
                EXPECT_EQ(v.object_voxel_count(), 1);
                EXPECT_EQ(v.mask[7], 1);
                continue;
            }
            expect_volume_matches(dsreg::read_longvol(file, range), kDims, values, range);
        }
    }
}

TEST_F(VolumeIoTest, LongvolV3LargeIncompressiblePayload) {
    // Half the voxels hold pseudo-random values, so the compressed stream spans several read
    // chunks and inflate hands over samples split between chunks (a dropped or misplaced partial
    // sample shifts every later voxel). The other half hold `marker`, checked exactly with the
    // window [marker, marker]. Byte-exact reassembly of split samples is tested directly by
    // VolumeIoMaskWriter.SamplesSplitAcrossChunksAreReassembled.
    const Index3 dims{64, 50, 20};
    const std::uint64_t marker = 0x000F0E0D0C0B0A09ull;  // < 2^52: exactly representable as double
    std::vector<std::uint64_t> values(static_cast<std::size_t>(voxel_count(dims)));
    std::uint64_t state = 12345;
    for (auto& v : values) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        v = (state >> 63) != 0 ? marker : state >> 12;
    }
    const std::string file = path("random.longvol");
    dsreg::write_longvol(file, dims, values, 3);
    EXPECT_GT(fs::file_size(file), 200000u);  // several 64 KiB read chunks
    for (const ValueRange& range : {range_min(double(std::uint64_t(1) << 51)), range_between(double(marker), double(marker))})
        expect_volume_matches(dsreg::read_longvol(file, range), dims, values, range);
}

TEST_F(VolumeIoTest, Pgm3dRoundTripAsciiAndBinary) {
    const std::vector<int> base = base_pattern(kDims, 61);
    std::vector<std::uint16_t> small, wide;
    for (const int v : base) {
        small.push_back(static_cast<std::uint16_t>(v * 4));     // maxval < 256: 1 byte per value
        wide.push_back(static_cast<std::uint16_t>(v * 1000));   // maxval ≥ 256: 2 bytes per value
    }
    struct Case {
        const std::vector<std::uint16_t>* values;
        double scale;
        bool binary;
    };
    for (const Case& c : {Case{&small, 4, false}, Case{&small, 4, true}, Case{&wide, 1000, false}, Case{&wide, 1000, true}}) {
        const std::string file = path(std::string(c.binary ? "bin" : "ascii") + (c.scale > 4 ? "_wide" : "_small") + ".pgm3d");
        SCOPED_TRACE(file);
        dsreg::write_pgm3d(file, kDims, *c.values, c.binary);
        EXPECT_EQ(read_bytes(file).substr(0, 5), c.binary ? "P5-3D" : "P2-3D");
        for (const ValueRange& range : {ValueRange{}, range_min(20 * c.scale), range_max(10 * c.scale), range_between(5 * c.scale, 40 * c.scale)})
            expect_volume_matches(dsreg::read_pgm3d(file, range), kDims, *c.values, range);
    }
}

template <typename T>
void check_raw_type(const std::string& dir, RawVoxelType type, double scale) {
    std::vector<T> values;
    const bool is_signed = std::is_signed_v<T>;
    for (const int b : base_pattern(kDims, 61)) values.push_back(static_cast<T>((is_signed ? b - 30 : b) * scale));
    // With only a max, ValueRange still requires value > 0; negative windows need both bounds.
    std::vector<ValueRange> ranges = {ValueRange{}, range_min(5 * scale), range_max(10 * scale), range_between(10 * scale, 20 * scale)};
    if (is_signed) ranges.push_back(range_between(-10 * scale, -3 * scale));
    for (const bool big_endian : {false, true}) {
        for (const std::uint64_t header_bytes : {std::uint64_t(0), std::uint64_t(13)}) {
            SCOPED_TRACE(std::string(big_endian ? "big" : "little") + " endian, header " + std::to_string(header_bytes));
            const std::string file = dir + "/values_" + std::to_string(int(type)) + (big_endian ? "_be" : "_le") +
                                     std::to_string(header_bytes) + ".raw";
            write_bytes(file, std::string(header_bytes, '#') + encode_values(values, big_endian));
            RawVolumeLayout layout;
            layout.dims = kDims;
            layout.type = type;
            layout.big_endian = big_endian;
            layout.header_bytes = header_bytes;
            for (const ValueRange& range : ranges) expect_volume_matches(dsreg::read_raw(file, layout, range), kDims, values, range);
        }
    }
}

TEST_F(VolumeIoTest, RawAllTypesBothEndiannesses) {
    const std::string dir = dir_.string();
    {
        SCOPED_TRACE("uint8");
        check_raw_type<std::uint8_t>(dir, RawVoxelType::UInt8, 4);
    }
    {
        SCOPED_TRACE("int8");
        check_raw_type<std::int8_t>(dir, RawVoxelType::Int8, 4);
    }
    {
        SCOPED_TRACE("uint16");
        check_raw_type<std::uint16_t>(dir, RawVoxelType::UInt16, 1000);
    }
    {
        SCOPED_TRACE("int16");
        check_raw_type<std::int16_t>(dir, RawVoxelType::Int16, 1000);
    }
    {
        SCOPED_TRACE("uint32");
        check_raw_type<std::uint32_t>(dir, RawVoxelType::UInt32, 1000003);
    }
    {
        SCOPED_TRACE("int32");
        check_raw_type<std::int32_t>(dir, RawVoxelType::Int32, 1000003);
    }
    {
        SCOPED_TRACE("uint64");
        check_raw_type<std::uint64_t>(dir, RawVoxelType::UInt64, 1e12 + 39);
    }
    {
        SCOPED_TRACE("int64");
        check_raw_type<std::int64_t>(dir, RawVoxelType::Int64, 1e12 + 39);
    }
    {
        SCOPED_TRACE("float32");
        check_raw_type<float>(dir, RawVoxelType::Float32, 0.25);
    }
    {
        SCOPED_TRACE("float64");
        check_raw_type<double>(dir, RawVoxelType::Float64, 0.125);
    }
}

TEST(VolumeIoMaskWriter, SamplesSplitAcrossChunksAreReassembled) {
    // Inflate hands over payload bytes in chunks of arbitrary sizes. Feed the same bytes in
    // every chunk size from 1 to 17 and check each value exactly, with a window [v, v] for
    // several values v: any misplaced byte moves a value out of (or into) its window.
    using dsreg::volume_io_detail::MaskWriter;
    using dsreg::volume_io_detail::SampleFormat;
    using dsreg::volume_io_detail::SampleKind;
    const std::vector<std::int64_t> values = {0x0102030405060708, -0x0A0B0C0D0E0F, 42, -1, 0x7FFFFFFFFFFF, 0x0102030405060708, 7};
    struct Case {
        SampleFormat format;
        std::string bytes;
    };
    std::vector<std::int32_t> narrow(values.begin(), values.end());  // wraps: that is fine, both sides agree
    std::vector<double> reals(values.begin(), values.end());
    for (const Case& c : {Case{{8, SampleKind::Signed, false}, encode_values(values, false)},
                          Case{{8, SampleKind::Signed, true}, encode_values(values, true)},
                          Case{{4, SampleKind::Signed, true}, encode_values(narrow, true)},
                          Case{{8, SampleKind::Float, false}, encode_values(reals, false)}}) {
        std::vector<double> decoded_truth;
        if (c.format.bytes == 4)
            decoded_truth.assign(narrow.begin(), narrow.end());
        else
            decoded_truth.assign(reals.begin(), reals.end());
        for (std::size_t chunk = 1; chunk <= 17; ++chunk) {
            for (const double target : decoded_truth) {
                SCOPED_TRACE("bytes " + std::to_string(c.format.bytes) + (c.format.big_endian ? " BE" : " LE") + ", chunk " +
                             std::to_string(chunk) + ", target " + std::to_string(target));
                std::vector<std::uint8_t> mask(values.size(), 7);
                MaskWriter writer("memory", c.format, range_between(target, target), mask);
                for (std::size_t start = 0; start < c.bytes.size(); start += chunk) {
                    const std::string piece = c.bytes.substr(start, chunk);
                    writer.consume(reinterpret_cast<const std::uint8_t*>(piece.data()), piece.size());
                }
                EXPECT_TRUE(writer.complete());
                EXPECT_EQ(mask, expected_mask(decoded_truth, range_between(target, target)));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Readers against hand-made files, writers against independent decoders

TEST_F(VolumeIoTest, VolV3MadeWithZlibCompressIsRead) {
    std::vector<std::uint8_t> values;
    for (const int v : base_pattern(kDims, 3)) values.push_back(static_cast<std::uint8_t>(v * 96 / 2));  // {0, 48, 96}
    const std::string file = path("handmade.vol");
    write_bytes(file, vol_header("5", "4", "3", "3") + zlib_compress(std::string(values.begin(), values.end())));
    expect_volume_matches(dsreg::read_vol(file), kDims, values, ValueRange{});
    expect_volume_matches(dsreg::read_vol(file, range_between(96, 96)), kDims, values, range_between(96, 96));
}

TEST_F(VolumeIoTest, VolWritersProduceDgtalLayout) {
    std::vector<std::uint8_t> values;
    for (const int v : base_pattern(kDims, 256)) values.push_back(static_cast<std::uint8_t>(v));
    const std::string payload(values.begin(), values.end());

    const std::string v2 = path("w2.vol");
    dsreg::write_vol(v2, kDims, values, 2);
    const std::string bytes2 = read_bytes(v2);
    const std::size_t end2 = bytes2.find("\n.\n");
    ASSERT_NE(end2, std::string::npos);
    EXPECT_NE(bytes2.find("X: 5\nY: 4\nZ: 3\n"), std::string::npos);
    EXPECT_NE(bytes2.find("Version: 2\n"), std::string::npos);
    EXPECT_EQ(bytes2.substr(end2 + 3), payload);

    const std::string v3 = path("w3.vol");
    dsreg::write_vol(v3, kDims, values, 3);
    const std::string bytes3 = read_bytes(v3);
    const std::size_t end3 = bytes3.find("\n.\n");
    ASSERT_NE(end3, std::string::npos);
    EXPECT_NE(bytes3.find("Version: 3\n"), std::string::npos);
    EXPECT_EQ(zlib_uncompress(bytes3.substr(end3 + 3), payload.size()), payload);
}

TEST_F(VolumeIoTest, LongvolValuesAreLittleEndian) {
    // Hand-made: value 2^32 + 1 stored least significant byte first, as DGtal's LongvolWriter does.
    const Index3 dims{2, 1, 1};
    const std::string payload = std::string("\x01\x00\x00\x00\x01\x00\x00\x00", 8) + std::string(8, '\0');
    const std::string header = "X: 2\nY: 1\nZ: 1\nLvoxel-Size: 4\nAlpha-Color: 0\nLvoxel-Endian: 0\nInt-Endian: 0123\nVersion: 2\n.\n";
    const std::string file = path("handmade.longvol");
    write_bytes(file, header + payload);
    const BinaryVolume exact = dsreg::read_longvol(file, range_between(4294967297.0, 4294967297.0));
    EXPECT_EQ(exact.grid.dims, dims);
    EXPECT_EQ(exact.mask, (std::vector<std::uint8_t>{1, 0}));

    // And our writer emits the same bytes.
    const std::string written = path("written.longvol");
    dsreg::write_longvol(written, dims, {4294967297ull, 0}, 2);
    const std::string bytes = read_bytes(written);
    ASSERT_GE(bytes.size(), payload.size());
    EXPECT_EQ(bytes.substr(bytes.size() - payload.size()), payload);
}

TEST_F(VolumeIoTest, Pgm3dHandMadeWithCommentsAndBigEndianValues) {
    // ASCII, comments between header tokens, irregular whitespace in the data.
    const std::string ascii = path("handmade_ascii.pgm3d");
    write_bytes(ascii, "P2-3D\n# a comment\n2 # width\n2\n# depth next\n 2\n9\n0 1 2\n3\t4 5\n\n6 7  \n");
    const BinaryVolume a = dsreg::read_pgm3d(ascii, range_between(2, 5));
    EXPECT_EQ(a.grid.dims, (Index3{2, 2, 2}));
    EXPECT_EQ(a.mask, (std::vector<std::uint8_t>{0, 0, 1, 1, 1, 1, 0, 0}));

    // Binary with maxval ≥ 256: 2 bytes per value, most significant first. 0x0102 = 258
    // (read little-endian it would be 513).
    const std::string binary = path("handmade_binary.p3d");
    write_bytes(binary, std::string("P5-3D\n2 1 1\n600\n") + std::string("\x01\x02\x00\x05", 4));
    const BinaryVolume b = dsreg::read_pgm3d(binary, range_between(250, 300));
    EXPECT_EQ(b.grid.dims, (Index3{2, 1, 1}));
    EXPECT_EQ(b.mask, (std::vector<std::uint8_t>{1, 0}));
}

TEST_F(VolumeIoTest, ReadVolumeDispatchesOnExtension) {
    std::vector<int> base = base_pattern(kDims, 61);
    std::vector<std::uint8_t> bytes(base.begin(), base.end());
    std::vector<std::uint64_t> longs(base.begin(), base.end());
    std::vector<std::uint16_t> shorts(base.begin(), base.end());
    const ValueRange range = range_min(30);
    dsreg::write_vol(path("a.vol"), kDims, bytes, 3);
    dsreg::write_longvol(path("a.longvol"), kDims, longs, 3);
    dsreg::write_longvol(path("a.lvol"), kDims, longs, 2);
    dsreg::write_pgm3d(path("a.pgm3d"), kDims, shorts, true);
    dsreg::write_pgm3d(path("a.P3D"), kDims, shorts, false);
    write_bytes(path("a.raw"), encode_values(bytes, false));
    RawVolumeLayout layout;
    layout.dims = kDims;
    for (const std::string name : {"a.vol", "a.longvol", "a.lvol", "a.pgm3d", "a.P3D", "a.raw"}) {
        SCOPED_TRACE(name);
        expect_volume_matches(dsreg::read_volume(path(name), range, &layout), kDims, base, range);
    }
    expect_error([&] { dsreg::read_volume(path("a.raw"), range); }, path("a.raw"), "layout");
    write_bytes(path("a.nii"), "whatever");
    expect_error([&] { dsreg::read_volume(path("a.xyz")); }, path("a.xyz"), "unknown extension '.xyz'");
    expect_error([&] { dsreg::read_volume(path("noextension")); }, path("noextension"), "no extension");
}

TEST(VolumeIo, ParseRawVoxelType) {
    EXPECT_EQ(dsreg::parse_raw_voxel_type("uint8"), RawVoxelType::UInt8);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("u8"), RawVoxelType::UInt8);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("int16"), RawVoxelType::Int16);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("I16"), RawVoxelType::Int16);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("uint32"), RawVoxelType::UInt32);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("int64"), RawVoxelType::Int64);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("uint64"), RawVoxelType::UInt64);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("float"), RawVoxelType::Float32);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("f32"), RawVoxelType::Float32);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("double"), RawVoxelType::Float64);
    EXPECT_EQ(dsreg::parse_raw_voxel_type("Float64"), RawVoxelType::Float64);
    EXPECT_THROW(dsreg::parse_raw_voxel_type("uint12"), dsreg::Error);
    EXPECT_THROW(dsreg::parse_raw_voxel_type(""), dsreg::Error);
}

// ---------------------------------------------------------------------------------------------
// Broken .vol / .longvol files

TEST_F(VolumeIoTest, VolRejectsTruncatedAndOversizedRawPayloads) {
    const std::string header = vol_header("5", "4", "3", "2");
    const std::string truncated = path("truncated.vol");
    write_bytes(truncated, header + std::string(59, '\x01'));
    expect_error([&] { dsreg::read_vol(truncated); }, truncated, "truncated payload: header says 5x4x3 = 60 voxels");

    const std::string trailing = path("trailing.vol");
    write_bytes(trailing, header + std::string(61, '\x01'));
    expect_error([&] { dsreg::read_vol(trailing); }, trailing, "1 trailing bytes");

    // Lying dimensions within the voxel limit: rejected from the file size, before allocating 8 GB.
    const std::string lying = path("lying.vol");
    write_bytes(lying, vol_header("2000", "2000", "2000", "2") + std::string(1000, '\x01'));
    expect_error([&] { dsreg::read_vol(lying); }, lying, "truncated payload: header says 2000x2000x2000 = 8000000000 voxels");

    const std::string longvol = path("truncated.longvol");
    write_bytes(longvol, vol_header("5", "4", "3", "2") + std::string(60 * 8 - 1, '\x01'));
    expect_error([&] { dsreg::read_longvol(longvol); }, longvol, "60 voxels x 8 bytes = 480 bytes");
}

TEST_F(VolumeIoTest, VolRejectsBadZlibPayloads) {
    const std::string header = vol_header("5", "4", "3", "3");

    // Zip bomb: a tiny stream that inflates far beyond the 60 bytes announced.
    const std::string bomb = path("bomb.vol");
    write_bytes(bomb, header + zlib_compress(std::string(1 << 20, '\0')));
    expect_error([&] { dsreg::read_vol(bomb); }, bomb, "payload larger than header says");

    // Just one byte too many is caught too (the cap is exact).
    const std::string one_more = path("one_more.vol");
    write_bytes(one_more, header + zlib_compress(std::string(61, '\x02')));
    expect_error([&] { dsreg::read_vol(one_more); }, one_more, "payload larger than header says");

    const std::string short_stream = path("short_stream.vol");
    write_bytes(short_stream, header + zlib_compress(std::string(59, '\x02')));
    expect_error([&] { dsreg::read_vol(short_stream); }, short_stream, "inflates to only 59 bytes");

    // Lying dimensions: 10^9 voxels cannot come out of a few dozen compressed bytes; rejected before allocating.
    const std::string lying = path("lying.vol");
    write_bytes(lying, vol_header("1000", "1000", "1000", "3") + zlib_compress(std::string(60, '\x02')));
    expect_error([&] { dsreg::read_vol(lying); }, lying, "can inflate to at most");

    std::string random(5000, '\0');
    std::uint32_t state = 7;
    for (char& c : random) c = static_cast<char>((state = state * 1103515245u + 12345u) >> 24);
    const std::string compressed = zlib_compress(random);
    const std::string cut = path("cut.vol");
    write_bytes(cut, vol_header("50", "10", "10", "3") + compressed.substr(0, compressed.size() / 2));
    expect_error([&] { dsreg::read_vol(cut); }, cut, "cut off");

    std::string damaged_stream = zlib_compress(std::string(60, '\x02'));
    damaged_stream[damaged_stream.size() - 2] ^= 0x55;  // breaks the Adler-32 checksum
    const std::string damaged = path("damaged.vol");
    write_bytes(damaged, header + damaged_stream);
    expect_error([&] { dsreg::read_vol(damaged); }, damaged, "corrupt zlib payload");

    const std::string garbage = path("garbage.vol");
    write_bytes(garbage, header + std::string(100, '\x42'));
    expect_error([&] { dsreg::read_vol(garbage); }, garbage, "corrupt zlib payload");

    const std::string trailing = path("trailing.vol");
    write_bytes(trailing, header + zlib_compress(std::string(60, '\x02')) + "xyz");
    expect_error([&] { dsreg::read_vol(trailing); }, trailing, "3 trailing bytes after the end of the zlib stream");
}

TEST_F(VolumeIoTest, VolRejectsBadDimensions) {
    const std::string payload(60, '\x01');
    struct Case {
        std::string x;
        std::string expected;
    };
    for (const Case& c : {Case{"0", "X: '0' is not a positive integer"}, Case{"-5", "X: '-5' is not a positive integer"},
                          Case{"12abc", "X: '12abc' is not a positive integer"}, Case{"abc", "'abc' is not a positive integer"},
                          Case{"", "X: '' is not a positive integer"}, Case{"5.0", "'5.0' is not a positive integer"},
                          Case{"99999999999999999999", "is not a positive integer"},
                          Case{"100000", "exceed the limit of"}}) {
        SCOPED_TRACE("X: " + c.x);
        const std::string file = path("dims.vol");
        write_bytes(file, vol_header(c.x, "100000", "100000", "2") + payload);
        expect_error([&] { dsreg::read_vol(file); }, file, c.expected);
    }
    // Overflowing product (each factor fine on its own).
    const std::string overflow = path("overflow.vol");
    write_bytes(overflow, vol_header("4000000000", "4000000000", "4000000000", "2") + payload);
    expect_error([&] { dsreg::read_vol(overflow); }, overflow, "exceed the limit");

    // A caller-chosen limit.
    const std::string small = path("small.vol");
    write_bytes(small, vol_header("5", "4", "3", "2") + payload);
    dsreg::VolumeLimits limits;
    limits.max_voxels = 59;
    expect_error([&] { dsreg::read_vol(small, {}, limits); }, small, "exceed the limit of 59 voxels");
    limits.max_voxels = 60;
    EXPECT_EQ(dsreg::read_vol(small, {}, limits).grid.dims, kDims);
}

TEST_F(VolumeIoTest, VolRejectsMalformedHeaders) {
    const std::string payload(60, '\x01');
    const std::string file = path("header.vol");
    struct Case {
        std::string header;
        std::string expected;
    };
    const std::vector<Case> cases = {
        {"X: 5\nY: 4\nVersion: 2\n.\n", "missing required header key 'Z'"},
        {"X: 5\nY: 4\nZ: 3\n.\n", "missing required header key 'Version'"},
        {"X: 5\nY: 4\nZ: 3\nX: 5\nVersion: 2\n.\n", "duplicate header key 'X'"},
        {"X: 5\nY: 4\nZ: 3\nVersion: 4\n.\n", "unsupported Version '4'"},
        {"X: 5\nY: 4\nZ: 3\nVersion: two\n.\n", "unsupported Version 'two'"},
        {"X: 5\nY: 4\nZ: 3\nVoxel-Size: 2\nVersion: 2\n.\n", "unsupported Voxel-Size '2'"},
        {"X: 5\nY: 4\nthis line has no colon\nZ: 3\nVersion: 2\n.\n", "header line 3 is not 'Key: value'"},
        {"X: 5\nY: 4\nZ: 3\nVersion: 2\n", "missing '.' line"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.expected);
        write_bytes(file, c.header + (c.expected == "missing '.' line" ? "" : payload));
        expect_error([&] { dsreg::read_vol(file); }, file, c.expected);
    }
    // Payload bytes straight after the keys, no "." line: reported, not read as a header forever.
    write_bytes(file, "X: 5\nY: 4\nZ: 3\nVersion: 2\n" + std::string(100000, 'a'));
    expect_error([&] { dsreg::read_vol(file); }, file, "no '.' line");

    // Not a .vol at all.
    write_bytes(file, std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'));
    expect_error([&] { dsreg::read_vol(file); }, file, "is not 'Key: value'");
    write_bytes(file, "");
    expect_error([&] { dsreg::read_vol(file); }, file, "missing '.' line");

    // Same header rules for .longvol.
    const std::string longvol = path("header.longvol");
    write_bytes(longvol, "X: 5\nY: 4\nZ: 3\nVersion: 1\n.\n" + std::string(480, '\0'));
    expect_error([&] { dsreg::read_longvol(longvol); }, longvol, "unsupported Version '1'");
}

TEST_F(VolumeIoTest, MissingOrUnreadableFiles) {
    const std::string missing = path("does_not_exist.vol");
    expect_error([&] { dsreg::read_vol(missing); }, missing, "no such file");
    expect_error([&] { dsreg::read_longvol(missing); }, missing, "no such file");
    expect_error([&] { dsreg::read_pgm3d(missing); }, missing, "no such file");
    RawVolumeLayout layout;
    layout.dims = kDims;
    expect_error([&] { dsreg::read_raw(missing, layout); }, missing, "no such file");
    expect_error([&] { dsreg::read_volume(missing); }, missing, "no such file");

    const std::string directory = path("folder.vol");
    fs::create_directories(directory);
    expect_error([&] { dsreg::read_vol(directory); }, directory, "is a directory");

    if (::geteuid() != 0) {  // root reads anything
        const std::string locked = path("locked.vol");
        write_bytes(locked, vol_header("5", "4", "3", "2") + std::string(60, '\x01'));
        fs::permissions(locked, fs::perms::none);
        expect_error([&] { dsreg::read_vol(locked); }, locked, "cannot open for reading");
    }
}

// ---------------------------------------------------------------------------------------------
// Broken PGM3D files

TEST_F(VolumeIoTest, Pgm3dRejectsBrokenFiles) {
    const std::string file = path("broken.pgm3d");
    struct Case {
        std::string content;
        std::string expected;
    };
    const std::vector<Case> cases = {
        {"P5\n2 2 2\n255\n" + std::string(8, '\1'), "bad magic 'P5'"},
        {"P6-3D\n2 2 2\n255\n" + std::string(8, '\1'), "bad magic 'P6-3D'"},
        {"", "bad magic ''"},
        {"P2-3D\n2 0 2\n255\n1 1 1 1 1 1 1 1\n", "height '0' is not a positive integer"},
        {"P2-3D\n2 -2 2\n255\n1 1 1 1 1 1 1 1\n", "height '-2' is not a positive integer"},
        {"P2-3D\n2 2x 2\n255\n1 1 1 1 1 1 1 1\n", "height '2x' is not a positive integer"},
        {"P2-3D\n2 2\n", "the header ends before the depth"},
        {"P2-3D\n2 2 2\n0\n1 1 1 1 1 1 1 1\n", "maxval '0' is not an integer in 1..65535"},
        {"P2-3D\n2 2 2\n65536\n1 1 1 1 1 1 1 1\n", "maxval '65536' is not an integer in 1..65535"},
        {"P2-3D\n2 2 2\n9\n1 1 1 10 1 1 1 1\n", "value '10' of voxel #3 exceeds maxval 9"},
        {"P2-3D\n2 2 2\n9\n1 1 1 -1 1 1 1 1\n", "value of voxel #3 '-1' is not a non-negative integer"},
        {"P2-3D\n2 2 2\n9\n1 1 1 x 1 1 1 1\n", "value of voxel #3 'x' is not a non-negative integer"},
        {"P2-3D\n2 2 2\n9\n1 1 1 1 1 1 1\n", "the file holds only 7 values"},
        {"P2-3D\n2 2 2\n9\n1 1 1 1 1 1 1 1 1\n", "trailing data after the 8 values"},
        {"P2-3D\n100 100 100\n9\n1 1 1 1\n", "can hold at most"},
        {"P5-3D\n2 2 2\n255\n" + std::string(7, '\1'), "truncated payload: header says 2x2x2 = 8 voxels"},
        {"P5-3D\n2 2 2\n255\n" + std::string(9, '\1'), "1 trailing bytes"},
        {"P5-3D\n2 2 2\n1000\n" + std::string(15, '\1'), "8 voxels x 2 bytes = 16 bytes"},
        {"P5-3D\n2 2 2\n200\n" + std::string(7, '\1') + "\xC9", "value 201 of voxel #7 exceeds maxval 200"},
        {"P5-3D\n2 2 2\n1000\n" + std::string(14, '\0') + "\x03\xE9", "value 1001 of voxel #7 exceeds maxval 1000"},
        {"P5-3D\n100000 100000 100000\n255\n" + std::string(8, '\1'), "exceed the limit"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.expected);
        write_bytes(file, c.content);
        expect_error([&] { dsreg::read_pgm3d(file); }, file, c.expected);
    }
}

// ---------------------------------------------------------------------------------------------
// Broken raw files

TEST_F(VolumeIoTest, RawRejectsSizeMismatchesAndBadLayouts) {
    RawVolumeLayout layout;
    layout.dims = kDims;
    layout.type = RawVoxelType::UInt16;
    const std::string file = path("broken.raw");

    write_bytes(file, std::string(119, '\1'));
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "truncated payload: layout says 5x4x3 = 60 voxels x 2 bytes = 120 bytes");
    write_bytes(file, std::string(121, '\1'));
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "1 trailing bytes");

    layout.header_bytes = 10;
    write_bytes(file, std::string(129, '\1'));
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "truncated payload");
    write_bytes(file, std::string(5, '\1'));
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "too few to skip 10 bytes");
    write_bytes(file, std::string(130, '\1'));
    EXPECT_EQ(dsreg::read_raw(file, layout).grid.dims, kDims);

    layout.dims = {5, 0, 3};
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "dimensions 5x0x3 must all be positive");
    layout.dims = {5, -4, 3};
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "must all be positive");
    layout.dims = {1 << 20, 1 << 20, 1 << 20};
    expect_error([&] { dsreg::read_raw(file, layout); }, file, "exceed the limit");
}

// ---------------------------------------------------------------------------------------------
// Writers

TEST_F(VolumeIoTest, WritersRejectInconsistentInputAndLeaveNoFile) {
    const std::string file = path("out.vol");
    expect_error([&] { dsreg::write_vol(file, kDims, std::vector<std::uint8_t>(59)); }, file, "59 values given for dimensions 5x4x3");
    expect_error([&] { dsreg::write_vol(file, kDims, std::vector<std::uint8_t>(60), 4); }, file, "unsupported version 4");
    expect_error([&] { dsreg::write_vol(file, {5, 0, 3}, {}); }, file, "must all be positive");
    expect_error([&] { dsreg::write_longvol(file, kDims, std::vector<std::uint64_t>(61)); }, file, "61 values given");
    expect_error([&] { dsreg::write_pgm3d(file, kDims, std::vector<std::uint16_t>(1)); }, file, "1 values given");
    EXPECT_FALSE(fs::exists(file));
    EXPECT_TRUE(fs::is_empty(dir_)) << "a temporary file was left behind";
}

TEST_F(VolumeIoTest, Pgm3dWriterHandlesAllZeroVolume) {
    const std::string file = path("zeros.pgm3d");
    dsreg::write_pgm3d(file, kDims, std::vector<std::uint16_t>(60, 0), true);
    const BinaryVolume volume = dsreg::read_pgm3d(file, range_max(0));  // value > 0 and ≤ 0: nothing
    EXPECT_EQ(volume.object_voxel_count(), 0);
    EXPECT_EQ(dsreg::read_pgm3d(file, range_between(0, 0)).object_voxel_count(), 60);
}

// ---------------------------------------------------------------------------------------------
// Real DGtal files from ../shared/data

std::string shared_file(const std::string& name) { return std::string(DSREG_SHARED_DATA_DIR) + "/" + name; }

/// The payload of a real version-3 .vol decoded with zlib's one-shot uncompress().
std::string independent_vol_payload(const std::string& file, std::size_t voxels) {
    const std::string bytes = read_bytes(file);
    const std::size_t end = bytes.find("\n.\n");
    EXPECT_NE(end, std::string::npos);
    return zlib_uncompress(bytes.substr(end + 3), voxels);
}

TEST(VolumeIoSharedData, Bunny64) {
    const std::string file = shared_file("bunny-64.vol");
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found";
    const BinaryVolume volume = dsreg::read_vol(file);
    EXPECT_EQ(volume.grid.dims, (Index3{64, 64, 64}));
    EXPECT_GT(volume.object_voxel_count(), 0);
    EXPECT_LT(volume.object_voxel_count(), 64 * 64 * 64);
}

TEST(VolumeIoSharedData, Cat10ObjectIsTheVoxelsValued96) {
    const std::string file = shared_file("cat10.vol");
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found";
    const std::string payload = independent_vol_payload(file, 40 * 40 * 40);
    const auto count_96 = std::count(payload.begin(), payload.end(), static_cast<char>(96));
    ASSERT_GT(count_96, 0);
    const BinaryVolume by_default = dsreg::read_vol(file);
    EXPECT_EQ(by_default.grid.dims, (Index3{40, 40, 40}));
    EXPECT_EQ(by_default.object_voxel_count(), count_96);
    EXPECT_EQ(dsreg::read_vol(file, range_between(96, 96)).object_voxel_count(), count_96);
}

TEST(VolumeIoSharedData, LobsterThresholdMatchesIndependentDecode) {
    const std::string file = shared_file("lobster.vol");
    if (!fs::exists(file)) GTEST_SKIP() << file << " not found";
    const Index3 dims{301, 324, 56};
    const std::string payload = independent_vol_payload(file, static_cast<std::size_t>(voxel_count(dims)));
    const std::vector<std::uint8_t> values(payload.begin(), payload.end());
    const ValueRange range = range_between(40, 200);
    expect_volume_matches(dsreg::read_vol(file, range), dims, values, range);
}

}  // namespace
