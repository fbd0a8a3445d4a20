// dsreg — images whose voxels ITK decodes (TIFF, HDF5, VTK, DICOM), and ITK's writers: the
// checks and conversions around the adapter of itk_bridge.hpp (this file does not include ITK).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <cstring>
#include <random>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"
#include "image_geometry.hpp"
#include "itk_bridge.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace volume_io_detail {

namespace {

/// Slabs of slices read at a time where ITK can stream: about this many bytes of values.
constexpr std::uint64_t kSlabBytes = std::uint64_t(16) << 20;

/// Slices per slab: at least one.
std::int64_t slab_slices(const Index3& dims, std::uint64_t bytes_per_value) {
    const std::uint64_t slice_bytes = static_cast<std::uint64_t>(dims[0] * dims[1]) * bytes_per_value;
    return std::max<std::int64_t>(1, std::min<std::int64_t>(dims[2], static_cast<std::int64_t>(kSlabBytes / slice_bytes)));
}

std::vector<std::uint8_t> allocate_buffer(const std::string& path, std::uint64_t bytes) {
    try {
        return std::vector<std::uint8_t>(static_cast<std::size_t>(bytes));
    } catch (const std::bad_alloc&) {
        fail(path, "not enough memory for a read buffer of " + std::to_string(bytes) + " bytes");
    }
}

/// Checks of every image ITK decodes: 3-D scalar, within the limits, not larger than its files
/// can hold. Allocates the destination with the image's geometry; returns whether the voxels
/// are wanted (not for a header-only destination).
bool prepare_destination(const std::string& path, const ImageHeader& header, const std::vector<std::string>& files,
                         const VolumeLimits& limits, VoxelDestination& destination) {
    const Index3 dims = image_dims(path, header);
    const std::int64_t voxels = checked_voxel_count(path, dims, limits);
    const std::uint64_t bytes = payload_bytes(path, voxels, header.sample.bytes);
    require_plausible_image_payload(path, bytes, total_file_bytes(files),
                                    "header says " + describe_payload(dims, voxels, header.sample.bytes));
    VolumeFileInfo info;
    info.format = header.format;
    info.value_type = header.value_type;
    info.world_geometry = header.format != itk_format_name(ItkFormat::Tiff);  // TIFF has no origin nor direction
    const VoxelGrid geometry = image_geometry(path, header, info);
    const bool wanted = destination.allocate(path, dims);
    destination.set_geometry(geometry);
    destination.info() = info;
    return wanted;
}

/// The slices [first, end) of the stream a read needs: those of the box, or all.
std::pair<std::int64_t, std::int64_t> needed_slices(const VoxelDestination& destination) {
    const StreamRegion* region = destination.region();
    if (region == nullptr) return {0, destination.dims()[2]};
    return {region->box.lo[2], region->box.hi[2]};
}

}  // namespace

void read_itk_voxels(const std::string& path, ItkFormat format, const VolumeLimits& limits, VoxelDestination& destination) {
    { const InputFile check(path); }  // a clear message for a missing file, a folder, a device
    if (format == ItkFormat::Tiff) {
        check_tiff_entries(path);
        check_tiff_pages(path);
    }
    if (format == ItkFormat::DicomFile) {
        check_dicom_meta(path);
        check_dicom_in_child_process({path});
    }
    if (format == ItkFormat::VtkImage) check_vtk_image_header(path);
    if (format == ItkFormat::Hdf5) {  // a box read decodes the chunks of its slices only: so are they checked
        const StreamRegion* region = destination.region();
        check_hdf5_voxel_data(path, region ? std::optional<std::array<std::int64_t, 2>>({region->box.lo[2], region->box.hi[2]})
                                           : std::nullopt);
    }
    ItkImageReader reader(path, format);
    const ImageHeader& header = reader.header();
    if (!prepare_destination(path, header, {path}, limits, destination)) return;
    const Index3& dims = destination.dims();
    // Formats ITK cannot stream (TIFF, DICOM files) are read in one region: a buffer of the whole
    // image in its own value type, for the time of the read. A box of them is refused: a
    // block-wise run would hold the whole image once per block.
    if (destination.region() != nullptr && !reader.can_stream())
        fail(path, "block-wise runs (--block-size, dsreg-mpi) read a box of the images ITK reads by slices, and ITK reads "
                   "this " + header.format + " file whole; convert it to .nii, .h5 or .raw (or run without --block-size)");
    const auto value_bytes = static_cast<std::uint64_t>(header.sample.bytes);
    const std::int64_t slab = reader.can_stream() ? slab_slices(dims, value_bytes) : dims[2];
    std::vector<std::uint8_t> buffer = allocate_buffer(path, static_cast<std::uint64_t>(dims[0] * dims[1] * slab) * value_bytes);
    SampleWriter sink = destination.writer(path, header.sample);
    const auto [first_slice, end_slice] = needed_slices(destination);
    sink.skip_to(static_cast<std::uint64_t>(dims[0] * dims[1] * first_slice));
    for (std::int64_t first = first_slice; first < end_slice; first += slab) {
        const std::int64_t count = std::min(slab, end_slice - first);
        reader.read_slices(first, count, buffer.data());
        sink.consume(buffer.data(), static_cast<std::size_t>(static_cast<std::uint64_t>(dims[0] * dims[1] * count) * value_bytes));
    }
}

