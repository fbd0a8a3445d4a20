// Medical and scientific image formats (dsreg/volume_io.hpp): NIfTI, NRRD, MetaImage, TIFF, HDF5,
// VTK, DICOM (written by ITK's own writers), NumPy .npy; geometry as ITK reads it, every value
// type, and the rejection of hostile or unsupported files with a message naming the file.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <fstream>
#include <functional>

#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"
#include "medical_test_support.hpp"
// check_dicom_in_child_process, tested on a file that makes GDCM abort (no ITK in the header).
#include "../src/volume/itk_bridge.hpp"

using namespace dsreg;
using dsreg::test::ScratchFolder;

namespace {

const RawVoxelType kAllTypes[] = {RawVoxelType::UInt8,  RawVoxelType::Int8,   RawVoxelType::UInt16, RawVoxelType::Int16,
                                  RawVoxelType::UInt32, RawVoxelType::Int32,  RawVoxelType::UInt64, RawVoxelType::Int64,
                                  RawVoxelType::Float32, RawVoxelType::Float64};

std::string type_name(RawVoxelType type) {
    const char* names[] = {"uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64", "float32", "float64"};
    return names[static_cast<int>(type)];
}

/// Values every type can hold exactly, with negative ones for signed types.
std::vector<double> test_values(const Index3& dims, RawVoxelType type) {
    const bool is_signed = type == RawVoxelType::Int8 || type == RawVoxelType::Int16 || type == RawVoxelType::Int32 ||
                           type == RawVoxelType::Int64 || type == RawVoxelType::Float32 || type == RawVoxelType::Float64;
    std::vector<double> values;
    for (std::int64_t n = 0; n < dims[0] * dims[1] * dims[2]; ++n) values.push_back(double((n * 37) % 101) - (is_signed ? 50 : 0));
    return values;
}

void expect_error(const std::function<void()>& action, const std::string& path, const std::string& fragment) {
    try {
        action();
        ADD_FAILURE() << "no error for " << path;
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
        EXPECT_NE(message.find(fragment), std::string::npos) << "'" << fragment << "' not in: " << message;
    }
}

void expect_same_grid(const VoxelGrid& read, const VoxelGrid& written, double tolerance) {
    EXPECT_EQ(read.dims, written.dims);
    EXPECT_LT((read.spacing - written.spacing).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LT((read.origin - written.origin).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LT((read.direction - written.direction).cwiseAbs().maxCoeff(), tolerance);
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes;
}

// ---------------------------------------------------------------------------------------------
// Round trips through ITK's writers: mask, values and geometry

struct FormatCase {
    const char* name;
    double geometry_tolerance;  ///< NIfTI stores geometry in float32
    bool keeps_direction;       ///< TIFF and VTK legacy images have no direction cosines
    bool keeps_origin;          ///< TIFF has no origin, and no slice spacing (read as 1)
};

const FormatCase kFormats[] = {
    {"a.nii", 1e-5, true, true},   {"a.nii.gz", 1e-5, true, true}, {"a.hdr", 1e-5, true, true},
    {"a.nrrd", 1e-12, true, true}, {"a.nhdr", 1e-12, true, true},  {"a.mha", 1e-12, true, true},
    {"a.mhd", 1e-12, true, true},  {"a.h5", 1e-12, true, true},    {"a.vtk", 1e-12, false, true},
    {"a.tif", 1e-6, false, false},
};

/// The geometry a format keeps of `grid`.
VoxelGrid grid_as_stored(const VoxelGrid& grid, const FormatCase& format) {
    VoxelGrid expected = grid;
    if (!format.keeps_direction) expected.direction.setIdentity();
    if (!format.keeps_origin) {
        expected.origin.setZero();
        expected.spacing.z() = 1;
    }
    return expected;
}

TEST(MedicalIo, EveryFormatRoundTripsTheMaskAndTheGeometry) {
    ScratchFolder scratch("medical-roundtrip");
    const VoxelGrid grid = test::oblique_grid({24, 20, 16});
    const std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 3);
    for (const FormatCase& format : kFormats) {
        SCOPED_TRACE(format.name);
        const std::string path = scratch.path(format.name);
        write_image(path, grid, labels, RawVoxelType::UInt8);
        VolumeFileInfo info;
        const BinaryVolume volume = read_volume(path, {}, nullptr, {}, &info);
        EXPECT_EQ(info.value_type, "uint8");
        ASSERT_EQ(volume.mask.size(), labels.size());
        std::int64_t inside = 0;
        for (std::size_t n = 0; n < labels.size(); ++n) {
            EXPECT_EQ(volume.mask[n], labels[n] > 0 ? 1 : 0) << "voxel " << n;
            inside += labels[n] > 0;
        }
        EXPECT_GT(inside, 100);
        expect_same_grid(volume.grid, grid_as_stored(grid, format), format.geometry_tolerance);
        // Whatever the format, the direction the pipeline gets is orthonormal.
        EXPECT_LT((volume.grid.direction.transpose() * volume.grid.direction - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    }
}

/// A label map of the ellipsoid cut in three by the planes x = centre and y = centre (index
/// space), values 0, 2, 5 and 300 (above a byte), as doubles in voxel order.
std::vector<double> three_labels(const VoxelGrid& grid) {
    std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1);
    for (std::int64_t k = 0; k < grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < grid.dims[0]; ++i) {
                double& label = labels[std::size_t(grid.linear_index(i, j, k))];
                if (label != 0) label = 2 * i < grid.dims[0] ? 2 : 2 * j < grid.dims[1] ? 5 : 300;
            }
    return labels;
}

void expect_label_map(const LabelVolume& read, const std::vector<double>& labels) {
    EXPECT_EQ(read.values, (std::vector<std::int64_t>{0, 2, 5, 300}));
    ASSERT_EQ(read.labels.size(), labels.size());
    for (std::size_t n = 0; n < labels.size(); ++n)
        ASSERT_EQ(read.values[read.labels[n]], std::int64_t(labels[n])) << "voxel " << n;
}

TEST(MedicalIo, EveryFormatReadsAsTheSameLabelMapWithItsGeometry) {
    ScratchFolder scratch("medical-labels");
    const VoxelGrid grid = test::oblique_grid({24, 20, 16});
    const std::vector<double> labels = three_labels(grid);
    for (const FormatCase& format : kFormats) {
        SCOPED_TRACE(format.name);
        const std::string path = scratch.path(format.name);
        write_image(path, grid, labels, RawVoxelType::UInt16);
        VolumeFileInfo info;
        const LabelVolume read = read_label_volume(path, nullptr, {}, &info);
        EXPECT_EQ(info.value_type, "uint16");
        EXPECT_EQ(info.world_geometry, format.keeps_origin);
        expect_label_map(read, labels);
        expect_same_grid(read.grid, grid_as_stored(grid, format), format.geometry_tolerance);
    }
    for (const bool fortran : {false, true}) {  // C order is read plane by plane
        SCOPED_TRACE(fortran ? "fortran.npy" : "c.npy");
        const std::string path = scratch.path(fortran ? "f.npy" : "c.npy");
        write_npy(path, grid.dims, labels, RawVoxelType::Int32, fortran);
        expect_label_map(read_label_volume(path), labels);
    }
    const std::string dicom = scratch.path("dicom");
    std::filesystem::create_directories(dicom);
    write_dicom_series(dicom, grid, labels, RawVoxelType::UInt16);
    const LabelVolume series = read_label_volume(dicom);
    expect_label_map(series, labels);
    expect_same_grid(series.grid, grid, 1e-6);
}

TEST(MedicalIo, EveryValueTypeInNiftiNrrdMetaImageAndNpy) {
    ScratchFolder scratch("medical-types");
    VoxelGrid grid;
    grid.dims = {5, 4, 3};
    ValueRange range;
    range.has_min = true;
    range.min = 7;
    range.has_max = true;
    range.max = 30;
    for (const RawVoxelType type : kAllTypes) {
        const std::vector<double> values = test_values(grid.dims, type);
        for (const char* extension : {"nii.gz", "nrrd", "mha", "npy"}) {
            const std::string path = scratch.path(type_name(type) + "." + extension);
            SCOPED_TRACE(path);
            if (std::string(extension) == "npy")
                write_npy(path, grid.dims, values, type);
            else
                write_image(path, grid, values, type);
            VolumeFileInfo info;
            const ScalarVolume read = read_volume_values(path, nullptr, {}, &info);
            EXPECT_EQ(info.value_type, type_name(type));
            ASSERT_EQ(read.values.size(), values.size());
            for (std::size_t n = 0; n < values.size(); ++n) EXPECT_EQ(read.values[n], float(values[n])) << "voxel " << n;
            const BinaryVolume mask = read_volume(path, range);
            for (std::size_t n = 0; n < values.size(); ++n) EXPECT_EQ(mask.mask[n], range.contains(values[n]) ? 1 : 0);
        }
    }
}

TEST(MedicalIo, NpyFortranAndCOrderGiveTheSameVoxels) {
    ScratchFolder scratch("medical-npy");
    const Index3 dims{6, 5, 4};
    const std::vector<double> values = test_values(dims, RawVoxelType::Int16);
    write_npy(scratch.path("c.npy"), dims, values, RawVoxelType::Int16, false);
    write_npy(scratch.path("f.npy"), dims, values, RawVoxelType::Int16, true);
    const ScalarVolume c = read_volume_values(scratch.path("c.npy"));
    const ScalarVolume f = read_volume_values(scratch.path("f.npy"));
    EXPECT_EQ(c.grid.dims, dims);
    EXPECT_EQ(f.grid.dims, dims);
    for (std::size_t n = 0; n < values.size(); ++n) {
        EXPECT_EQ(c.values[n], float(values[n]));
        EXPECT_EQ(f.values[n], float(values[n]));
    }
    // The C-order file really stores k fastest: a[0, 0, 1] is its second value.
    const std::string bytes = read_bytes(scratch.path("c.npy"));
    std::int16_t second = 0;
    std::memcpy(&second, bytes.data() + 128 + 2, 2);
    VoxelGrid g;
    g.dims = dims;
    EXPECT_EQ(second, std::int16_t(values[std::size_t(g.linear_index(0, 0, 1))]));
}

TEST(MedicalIo, DicomSeriesRoundTripsTheMaskAndTheGeometry) {
    ScratchFolder scratch("medical-dicom");
    const VoxelGrid grid = test::oblique_grid({20, 18, 12});
    const std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1);
    write_dicom_series(scratch.folder(), grid, labels, RawVoxelType::UInt16);
    VolumeFileInfo info;
    const BinaryVolume volume = read_volume(scratch.folder(), {}, nullptr, {}, &info);
    EXPECT_EQ(info.format, "DICOM series");
    expect_same_grid(volume.grid, grid, 1e-6);
    ASSERT_EQ(volume.mask.size(), labels.size());
    for (std::size_t n = 0; n < labels.size(); ++n) ASSERT_EQ(volume.mask[n], labels[n] > 0 ? 1 : 0) << "voxel " << n;
}

// ---------------------------------------------------------------------------------------------
// Unsupported images

TEST(MedicalIo, FourDimensionalAndVectorImagesAreRejectedClearly) {
    ScratchFolder scratch("medical-4d");
    // A 4-D NIfTI (3 time points) and a vector image, as nibabel would write them: own header bytes.
    const auto nifti = [&](const std::string& name, std::int16_t rank, std::int16_t t, std::int16_t components) {
        std::string header(352, '\0');
        const auto put16 = [&](std::size_t at, std::int16_t v) { std::memcpy(&header[at], &v, 2); };
        const auto put32f = [&](std::size_t at, float v) { std::memcpy(&header[at], &v, 4); };
        const std::int32_t size = 348;
        std::memcpy(&header[0], &size, 4);
        put16(40, rank);
        put16(42, 4), put16(44, 3), put16(46, 2), put16(48, t), put16(50, components);
        put16(70, 2), put16(72, 8);
        for (int d = 0; d < 8; ++d) put32f(76 + 4 * d, 1.0f);
        put32f(108, 352.0f);
        std::memcpy(&header[344], "n+1\0", 4);
        write_bytes(scratch.path(name), header + std::string(std::size_t(4 * 3 * 2 * t * components), '\1'));
    };
    nifti("time.nii", 4, 3, 1);
    expect_error([&] { read_volume(scratch.path("time.nii")); }, scratch.path("time.nii"), "4-D image");
    nifti("vector.nii", 5, 1, 3);
    expect_error([&] { read_volume(scratch.path("vector.nii")); }, scratch.path("vector.nii"), "vector image with 3 values per voxel");
    // A 4-D NIfTI with a single volume is a 3-D image.
    nifti("one.nii", 4, 1, 1);
    EXPECT_EQ(read_volume(scratch.path("one.nii")).grid.dims, (Index3{4, 3, 2}));

    // A vector NRRD (3 components per voxel, the way ITK writes a vector image).
    write_bytes(scratch.path("vector.nrrd"), "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 3 4 3 2\nkinds: vector domain domain domain\n"
                                             "encoding: raw\nspace: left-posterior-superior\n\n" +
                                                 std::string(3 * 4 * 3 * 2, '\1'));
    expect_error([&] { read_volume(scratch.path("vector.nrrd")); }, scratch.path("vector.nrrd"), "3 values per voxel");
    write_bytes(scratch.path("time.nrrd"), "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 4 3 2 5\nencoding: raw\n\n" +
                                               std::string(4 * 3 * 2 * 5, '\1'));
    expect_error([&] { read_volume(scratch.path("time.nrrd")); }, scratch.path("time.nrrd"), "4-D image");
}

// ---------------------------------------------------------------------------------------------
// Hostile files: a message naming the file, nothing allocated from a lying header

TEST(MedicalIo, TruncatedNiftiGzIsRejected) {
    ScratchFolder scratch("medical-truncated");
    const VoxelGrid grid = test::oblique_grid({24, 20, 16});
    const std::vector<double> values = test_values(grid.dims, RawVoxelType::Float32);
    const std::string path = scratch.path("cut.nii.gz");
    write_image(path, grid, values, RawVoxelType::Float32);
    const std::string bytes = read_bytes(path);
    write_bytes(path, bytes.substr(0, bytes.size() / 2));
    expect_error([&] { read_volume(path); }, path, "truncated payload");
    write_bytes(path, bytes.substr(0, 100));
    expect_error([&] { read_volume(path); }, path, "truncated");
    write_bytes(path, bytes.substr(0, 10));
    expect_error([&] { read_volume(path); }, path, "cut off");
}

TEST(MedicalIo, LyingNrrdHeaderIsRejectedBeforeAllocating) {
    ScratchFolder scratch("medical-lying");
    // Claims 2000³ int16 voxels (16 GB) with 10 bytes of raw data, then of gzip data.
    const std::string header = "NRRD0004\ntype: short\ndimension: 3\nsizes: 2000 2000 2000\nendian: little\n";
    write_bytes(scratch.path("raw.nrrd"), header + "encoding: raw\n\n0123456789");
    expect_error([&] { read_volume(scratch.path("raw.nrrd")); }, scratch.path("raw.nrrd"), "truncated payload");
    write_bytes(scratch.path("gz.nrrd"), header + "encoding: gzip\n\n0123456789");
    expect_error([&] { read_volume(scratch.path("gz.nrrd")); }, scratch.path("gz.nrrd"), "truncated or lying header");
    // Dimensions beyond the voxel limit.
    write_bytes(scratch.path("huge.nrrd"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n\nx");
    expect_error([&] { read_volume(scratch.path("huge.nrrd")); }, scratch.path("huge.nrrd"), "exceed the limit");
    // A detached header naming a missing data file.
    write_bytes(scratch.path("detached.nhdr"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: gone.raw\n");
    expect_error([&] { read_volume(scratch.path("detached.nhdr")); }, scratch.path("detached.nhdr"), "gone.raw (data file) does not exist");
    // --max-voxels is honoured before the payload is read.
    write_bytes(scratch.path("small.nrrd"), "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" + std::string(64, '\1'));
    VolumeLimits limits;
    limits.max_voxels = 63;
    expect_error([&] { read_volume(scratch.path("small.nrrd"), {}, nullptr, limits); }, scratch.path("small.nrrd"),
                 "exceed the limit of 63 voxels");
    EXPECT_EQ(read_volume(scratch.path("small.nrrd")).object_voxel_count(), 64);
}

TEST(MedicalIo, MetaImageWithoutItsDataFileIsRejected) {
    ScratchFolder scratch("medical-mhd");
    VoxelGrid grid;
    grid.dims = {6, 5, 4};
    const std::string path = scratch.path("a.mhd");
    write_image(path, grid, test_values(grid.dims, RawVoxelType::UInt8), RawVoxelType::UInt8, false);
    EXPECT_EQ(read_volume(path).grid.dims, grid.dims);
    for (const std::string& name : scratch.entries())
        if (name != "a.mhd") std::filesystem::remove(scratch.path(name));
    expect_error([&] { read_volume(path); }, path, "does not exist");
    // A LOCAL MetaImage whose payload is cut short, and one whose compressed payload lies.
    write_bytes(scratch.path("short.mha"),
                "ObjectType = Image\nNDims = 3\nDimSize = 10 10 10\nElementType = MET_USHORT\nElementDataFile = LOCAL\n" +
                    std::string(100, '\0'));
    expect_error([&] { read_volume(scratch.path("short.mha")); }, scratch.path("short.mha"), "truncated payload");
    write_bytes(scratch.path("bomb.mha"), "ObjectType = Image\nNDims = 3\nDimSize = 1000 1000 1000\nElementType = MET_UCHAR\n"
                                          "CompressedData = True\nElementDataFile = LOCAL\nxxxx");
    expect_error([&] { read_volume(scratch.path("bomb.mha")); }, scratch.path("bomb.mha"), "truncated or lying header");
    // ITK's MetaIO matches keys case by case: past "ElementdataFile" it read on as header through
    // the payload, whose long binary "key" overflowed a 255-byte field (found by fuzzing).
    write_bytes(scratch.path("case.mha"), "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n"
                                          "ElementdataFile = LOCAL\n" + std::string(400, 'a') + " = 1\n");
    expect_error([&] { read_volume(scratch.path("case.mha")); }, scratch.path("case.mha"),
                 "'ElementdataFile' must be spelled 'ElementDataFile'");
    // A type ITK does not know is refused by dsreg's header check (the first fuzz input that
    // garbled it, crash-garbled-element-type.mha, did so past such a key).
    write_bytes(scratch.path("type.mha"), "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCH\n"
                                          "ElementDataFile = LOCAL\n" + std::string(8, '\0'));
    expect_error([&] { read_volume(scratch.path("type.mha")); }, scratch.path("type.mha"), "unsupported ElementType 'MET_UCH'");
}

/// The byte offset of the value of `tag` in the `directory`-th IFD (0-based) of a little-endian
/// TIFF, whose entry holds one short or long value; npos when absent.
std::size_t tiff_tag_value_offset(const std::string& bytes, int directory, std::uint16_t tag) {
    const auto u16 = [&](std::size_t at) { return std::uint16_t(std::uint8_t(bytes[at]) | std::uint8_t(bytes[at + 1]) << 8); };
    const auto u32 = [&](std::size_t at) { return std::uint32_t(u16(at)) | std::uint32_t(u16(at + 2)) << 16; };
    if (bytes.compare(0, 4, std::string("II*\0", 4)) != 0) return std::string::npos;
    std::size_t ifd = u32(4);
    for (int d = 0; d < directory && ifd != 0; ++d) ifd = u32(ifd + 2 + 12 * std::size_t(u16(ifd)));
    if (ifd == 0) return std::string::npos;
    for (std::size_t e = 0; e < u16(ifd); ++e)
        if (u16(ifd + 2 + 12 * e) == tag) return ifd + 2 + 12 * e + 8;
    return std::string::npos;
}

TEST(MedicalIo, TiffStackWhosePagesDifferIsRefusedBeforeItkReadsIt) {
    // ITK's TIFF reader sizes the stack from the first page and the pages' subfile types, then
    // decodes every directory as it comes: a second directory that lost its "page" subfile type
    // made it write one slice past its buffer (heap overflow, found by mutating a stack).
    ScratchFolder scratch("medical-tiff-pages");
    const VoxelGrid grid = test::oblique_grid({8, 7, 4});
    const std::vector<double> labels = test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 3);
    const std::string good = scratch.path("good.tif");
    write_image(good, grid, labels, RawVoxelType::UInt8);
    ASSERT_NO_THROW(read_volume(good));
    const std::string bytes = read_bytes(good);
    const struct {
        const char* name;
        std::uint16_t tag;
        char value;
        const char* says;
    } cases[] = {{"subfile.tif", 254, char(0xf4), "subfile type 244"}, {"bits.tif", 258, 16, "1 x 16 bits per pixel"}};
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        const std::size_t at = tiff_tag_value_offset(bytes, 1, c.tag);
        ASSERT_NE(at, std::string::npos) << "ITK's writer no longer writes tag " << c.tag;
        std::string changed = bytes;
        changed[at] = c.value;
        const std::string path = scratch.path(c.name);
        write_bytes(path, changed);
        try {
            read_volume(path);
            ADD_FAILURE() << "accepted";
        } catch (const Error& error) {
            const std::string message = error.what();
            EXPECT_EQ(message.rfind(path + ": page 2 is ", 0), 0u) << message;
            EXPECT_NE(message.find(c.says), std::string::npos) << message;
        }
    }
}

/// Runs read_volume(path) and checks that it fails with a message that starts with the path and
/// contains `says`.
void expect_refused(const std::string& path, const std::string& says) {
    try {
        read_volume(path);
        ADD_FAILURE() << path << " accepted";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
        EXPECT_NE(message.find(says), std::string::npos) << message;
    }
}

/// The bytes of a small label image (8x7x4 voxels, uint8) written by ITK as `name` in `scratch`.
std::string small_image_bytes(const ScratchFolder& scratch, const std::string& name) {
    const VoxelGrid grid = test::oblique_grid({8, 7, 4});
    write_image(scratch.path(name), grid, test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 3), RawVoxelType::UInt8);
    return read_bytes(scratch.path(name));
}

TEST(MedicalIo, TiffTagsItkCopiesUnsafelyAreRefusedBeforeItkReadsThem) {
    // ITK's TIFF reader copies every tag into its metadata: 20 bytes of a DateTime, whatever its
    // length (heap overflow), and DotRange with one pointer where its libtiff writes two (a
    // crash). Both found by fuzzing; here the Software tag ITK writes becomes either.
    ScratchFolder scratch("medical-tiff-tags");
    const std::string bytes = small_image_bytes(scratch, "good.tif");
    const std::size_t software = tiff_tag_value_offset(bytes, 0, 305);
    ASSERT_NE(software, std::string::npos) << "ITK's writer no longer writes a Software tag";
    const std::size_t entry = software - 8;
    const auto put16 = [](std::string& b, std::size_t at, std::uint16_t v) { b[at] = char(v & 0xff), b[at + 1] = char(v >> 8); };
    std::string date_time = bytes;  // "InsightToolkit" as a DateTime: 14 characters
    put16(date_time, entry, 306);
    write_bytes(scratch.path("date-time.tif"), date_time);
    expect_refused(scratch.path("date-time.tif"), "page 1 has a DateTime tag of 14 characters");
    std::string dot_range = bytes;  // DotRange, two shorts: 7 and 9
    put16(dot_range, entry, 336), put16(dot_range, entry + 2, 3), put16(dot_range, entry + 4, 2), put16(dot_range, entry + 6, 0);
    put16(dot_range, entry + 8, 7), put16(dot_range, entry + 10, 9);
    write_bytes(scratch.path("dot-range.tif"), dot_range);
    expect_refused(scratch.path("dot-range.tif"), "page 1 has a DotRange tag");
    std::string long_text = bytes;  // the Software tag counting 1.8 billion characters
    put16(long_text, entry + 4, 0), put16(long_text, entry + 6, 0x6b6c);
    write_bytes(scratch.path("long-text.tif"), long_text);
    expect_refused(scratch.path("long-text.tif"), "directory 1: tag 305 claims 1802240000 values, more than the file holds");
    // The same long Software tag in a last directory the file ends right after: its entries are
    // whole, the offset of a next directory is cut off, and libtiff reads it (found by fuzzing).
    const auto u16 = [&](std::size_t at) { return std::size_t(std::uint8_t(bytes[at]) | std::uint8_t(bytes[at + 1]) << 8); };
    const auto u32 = [&](std::size_t at) { return u16(at) | u16(at + 2) << 16; };
    std::size_t last = u32(4), next_field = 4;
    while (u32(last + 2 + 12 * u16(last)) != 0) next_field = last + 2 + 12 * u16(last), last = u32(next_field);
    ASSERT_NE(next_field, 4u) << "ITK's writer no longer writes one directory per slice";
    std::string cut_short = bytes;
    const std::size_t copy = cut_short.size(), software_entry = tiff_tag_value_offset(bytes, 3, 305) - 8;
    cut_short += bytes.substr(last, 2 + 12 * u16(last));  // the last directory again, without its next offset
    put16(cut_short, copy + (software_entry - last) + 4, 0x000f), put16(cut_short, copy + (software_entry - last) + 6, 0x6c00);
    put16(cut_short, next_field, std::uint16_t(copy & 0xffff)), put16(cut_short, next_field + 2, std::uint16_t(copy >> 16));
    write_bytes(scratch.path("cut-short.tif"), cut_short);
    expect_refused(scratch.path("cut-short.tif"), "directory 4: tag 305 claims 1811939343 values, more than the file holds");
    std::string one_byte = bytes;  // an unknown tag 65000, one byte of text without a NUL
    put16(one_byte, entry, 65000), put16(one_byte, entry + 4, 1), put16(one_byte, entry + 8, 1);
    write_bytes(scratch.path("one-byte.tif"), one_byte);
    expect_refused(scratch.path("one-byte.tif"), "page 1 has an unknown text tag 65000 of one byte");
}

TEST(MedicalIo, TiffDirectoryLoopIsRefusedBeforeItkReadsIt) {
    // ITK's libtiff counts the directories without noticing a loop: a directory naming itself as
    // the next one hung the reader (found by fuzzing). Here page 2 names itself.
    ScratchFolder scratch("medical-tiff-loop");
    std::string bytes = small_image_bytes(scratch, "good.tif");
    ASSERT_NE(tiff_tag_value_offset(bytes, 1, 256), std::string::npos) << "not a little-endian stack of pages";
    std::uint32_t first_ifd = 0, second_ifd = 0;
    std::uint16_t entries = 0;
    std::memcpy(&first_ifd, &bytes[4], 4);
    std::memcpy(&entries, &bytes[first_ifd], 2);
    std::memcpy(&second_ifd, &bytes[first_ifd + 2 + 12 * std::size_t(entries)], 4);
    std::memcpy(&entries, &bytes[second_ifd], 2);
    std::memcpy(&bytes[second_ifd + 2 + 12 * std::size_t(entries)], &second_ifd, 4);
    write_bytes(scratch.path("loop.tif"), bytes);
    expect_refused(scratch.path("loop.tif"), "directory 3 cannot be read (a loop in the chain of directories");
}

TEST(MedicalIo, VtkImageHeaderLinesAreCheckedBeforeItkReadsThem) {
    // ITK's reader scans each header line as a C string: a NUL byte in the SPACING line left the
    // other spacings uninitialized (two reads gave two grids; found by fuzzing).
    ScratchFolder scratch("medical-vtk-header");
    const std::string bytes = small_image_bytes(scratch, "good.vtk");
    const std::size_t spacing = bytes.find("\nSPACING ");
    ASSERT_NE(spacing, std::string::npos) << "ITK's writer no longer writes a SPACING line";
    const std::size_t second = bytes.find(' ', spacing + 9);
    std::string nul = bytes;
    nul[second] = '\0';
    write_bytes(scratch.path("nul.vtk"), nul);
    expect_refused(scratch.path("nul.vtk"), "holds control characters");
    std::string two = bytes;
    two.erase(second, bytes.find('\n', spacing + 1) - second);  // "SPACING x"
    two.insert(second, " 1");
    write_bytes(scratch.path("two.vtk"), two);
    expect_refused(scratch.path("two.vtk"), "('SPACING', read as spacing) gives 2 values, not 3");
    std::string run_into = bytes;  // "SPACINGx0.75 ...": ITK skips the first word, number included
    run_into[spacing + 8] = 'x';
    write_bytes(scratch.path("run-into.vtk"), run_into);
    expect_refused(scratch.path("run-into.vtk"), "read as spacing) gives 2 values, not 3");
    // ITK's reader took a binary payload cut short without a word (the last voxels unset).
    write_bytes(scratch.path("short.vtk"), bytes.substr(0, bytes.size() - 5));
    expect_refused(scratch.path("short.vtk"), "truncated payload: the header says 224 voxels of 1 bytes = 224 bytes");
    // ITK finds SCALARS anywhere in the line, so a garbled keyword still gives it the type.
    std::string garbled = bytes.substr(0, bytes.size() - 5);
    const std::size_t scalars = garbled.find("SCALARS scalars");
    ASSERT_NE(scalars, std::string::npos);
    garbled[scalars + 3] = '*';
    write_bytes(scratch.path("garbled.vtk"), garbled);
    expect_refused(scratch.path("garbled.vtk"), "truncated payload: the header says 224 voxels");
    // ITK steps back when the line after SCALARS is not LOOKUP_TABLE: that line is payload.
    std::string no_table = bytes.substr(0, bytes.size() - 30);
    no_table[no_table.find("LOOKUP_TABLE")] = 'X';
    write_bytes(scratch.path("no-table.vtk"), no_table);
    expect_refused(scratch.path("no-table.vtk"), "truncated payload: the header says 224 voxels");
    // COLOR_SCALARS (unsigned bytes, no lookup table): ITK's whole read took a short payload too.
    std::string color = bytes;
    const std::size_t table = color.find("LOOKUP_TABLE default\n");
    ASSERT_NE(table, std::string::npos);
    color.replace(scalars, table + 21 - scalars, "COLOR_SCALARS c 1\n");
    write_bytes(scratch.path("color.vtk"), color);
    EXPECT_EQ(read_volume(scratch.path("color.vtk")).mask, read_volume(scratch.path("good.vtk")).mask);
    write_bytes(scratch.path("short-color.vtk"), color.substr(0, color.size() - 5));
    expect_refused(scratch.path("short-color.vtk"), "truncated payload: the header says 224 voxels of 1 bytes = 224 bytes");
    // After COLOR_SCALARS, ITK's whole read takes a LOOKUP_TABLE line for voxels, its slab read skips it.
    color.insert(color.find("COLOR_SCALARS c 1\n") + 18, "LOOKUP_TABLE default\n");
    write_bytes(scratch.path("color-table.vtk"), color);
    expect_refused(scratch.path("color-table.vtk"), "a LOOKUP_TABLE line after COLOR_SCALARS");
    // ITK skips empty lines: with one before the file type line, its BINARY is ITK's line 3 still.
    write_bytes(scratch.path("blank-short.vtk"), "\n" + bytes.substr(0, bytes.size() - 5));
    expect_refused(scratch.path("blank-short.vtk"), "truncated payload: the header says 224 voxels");
    write_bytes(scratch.path("blank.vtk"), "\n" + bytes);
    EXPECT_EQ(read_volume(scratch.path("blank.vtk")).mask, read_volume(scratch.path("good.vtk")).mask);
}

TEST(MedicalIo, DamagedHdf5IsAnErrorNotACrash) {
    // HDF5's C++ exceptions (not std::exception) crossed ITK's reader and ended the process in
    // std::terminate: here the signature of the chunk index ("TREE") is damaged.
    ScratchFolder scratch("medical-hdf5-damaged");
    const VoxelGrid grid = test::oblique_grid({24, 20, 16});
    const std::string path = scratch.path("a.h5");
    write_image(path, grid, test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 3), RawVoxelType::UInt8);
    std::string bytes = read_bytes(path);
    const std::size_t tree = bytes.rfind("TREE");
    ASSERT_NE(tree, std::string::npos) << "ITK's HDF5 writer no longer writes a v1 B-tree";
    bytes[tree] = 'X';
    write_bytes(path, bytes);
    expect_refused(path, "cannot read the HDF5 voxels");
}

TEST(MedicalIo, Hdf5ChunkIndexClaimingMoreThanTheFileIsRefusedBeforeItkReadsIt) {
    // HDF5 allocates a chunk as its index says it is stored: 1.6 GB for a 13 KB file (found by
    // fuzzing). Here the first chunk's size in the chunk index (a v1 B-tree of type 1) lies.
    ScratchFolder scratch("medical-hdf5-chunks");
    std::string bytes = small_image_bytes(scratch, "a.h5");
    std::size_t tree = bytes.find("TREE");
    while (tree != std::string::npos && bytes[tree + 4] != 1) tree = bytes.find("TREE", tree + 4);
    ASSERT_NE(tree, std::string::npos) << "ITK's HDF5 writer no longer indexes its chunks with a v1 B-tree";
    const std::uint32_t huge = 0x60000000;
    std::memcpy(&bytes[tree + 24], &huge, 4);  // after the node's signature, type, level, count, siblings
    write_bytes(scratch.path("a.h5"), bytes);
    expect_refused(scratch.path("a.h5"), "the voxel data set claims");
}

TEST(MedicalIo, DicomMetaInformationThatEndsEarlyIsRefusedBeforeGdcmReadsIt) {
    // Debian's GDCM asserts (aborts the process) where the file meta information group 0002 runs
    // past the end of the file, names no value representation, or is all the file holds.
    ScratchFolder scratch("medical-dicom-meta");
    const VoxelGrid grid = test::oblique_grid({10, 9, 3});
    write_dicom_series(scratch.folder(), grid, test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1),
                       RawVoxelType::UInt16);
    std::vector<std::string> slices = scratch.entries();
    std::sort(slices.begin(), slices.end());
    ASSERT_GE(slices.size(), 3u);
    const std::string bytes = read_bytes(scratch.path(slices[1]));
    ASSERT_EQ(bytes.compare(128, 4, "DICM"), 0);
    // (0002,0000) UL 4 <group length>: the meta information ends at 132 + 12 + that length.
    ASSERT_EQ(bytes.compare(132, 6, std::string("\x02\x00\x00\x00UL", 6)), 0);
    std::uint32_t group_length = 0;
    std::memcpy(&group_length, bytes.data() + 140, 4);
    const std::size_t meta_end = 144 + group_length;
    ASSERT_LT(meta_end, bytes.size());
    ScratchFolder damaged("medical-dicom-meta-damaged");
    write_bytes(damaged.path("cut-in-meta.dcm"), bytes.substr(0, meta_end - 3));
    expect_refused(damaged.path("cut-in-meta.dcm"), "the file ends inside its DICOM meta information");
    write_bytes(damaged.path("meta-only.dcm"), bytes.substr(0, meta_end));
    expect_refused(damaged.path("meta-only.dcm"), "holds DICOM meta information and no data set");
    std::string no_vr = bytes;
    no_vr[136] = no_vr[137] = '\x01';
    write_bytes(damaged.path("no-vr.dcm"), no_vr);
    expect_refused(damaged.path("no-vr.dcm"), "(0002,0000) has no explicit value representation");
    std::string sequence = bytes;  // GDCM asserts on a sequence in group 0002
    sequence[136] = 'S', sequence[137] = 'Q';
    write_bytes(damaged.path("sequence.dcm"), sequence);
    expect_refused(damaged.path("sequence.dcm"), "DICOM meta information element (0002,0000) is a sequence");
    // GDCM allocates what a data element's length says: the first element of the data set
    // (implicit VR little endian, as ITK writes it: tag, then a 4-byte length) says 1.8 GB.
    std::string long_element = bytes;
    const std::uint32_t huge = 0x70000000;
    std::memcpy(&long_element[meta_end + 4], &huge, 4);
    write_bytes(damaged.path("long-element.dcm"), long_element);
    expect_refused(damaged.path("long-element.dcm"), "announces 1879048192 bytes, but the file holds");
    // GDCM asserts on Samples per Pixel other than 1, 3 or 4 (implicit VR: tag, length 2, value).
    std::string samples = bytes;
    const std::size_t spp = samples.find(std::string("\x28\x00\x02\x00\x02\x00\x00\x00", 8), meta_end);
    ASSERT_NE(spp, std::string::npos);
    samples[spp + 8] = 2;
    write_bytes(damaged.path("samples.dcm"), samples);
    expect_refused(damaged.path("samples.dcm"), "Samples per Pixel (0028,0002) is 2 (DICOM allows 1, 3 or 4)");
    // GDCM asserts on a pixel format without a scalar type: signed single bits, 24-bit pixels.
    std::string signed_bits = bytes;
    const std::size_t allocated = signed_bits.find(std::string("\x28\x00\x00\x01\x02\x00\x00\x00", 8), meta_end);
    ASSERT_NE(allocated, std::string::npos);
    signed_bits[allocated + 8] = 24;
    write_bytes(damaged.path("bits.dcm"), signed_bits);
    expect_refused(damaged.path("bits.dcm"), "Bits Allocated (0028,0100) is 24 (1, 8, 12, 16, 32 or 64 here)");
    signed_bits[allocated + 8] = 8;  // below the 16 Bits Stored: GDCM throws what ITK does not catch
    write_bytes(damaged.path("stored.dcm"), signed_bits);
    expect_refused(damaged.path("stored.dcm"), "Bits Stored (0028,0101) is 16, more than Bits Allocated (0028,0100) 8");
    // Pixel Data short of what Rows x Columns x Bits Allocated say: GDCM and ITK read the rest from
    // memory never written. Here the file loses its last 2 bytes and its Pixel Data's length 2.
    std::string short_pixels = bytes.substr(0, bytes.size() - 2);
    const std::size_t pixel_data = short_pixels.rfind(std::string("\xe0\x7f\x10\x00", 4));
    ASSERT_NE(pixel_data, std::string::npos);
    std::uint32_t pixel_bytes = 0;
    std::memcpy(&pixel_bytes, &short_pixels[pixel_data + 4], 4);
    pixel_bytes -= 2;
    std::memcpy(&short_pixels[pixel_data + 4], &pixel_bytes, 4);
    write_bytes(damaged.path("short-pixels.dcm"), short_pixels);
    expect_refused(damaged.path("short-pixels.dcm"), "Pixel Data (7FE0,0010) holds 178 bytes, but 9 rows x 10 columns x 1 frames");
    // Encapsulated Pixel Data (undefined length) must hold items: GDCM asserted on another element there.
    const std::size_t native = bytes.rfind(std::string("\xe0\x7f\x10\x00", 4));
    ASSERT_NE(native, std::string::npos);
    std::string encapsulated = bytes.substr(0, native + 4) + std::string(4, '\xff');  // undefined length
    encapsulated += std::string("\x28\x00\x10\x00\x00\x00\x00\x00", 8);  // (0028,0010), where an item must be
    write_bytes(damaged.path("encapsulated.dcm"), encapsulated);
    expect_refused(damaged.path("encapsulated.dcm"), "encapsulated Pixel Data (7FE0,0010) holds (0028,0010) where an item");
    // Without meta information after the preamble GDCM guesses the encoding (and misread one).
    std::string group_3 = bytes;
    group_3[132] = 3;
    write_bytes(damaged.path("group-3.dcm"), group_3);
    expect_refused(damaged.path("group-3.dcm"), "the DICM preamble is not followed by DICOM meta information");
    // GDCM asserted on a file cut inside the header (tag, length) of an element of its data set.
    write_bytes(damaged.path("cut-element.dcm"), bytes + std::string("\x10\x00\x10", 3));
    expect_refused(damaged.path("cut-element.dcm"), "the file ends inside a data element's header (3 bytes after the last element)");
    // In a series folder, GDCM reads every file: one cut file is named.
    write_bytes(scratch.path(slices[1]), bytes.substr(0, meta_end - 3));
    expect_refused(scratch.path(slices[1]), "the file ends inside its DICOM meta information");
    try {
        read_volume(scratch.folder());
        ADD_FAILURE() << "series accepted";
    } catch (const Error& error) {
        EXPECT_EQ(std::string(error.what()).rfind(scratch.path(slices[1]) + ": the file ends inside", 0), 0u) << error.what();
    }
}

TEST(MedicalIo, DicomFileThatMakesGdcmAbortIsRefusedNotFatal) {
    // Signed single-bit pixels make Debian's GDCM (assertions on) abort in its pixel format.
    // check_dicom_meta refuses them first; here the child process alone must contain the abort.
    ScratchFolder scratch("medical-dicom-child");
    const VoxelGrid grid = test::oblique_grid({10, 9, 2});
    write_dicom_series(scratch.folder(), grid, test::sample_ellipsoid(grid, test::test_ellipsoid(grid), 1), RawVoxelType::UInt16);
    std::vector<std::string> slices = scratch.entries();
    std::sort(slices.begin(), slices.end());
    const std::string valid = scratch.path(slices[0]);
    EXPECT_NO_THROW(volume_io_detail::check_dicom_in_child_process({valid}));
    std::string bytes = read_bytes(valid);
    for (const std::string element : {std::string("\x28\x00\x00\x01\x02\x00\x00\x00", 8), std::string("\x28\x00\x03\x01\x02\x00\x00\x00", 8)}) {
        const std::size_t at = bytes.find(element);
        ASSERT_NE(at, std::string::npos);
        bytes[at + 8] = 1, bytes[at + 9] = 0;  // Bits Allocated 1, Pixel Representation 1
    }
    ScratchFolder damaged("medical-dicom-child-damaged");
    write_bytes(damaged.path("abort.dcm"), bytes);
    // One child reads a series' files in turn: the message names the one it died on.
    try {
        volume_io_detail::check_dicom_in_child_process({valid, damaged.path("abort.dcm"), scratch.path(slices[1])});
        ADD_FAILURE() << "GDCM did not abort on signed single bits";
    } catch (const Error& error) {
        EXPECT_EQ(std::string(error.what()).rfind(damaged.path("abort.dcm") + ": GDCM, the DICOM library, aborted reading this file (signal 6", 0), 0u)
            << error.what();
    }
    expect_refused(damaged.path("abort.dcm"), "Bits Allocated (0028,0100) is 1 with signed values");
}

TEST(MedicalIo, MalformedHeadersGetMessagesNamingTheFile) {
    ScratchFolder scratch("medical-malformed");
    const std::vector<std::pair<std::string, std::string>> files = {
        {"empty.nii", ""},
        {"garbage.nii", std::string(400, 'x')},
        {"garbage.nii.gz", "not gzip at all"},
        {"garbage.nrrd", "NRRD9\nstuff\n"},
        {"nosizes.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nencoding: raw\n\n"},
        {"bzip.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n\n"},
        {"garbage.mha", "hello\n"},
        {"garbage.npy", "\x93NUMPY\x01\x00\x10\x00{'descr': '<x9'}"},
        {"garbage.tif", "II*\0garbage"},
        {"garbage.h5", "not hdf5"},
        {"garbage.vtk", "# vtk DataFile Version 3.0\nnothing\n"},
    };
    for (const auto& [name, bytes] : files) {
        SCOPED_TRACE(name);
        write_bytes(scratch.path(name), bytes);
        try {
            read_volume(scratch.path(name));
            ADD_FAILURE() << "accepted";
        } catch (const Error& error) {
            const std::string message = error.what();
            EXPECT_EQ(message.rfind(scratch.path(name) + ": ", 0), 0u) << message;
            EXPECT_EQ(message.find("ITK ERROR"), std::string::npos) << message;
            EXPECT_EQ(message.find(".cxx:"), std::string::npos) << message;
        }
    }
    const std::string empty_folder = scratch.path("no-dicom");
    std::filesystem::create_directories(empty_folder);
    expect_error([&] { read_volume(empty_folder); }, empty_folder, "no DICOM image series");
}

// ---------------------------------------------------------------------------------------------
// NIfTI geometry: dsreg's own rules (NIfTI-2, sforms ITK refuses) against ITK's (NIfTI-1)

/// A NIfTI-1 or NIfTI-2 file of 4×3×2 uint8 voxels with the given transforms.
struct NiftiFields {
    int qform_code = 0, sform_code = 0;
    float pixdim[4] = {1, 0.75f, 1.0f, 1.25f};  ///< qfac, dx, dy, dz
    float quatern[3] = {0, 0, 0};
    float qoffset[3] = {0, 0, 0};
    float srow[3][4] = {{0.75f, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1.25f, 0}};
};

std::string nifti_file(const NiftiFields& f, int version) {
    const std::size_t header_size = version == 1 ? 348 : 540, offset = version == 1 ? 352 : 544;
    std::string h(offset, '\0');
    const auto put = [&](std::size_t at, auto value) { std::memcpy(&h[at], &value, sizeof value); };
    put(0, std::int32_t(header_size));
    if (version == 1) {
        put(40, std::int16_t(3)), put(42, std::int16_t(4)), put(44, std::int16_t(3)), put(46, std::int16_t(2));
        for (int d = 4; d < 8; ++d) put(40 + 2 * d, std::int16_t(1));
        put(70, std::int16_t(2)), put(72, std::int16_t(8));
        for (int d = 0; d < 4; ++d) put(76 + 4 * d, f.pixdim[d]);
        put(108, float(offset));
        put(112, 1.0f);
        put(252, std::int16_t(f.qform_code)), put(254, std::int16_t(f.sform_code));
        for (int i = 0; i < 3; ++i) put(256 + 4 * i, f.quatern[i]), put(268 + 4 * i, f.qoffset[i]);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) put(280 + 16 * r + 4 * c, f.srow[r][c]);
        std::memcpy(&h[344], "n+1\0", 4);
    } else {
        std::memcpy(&h[4], "n+2\0\r\n\032\n", 8);
        put(12, std::int16_t(2)), put(14, std::int16_t(8));
        put(16, std::int64_t(3)), put(24, std::int64_t(4)), put(32, std::int64_t(3)), put(40, std::int64_t(2));
        for (int d = 4; d < 8; ++d) put(16 + 8 * d, std::int64_t(1));
        for (int d = 0; d < 4; ++d) put(104 + 8 * d, double(f.pixdim[d]));
        put(168, std::int64_t(offset));
        put(176, 1.0);
        put(344, std::int32_t(f.qform_code)), put(348, std::int32_t(f.sform_code));
        for (int i = 0; i < 3; ++i) put(352 + 8 * i, double(f.quatern[i])), put(376 + 8 * i, double(f.qoffset[i]));
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) put(400 + 32 * r + 8 * c, double(f.srow[r][c]));
    }
    std::string voxels(24, '\0');
    for (int n = 0; n < 24; ++n) voxels[std::size_t(n)] = char(n % 3);
    return h + voxels;
}

