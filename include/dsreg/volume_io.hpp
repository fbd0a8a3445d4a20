// dsreg — reading and writing voxel volumes.
//
// Readers decode the voxel values and keep those inside a ValueRange as the object, so a volume
// costs one byte per voxel in memory whatever its value type. Every reader checks the header
// against the real size of the file (or of the decompressed payload) before allocating, and
// throws dsreg::Error naming the file and the problem on any malformed input.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// Scalar type of the voxels of a headerless raw volume.
enum class RawVoxelType { UInt8, Int8, UInt16, Int16, UInt32, Int32, UInt64, Int64, Float32, Float64 };

/// What a raw volume file does not say about itself.
struct RawVolumeLayout {
    Index3 dims{0, 0, 0};
    RawVoxelType type = RawVoxelType::UInt8;
    bool big_endian = false;
    std::uint64_t header_bytes = 0;  ///< bytes to skip at the start of the file
};

/// Limits that protect the machine from absurd headers.
struct VolumeLimits {
    std::int64_t max_voxels = std::int64_t(1) << 34;  ///< 16 Gi voxels
};

/// Parse a RawVoxelType from its CLI name: uint8 int8 uint16 int16 uint32 int32 uint64 int64
/// float32 float64 (also u8, i16, f32, double, float ...). Throws dsreg::Error otherwise.
RawVoxelType parse_raw_voxel_type(const std::string& name);

/// DGtal .vol, versions 2 (raw bytes) and 3 (zlib payload). Spacing 1, origin 0.
BinaryVolume read_vol(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// DGtal .longvol (64-bit voxel values), versions 2 and 3.
BinaryVolume read_longvol(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// PGM 3D, ASCII ("P2-3D") or binary ("P5-3D"; 1 or 2 bytes per value, big-endian).
BinaryVolume read_pgm3d(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// Headerless raw volume with the given layout.
BinaryVolume read_raw(const std::string& path, const RawVolumeLayout& layout, const ValueRange& range = {},
                      const VolumeLimits& limits = {});

/// Chooses the reader from the file extension (.vol .longvol .pgm3d/.p3d .raw). A .raw file
/// needs `raw_layout`; it is ignored for the other formats.
BinaryVolume read_volume(const std::string& path, const ValueRange& range = {}, const RawVolumeLayout* raw_layout = nullptr,
                         const VolumeLimits& limits = {});

/// Writers (atomic: a temporary file renamed into place). `values` holds one value per voxel of
/// `dims`, x fastest. Used by tests, fuzz seeds and users converting volumes.
void write_vol(const std::string& path, const Index3& dims, const std::vector<std::uint8_t>& values, int version = 3);
void write_longvol(const std::string& path, const Index3& dims, const std::vector<std::uint64_t>& values, int version = 3);
void write_pgm3d(const std::string& path, const Index3& dims, const std::vector<std::uint16_t>& values, bool binary = true);

}  // namespace dsreg