void read_dicom_series_voxels(const std::string& folder, const VolumeLimits& limits, VoxelDestination& destination) {
    // GDCM reads every file of the folder to sort out the series.
    std::error_code error;
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error))
        if (entry.is_regular_file(error)) {
            files.push_back(entry.path().string());
            check_dicom_meta(files.back());
        }
    check_dicom_in_child_process(files);
    DicomSeriesReader reader(folder);
    const ImageHeader& header = reader.header();
    if (!prepare_destination(folder, header, reader.files(), limits, destination)) return;
    const Index3& dims = destination.dims();
    destination.info().notes.push_back(std::to_string(reader.files().size()) + " DICOM files");
    const std::int64_t slab = slab_slices(dims, sizeof(double));
    std::vector<double> buffer(static_cast<std::size_t>(dims[0] * dims[1] * slab));
    SampleWriter sink = destination.writer(folder, native_sample(8, SampleKind::Float));
    for (std::int64_t first = 0; first < dims[2]; first += slab) {
        const std::int64_t count = std::min(slab, dims[2] - first);
        reader.read_slices(first, count, buffer.data());
        if (reader.spacing_deviation() > 1e-3 * header.spacing[2])
            fail(folder, "the slices are not evenly spaced (a missing slice?): the distance between two neighbouring slices "
                         "differs by " + std::to_string(reader.spacing_deviation()) + " from the mean spacing " +
                             std::to_string(header.spacing[2]));
        sink.consume(reinterpret_cast<const std::uint8_t*>(buffer.data()),
                     static_cast<std::size_t>(dims[0] * dims[1] * count) * sizeof(double));
    }
}

}  // namespace volume_io_detail

// ----------------------------------------------------------------------------------------------
// Writers