TEST(MedicalIo, Nifti2GeometryFollowsItksRulesForNifti1) {
    ScratchFolder scratch("medical-nifti2");
    std::vector<std::pair<std::string, NiftiFields>> cases;
    NiftiFields none;
    cases.emplace_back("no transform", none);
    NiftiFields qform;  // rotation about an oblique axis, left-handed (qfac = -1)
    qform.qform_code = 1;
    qform.pixdim[0] = -1;
    qform.quatern[0] = 0.2f, qform.quatern[1] = -0.3f, qform.quatern[2] = 0.1f;
    qform.qoffset[0] = -12.5f, qform.qoffset[1] = 30.25f, qform.qoffset[2] = 4;
    cases.emplace_back("qform", qform);
    NiftiFields sform;
    sform.sform_code = 2;
    const Eigen::Matrix3d r = test::rotation(25, Eigen::Vector3d(1, 2, 3));
    for (int row = 0; row < 3; ++row) {
        for (int c = 0; c < 3; ++c) sform.srow[row][c] = float(r(row, c) * sform.pixdim[c + 1]);
        sform.srow[row][3] = float(row * 7.5 - 3);
    }
    cases.emplace_back("sform", sform);
    NiftiFields both_differ = qform;  // ITK takes the qform when an aligned sform disagrees
    both_differ.sform_code = 2;
    std::memcpy(both_differ.srow, sform.srow, sizeof sform.srow);
    cases.emplace_back("both, sform code 2", both_differ);
    NiftiFields scanner = both_differ;  // and the sform when it is SCANNER_ANAT
    scanner.sform_code = 1;
    cases.emplace_back("both, sform code 1", scanner);
    for (const auto& [name, fields] : cases) {
        SCOPED_TRACE(name);
        write_bytes(scratch.path("one.nii"), nifti_file(fields, 1));
        write_bytes(scratch.path("two.nii"), nifti_file(fields, 2));
        VolumeFileInfo info1, info2;
        const BinaryVolume one = read_volume(scratch.path("one.nii"), {}, nullptr, {}, &info1);  // ITK's geometry
        const BinaryVolume two = read_volume(scratch.path("two.nii"), {}, nullptr, {}, &info2);  // dsreg's
        EXPECT_EQ(info1.format, "NIfTI-1");
        EXPECT_EQ(info2.format, "NIfTI-2");
        expect_same_grid(two.grid, one.grid, 1e-6);
        EXPECT_EQ(one.mask, two.mask);
    }
}

