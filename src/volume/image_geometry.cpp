// dsreg — from a medical image header (any dimension, ITK's geometry) to a 3-D scalar grid.
#include "image_geometry.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "dsreg/error.hpp"

namespace dsreg::volume_io_detail {

namespace {

std::string format_number(double value) {
    std::ostringstream text;
    text.precision(6);
    text << value;
    return text.str();
}

bool host_little_endian() {
    const std::uint16_t probe = 1;
    return *reinterpret_cast<const std::uint8_t*>(&probe) == 1;
}

}  // namespace

SampleFormat native_sample(int bytes, SampleKind kind) { return SampleFormat{bytes, kind, !host_little_endian()}; }

std::string sample_type_name(const SampleFormat& sample) {
    const std::string bits = std::to_string(8 * sample.bytes);
    switch (sample.kind) {
    case SampleKind::Unsigned: return "uint" + bits;
    case SampleKind::Signed: return "int" + bits;
    case SampleKind::Float: return "float" + bits;
    }
    return "";
}

Index3 image_dims(const std::string& path, const ImageHeader& header) {
    if (header.pixel_type == "unknown" || header.value_type == "unknown")
        fail(path, "the header gives no voxel type that ITK recognizes (its type field is missing or garbled)");
    if (header.pixel_type != "scalar" || header.components != 1) {
        const std::string kind = header.pixel_type == "scalar" ? "multi-component" : header.pixel_type;
        fail(path, kind + " image with " + std::to_string(header.components) +
                       " values per voxel: dsreg needs a scalar image (one value per voxel, e.g. a label map)");
    }
    if (!header.value_type_supported)
        fail(path, "voxel values of type " + header.value_type +
                       " are not supported (integers of 8 to 64 bits, float32 and float64 are)");
    if (header.sizes.empty()) fail(path, "the header announces an image with no dimension");
    Index3 dims{1, 1, 1};
    for (std::size_t d = 0; d < header.sizes.size(); ++d) {
        const std::int64_t size = header.sizes[d];
        if (size <= 0) fail(path, "dimension " + std::to_string(d + 1) + " has size " + std::to_string(size));
        if (d < 3) {
            dims[d] = size;
        } else if (size > 1) {
            fail(path, std::to_string(header.sizes.size()) + "-D image (" + std::to_string(size) + " along dimension " +
                           std::to_string(d + 1) +
                           "): dsreg needs a single 3-D volume; extract one first (e.g. one time point)");
        }
    }
    return dims;
}

void check_sizes_within_limits(const std::string& path, const std::vector<std::int64_t>& sizes, std::int64_t components,
                               const VolumeLimits& limits) {
    std::int64_t product = components;
    std::string shown;
    for (const std::int64_t size : sizes) shown += (shown.empty() ? "" : "x") + std::to_string(size);
    for (const std::int64_t size : sizes) {
        if (size <= 0) fail(path, "sizes " + shown + " must all be positive");
        if (size > limits.max_voxels / product)  // divide first: no overflow
            fail(path, "sizes " + shown + " exceed the limit of " + std::to_string(limits.max_voxels) + " voxels");
        product *= size;
    }
}

VoxelGrid image_geometry(const std::string& path, const ImageHeader& header, VolumeFileInfo& info) {
    VoxelGrid grid;
    const std::size_t n = std::min<std::size_t>(3, header.sizes.size());
    for (std::size_t c = 0; c < n; ++c) {
        const double spacing = c < header.spacing.size() ? header.spacing[c] : 1.0;
        const double origin = c < header.origin.size() ? header.origin[c] : 0.0;
        if (!std::isfinite(spacing) || spacing == 0)
            fail(path, "voxel size " + format_number(spacing) + " along axis " + std::to_string(c + 1) +
                           " is not a non-zero finite number");
        if (!std::isfinite(origin)) fail(path, "the origin is not finite");
        grid.spacing[c] = std::abs(spacing);
        grid.origin[c] = origin;
        // Direction cosines of axis c within the first three world coordinates.
        Eigen::Vector3d column = Eigen::Vector3d::Unit(static_cast<Eigen::Index>(c));
        if (c < header.direction.size())
            for (std::size_t r = 0; r < 3; ++r) column[r] = r < header.direction[c].size() ? header.direction[c][r] : 0.0;
        if (!column.allFinite() || column.norm() == 0)
            fail(path, "the direction of axis " + std::to_string(c + 1) + " is zero or not finite");
        grid.direction.col(static_cast<Eigen::Index>(c)) = (spacing < 0 ? -1.0 : 1.0) * column;
    }
    // A 2-D image: its third axis is the right-handed normal of the first two.
    if (n < 3) grid.direction.col(2) = grid.direction.col(0).cross(grid.direction.col(1)).normalized();
    if (n < 2) grid.direction.col(1) = grid.direction.col(2).cross(grid.direction.col(0)).normalized();

    const std::string problem = direction_problem(grid.direction);
    if (!problem.empty()) fail(path, problem);
    const double error = orthonormality_error(grid.direction);
    if (error > 1e-12) {
        grid.direction = nearest_orthonormal(grid.direction);
        if (error > 1e-6)
            info.notes.push_back("direction cosines orthonormalized (they were off by up to " + format_number(error) + ")");
    }
    return grid;
}

std::uint64_t total_file_bytes(const std::vector<std::string>& files) {
    std::uint64_t total = 0;
    for (const std::string& file : files) {
        std::error_code error;
        const auto size = std::filesystem::file_size(file, error);
        if (!error) total += size;
    }
    return total;
}

void require_plausible_image_payload(const std::string& path, std::uint64_t payload_bytes, std::uint64_t stored_bytes,
                                     const std::string& description) {
    const std::uint64_t max_bytes = max_inflated_size(stored_bytes);
    if (payload_bytes > max_bytes)
        fail(path, "truncated or lying header: " + description + ", but its " + std::to_string(stored_bytes) +
                       " bytes of file can hold at most " + std::to_string(max_bytes) + " bytes of voxels even compressed");
}

}  // namespace dsreg::volume_io_detail