namespace {

using namespace volume_io_detail;

bool name_ends_with(const std::string& path, const std::string& suffix) {
    std::string name = std::filesystem::path(path).filename().string();
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The ITK format written for a file name, or throws.
ItkFormat writer_format(const std::string& path) {
    const auto is = [&](std::initializer_list<const char*> suffixes) {
        return std::any_of(suffixes.begin(), suffixes.end(), [&](const char* suffix) { return name_ends_with(path, suffix); });
    };
    if (is({".nii", ".nii.gz", ".hdr"})) return ItkFormat::Nifti;
    if (is({".nrrd", ".nhdr"})) return ItkFormat::Nrrd;
    if (is({".mha", ".mhd"})) return ItkFormat::MetaImage;
    if (is({".tif", ".tiff"})) return ItkFormat::Tiff;
    if (is({".h5", ".hdf5"})) return ItkFormat::Hdf5;
    if (is({".vtk"})) return ItkFormat::VtkImage;
    fail(path, "cannot write an image in this format (use .nii, .nii.gz, .hdr, .nrrd, .nhdr, .mha, .mhd, .tif, .h5 or .vtk)");
}

SampleFormat sample_of(RawVoxelType type) {
    switch (type) {
    case RawVoxelType::UInt8: return native_sample(1, SampleKind::Unsigned);
    case RawVoxelType::Int8: return native_sample(1, SampleKind::Signed);
    case RawVoxelType::UInt16: return native_sample(2, SampleKind::Unsigned);
    case RawVoxelType::Int16: return native_sample(2, SampleKind::Signed);
    case RawVoxelType::UInt32: return native_sample(4, SampleKind::Unsigned);
    case RawVoxelType::Int32: return native_sample(4, SampleKind::Signed);
    case RawVoxelType::UInt64: return native_sample(8, SampleKind::Unsigned);
    case RawVoxelType::Int64: return native_sample(8, SampleKind::Signed);
    case RawVoxelType::Float32: return native_sample(4, SampleKind::Float);
    case RawVoxelType::Float64: return native_sample(8, SampleKind::Float);
    }
    return {};
}

template <typename T>
void convert_into(const double* values, std::size_t count, std::vector<std::uint8_t>& bytes) {
    bytes.resize(count * sizeof(T));
    for (std::size_t i = 0; i < count; ++i) {
        const T value = static_cast<T>(values[i]);
        std::memcpy(bytes.data() + i * sizeof(T), &value, sizeof(T));
    }
}

/// `count` values converted to `type`, in host byte order, as ITK's writers take them.
std::vector<std::uint8_t> typed_values(const double* values, std::size_t count, RawVoxelType type) {
    std::vector<std::uint8_t> bytes;
    switch (type) {
    case RawVoxelType::UInt8: convert_into<std::uint8_t>(values, count, bytes); break;
    case RawVoxelType::Int8: convert_into<std::int8_t>(values, count, bytes); break;
    case RawVoxelType::UInt16: convert_into<std::uint16_t>(values, count, bytes); break;
    case RawVoxelType::Int16: convert_into<std::int16_t>(values, count, bytes); break;
    case RawVoxelType::UInt32: convert_into<std::uint32_t>(values, count, bytes); break;
    case RawVoxelType::Int32: convert_into<std::int32_t>(values, count, bytes); break;
    case RawVoxelType::UInt64: convert_into<std::uint64_t>(values, count, bytes); break;
    case RawVoxelType::Int64: convert_into<std::int64_t>(values, count, bytes); break;
    case RawVoxelType::Float32: convert_into<float>(values, count, bytes); break;
    case RawVoxelType::Float64: convert_into<double>(values, count, bytes); break;
    }
    return bytes;
}

void check_writer_grid(const std::string& path, const VoxelGrid& grid, std::size_t value_count) {
    check_writer_input(path, grid.dims, value_count);
    if (!grid.spacing.allFinite() || (grid.spacing.array() <= 0).any()) fail(path, "cannot write: the spacing must be positive");
    if (!grid.origin.allFinite()) fail(path, "cannot write: the origin must be finite");
    if (!grid.direction.allFinite() || orthonormality_error(grid.direction) > 1e-6)
        fail(path, "cannot write: the direction cosines must be orthonormal");
}

/// A 3-D scalar image header for ITK's writers: `dims` voxels at `origin`, `grid`'s spacing and direction.
ImageHeader image_of(const VoxelGrid& grid, const Index3& dims, const Eigen::Vector3d& origin, RawVoxelType type) {
    ImageHeader image;
    for (int d = 0; d < 3; ++d) {
        image.sizes.push_back(dims[d]);
        image.spacing.push_back(grid.spacing[d]);
        image.origin.push_back(origin[d]);
        image.direction.push_back({grid.direction(0, d), grid.direction(1, d), grid.direction(2, d)});
    }
    image.sample = sample_of(type);
    return image;
}

/// "2.25." followed by a random 128-bit number in decimal: a DICOM UID (ISO/IEC 9834-8 form).
std::string new_dicom_uid() {
    std::random_device device;
    std::uint32_t words[4];
    for (std::uint32_t& word : words) word = device();
    std::string digits;
    while (words[0] || words[1] || words[2] || words[3]) {  // repeated division by 10
        std::uint64_t remainder = 0;
        for (std::uint32_t& word : words) {
            const std::uint64_t current = (remainder << 32) | word;
            word = static_cast<std::uint32_t>(current / 10);
            remainder = current % 10;
        }
        digits.push_back(static_cast<char>('0' + remainder));
    }
    if (digits.empty()) digits = "0";
    std::reverse(digits.begin(), digits.end());
    return "2.25." + digits;
}

/// Numbers as a DICOM multi-valued decimal string: each with as many digits as its 16
/// characters allow (17 significant digits, or fewer when they do not fit).
std::string dicom_numbers(std::initializer_list<double> numbers) {
    std::string text;
    for (const double x : numbers) {
        char buffer[40];
        for (int digits = 17; digits > 0; --digits)
            if (std::snprintf(buffer, sizeof buffer, "%.*g", digits, x) <= 16) break;
        if (!text.empty()) text += '\\';
        text += buffer;
    }
    return text;
}

}  // namespace

void write_image(const std::string& path, const VoxelGrid& grid, const std::vector<double>& values, RawVoxelType type,
                 bool compress) {
    check_writer_grid(path, grid, values.size());
    const ItkFormat format = writer_format(path);
    const std::vector<std::uint8_t> buffer = typed_values(values.data(), values.size(), type);
    const ImageHeader image = image_of(grid, grid.dims, grid.origin, type);
    // Formats whose header names a second file cannot be renamed into place.
    if (name_ends_with(path, ".hdr") || name_ends_with(path, ".mhd") || name_ends_with(path, ".nhdr"))
        return write_itk_image(path, format, image, buffer.data(), compress);
    const std::filesystem::path target(path);
    const std::filesystem::path temporary =
        target.parent_path() / (".dsreg-tmp-" + std::to_string(std::random_device{}()) + "-" + target.filename().string());
    try {
        write_itk_image(temporary.string(), format, image, buffer.data(), compress);
        std::filesystem::rename(temporary, target);
    } catch (const std::filesystem::filesystem_error& error) {
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        fail(path, std::string("cannot write: ") + error.code().message());
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        throw;
    }
}

void write_dicom_series(const std::string& folder, const VoxelGrid& grid, const std::vector<double>& values, RawVoxelType type) {
    check_writer_grid(folder, grid, values.size());
    if (type != RawVoxelType::UInt8 && type != RawVoxelType::Int8 && type != RawVoxelType::UInt16 && type != RawVoxelType::Int16)
        fail(folder, "cannot write a DICOM series of this value type (uint8, int8, uint16 and int16 only)");
    if (!std::filesystem::is_directory(folder)) fail(folder, "cannot write a DICOM series: not an existing folder");
    const std::string study = new_dicom_uid(), series = new_dicom_uid(), frame_of_reference = new_dicom_uid();
    const auto slice_voxels = static_cast<std::size_t>(grid.dims[0] * grid.dims[1]);
    const Eigen::Vector3d row = grid.direction.col(0), column = grid.direction.col(1);
    for (std::int64_t k = 0; k < grid.dims[2]; ++k) {
        const std::vector<std::uint8_t> buffer = typed_values(values.data() + k * slice_voxels, slice_voxels, type);
        const Eigen::Vector3d position = grid.origin + grid.direction.col(2) * (grid.spacing.z() * double(k));
        const std::vector<std::pair<std::string, std::string>> tags = {
            // CT Image Storage: GDCM keeps Image Position/Orientation and Pixel Spacing only for
            // the image storage classes that define them (not for the default Secondary Capture).
            {"0008|0016", "1.2.840.10008.5.1.4.1.1.2"},
            {"0008|0060", "CT"},
            {"0028|0004", "MONOCHROME2"},
            {"0010|0010", "dsreg^test"},
            {"0020|000d", study},
            {"0020|000e", series},
            {"0020|0052", frame_of_reference},
            {"0008|0018", new_dicom_uid()},
            {"0020|0013", std::to_string(k + 1)},
            {"0020|0032", dicom_numbers({position.x(), position.y(), position.z()})},
            {"0020|0037", dicom_numbers({row.x(), row.y(), row.z(), column.x(), column.y(), column.z()})},
            {"0018|0050", dicom_numbers({grid.spacing.z()})},
        };
        char name[32];
        std::snprintf(name, sizeof name, "slice%04lld.dcm", static_cast<long long>(k));
        write_itk_dicom_slice((std::filesystem::path(folder) / name).string(),
                              image_of(grid, {grid.dims[0], grid.dims[1], 1}, position, type), buffer.data(), tags);
    }
}

}  // namespace dsreg