TEST(MedicalIo, SlightlyShearedSformIsOrthonormalizedAndAStrongShearRejected) {
    ScratchFolder scratch("medical-shear");
    NiftiFields slight;
    slight.sform_code = 2;
    slight.srow[0][1] = 0.0005f;  // ITK 5.2 refuses this file; dsreg orthonormalizes it and says so
    write_bytes(scratch.path("slight.nii"), nifti_file(slight, 1));
    VolumeFileInfo info;
    const BinaryVolume volume = read_volume(scratch.path("slight.nii"), {}, nullptr, {}, &info);
    ASSERT_FALSE(info.notes.empty());
    EXPECT_NE(info.notes.front().find("not orthonormal"), std::string::npos);
    EXPECT_LT((volume.grid.direction.transpose() * volume.grid.direction - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    NiftiFields strong = slight;
    strong.srow[0][1] = 0.2f;  // 11 degrees of shear
    write_bytes(scratch.path("strong.nii"), nifti_file(strong, 1));
    expect_error([&] { read_volume(scratch.path("strong.nii")); }, scratch.path("strong.nii"), "not orthonormal");
}

TEST(MedicalIo, NiftiScaleSlopeIsApplied) {
    ScratchFolder scratch("medical-slope");
    NiftiFields fields;
    std::string bytes = nifti_file(fields, 1);
    const float slope = 2.5f, intercept = -1.0f;
    std::memcpy(&bytes[112], &slope, 4);
    std::memcpy(&bytes[116], &intercept, 4);
    write_bytes(scratch.path("scaled.nii"), bytes);
    const ScalarVolume values = read_volume_values(scratch.path("scaled.nii"));
    for (int n = 0; n < 24; ++n) EXPECT_EQ(values.values[std::size_t(n)], float((n % 3) * 2.5 - 1.0));
}

}  // namespace
