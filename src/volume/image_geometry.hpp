// dsreg — from what a medical image header announces to dsreg's 3-D scalar grid (not public API).
//
// The medical readers (NIfTI, NRRD, MetaImage, TIFF, HDF5, VTK, DICOM) describe an image as ITK
// does (ImageHeader, itk_bridge.hpp): any number of dimensions, a pixel of one or more components,
// spacing, origin and direction cosines per dimension. image_dims() and image_geometry() turn that
// into dsreg's grid, with one clear message for everything dsreg cannot take (4-D, vector pixels,
// sheared directions, ...), before any payload is read.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/grid_placement.hpp"
#include "dsreg/volume.hpp"
#include "dsreg/volume_io.hpp"
#include "itk_bridge.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {


/// The 3-D grid size of `header`: its dimensions beyond the third must all be 1, its pixels
/// scalar with one component of a supported type. Throws dsreg::Error naming `path` otherwise
/// ("4-D image of 10 volumes", "vector image with 3 components per voxel", ...). Fewer than
/// three dimensions give sizes of 1.
Index3 image_dims(const std::string& path, const ImageHeader& header);

/// Spacing, origin and direction of the first three dimensions of `header` (dims unset): a
/// negative spacing is made positive by negating its direction column; a direction matrix within
/// kOrthonormalTolerance of orthonormal (grid_placement.hpp) is replaced by the nearest orthonormal matrix (noted in
/// `info`), others are rejected; zero or non-finite values are rejected.
VoxelGrid image_geometry(const std::string& path, const ImageHeader& header, VolumeFileInfo& info);

/// Throws (naming `path`) unless the product of `sizes` (times `components`) is at most
/// limits.max_voxels: run on a header's own sizes before anything else reads the file.
void check_sizes_within_limits(const std::string& path, const std::vector<std::int64_t>& sizes, std::int64_t components,
                               const VolumeLimits& limits);

/// The total bytes of the files that hold an image (for the plausibility bound of decoders that
/// ITK runs: at most max_inflated_size(total) bytes of voxels). Missing files count 0.
std::uint64_t total_file_bytes(const std::vector<std::string>& files);

/// Throws dsreg::Error naming `path` unless `payload_bytes` could come out of `stored_bytes`
/// of file (allowing the deflate bound of 1032:1), i.e. the header does not lie grossly.
void require_plausible_image_payload(const std::string& path, std::uint64_t payload_bytes, std::uint64_t stored_bytes,
                                     const std::string& description);

/// The SampleFormat of an integer or float value of `bytes` bytes, in the host's byte order.
SampleFormat native_sample(int bytes, SampleKind kind);

/// "uint8", "int16", "float32", ... for a SampleFormat.
std::string sample_type_name(const SampleFormat& sample);

}  // namespace dsreg::volume_io_detail
