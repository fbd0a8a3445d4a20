// dsreg — headerless raw volumes: `header_bytes` to skip, then exactly X·Y·Z values of the
// layout's type and byte order, x fastest, and nothing after them.
#include <algorithm>
#include <cctype>
#include <utility>

#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace {

using namespace volume_io_detail;

SampleFormat sample_format(const RawVolumeLayout& layout) {
    SampleFormat format;
    format.big_endian = layout.big_endian;
    switch (layout.type) {
    case RawVoxelType::UInt8: format.bytes = 1; format.kind = SampleKind::Unsigned; break;
    case RawVoxelType::Int8: format.bytes = 1; format.kind = SampleKind::Signed; break;
    case RawVoxelType::UInt16: format.bytes = 2; format.kind = SampleKind::Unsigned; break;
    case RawVoxelType::Int16: format.bytes = 2; format.kind = SampleKind::Signed; break;
    case RawVoxelType::UInt32: format.bytes = 4; format.kind = SampleKind::Unsigned; break;
    case RawVoxelType::Int32: format.bytes = 4; format.kind = SampleKind::Signed; break;
    case RawVoxelType::UInt64: format.bytes = 8; format.kind = SampleKind::Unsigned; break;
    case RawVoxelType::Int64: format.bytes = 8; format.kind = SampleKind::Signed; break;
    case RawVoxelType::Float32: format.bytes = 4; format.kind = SampleKind::Float; break;
    case RawVoxelType::Float64: format.bytes = 8; format.kind = SampleKind::Float; break;
    }
    return format;
}

}  // namespace

RawVoxelType parse_raw_voxel_type(const std::string& name) {
    static const std::pair<const char*, RawVoxelType> names[] = {
        {"uint8", RawVoxelType::UInt8},     {"u8", RawVoxelType::UInt8},       {"uchar", RawVoxelType::UInt8},
        {"byte", RawVoxelType::UInt8},      {"int8", RawVoxelType::Int8},      {"i8", RawVoxelType::Int8},
        {"schar", RawVoxelType::Int8},      {"uint16", RawVoxelType::UInt16},  {"u16", RawVoxelType::UInt16},
        {"ushort", RawVoxelType::UInt16},   {"int16", RawVoxelType::Int16},    {"i16", RawVoxelType::Int16},
        {"short", RawVoxelType::Int16},     {"uint32", RawVoxelType::UInt32},  {"u32", RawVoxelType::UInt32},
        {"uint", RawVoxelType::UInt32},     {"int32", RawVoxelType::Int32},    {"i32", RawVoxelType::Int32},
        {"int", RawVoxelType::Int32},       {"uint64", RawVoxelType::UInt64},  {"u64", RawVoxelType::UInt64},
        {"int64", RawVoxelType::Int64},     {"i64", RawVoxelType::Int64},      {"float32", RawVoxelType::Float32},
        {"f32", RawVoxelType::Float32},     {"float", RawVoxelType::Float32},  {"float64", RawVoxelType::Float64},
        {"f64", RawVoxelType::Float64},     {"double", RawVoxelType::Float64},
    };
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    for (const auto& [known, type] : names)
        if (lower == known) return type;
    throw Error("unknown raw voxel type " + quote_excerpt(name) +
                " (expected uint8, int8, uint16, int16, uint32, int32, uint64, int64, float32 or float64)");
}

namespace volume_io_detail {

void read_raw_voxels(const std::string& path, const RawVolumeLayout& layout, const VolumeLimits& limits,
                     VoxelDestination& destination) {
    InputFile file(path);
    const SampleFormat sample = sample_format(layout);
    const std::int64_t voxels = checked_voxel_count(path, layout.dims, limits);
    const std::uint64_t expected = payload_bytes(path, voxels, sample.bytes);
    file.skip(layout.header_bytes);
    std::string description = "layout says " + describe_payload(layout.dims, voxels, sample.bytes);
    if (layout.header_bytes > 0) description += " after " + std::to_string(layout.header_bytes) + " header bytes";
    require_exact_payload(file, expected, description);

    if (!destination.allocate(path, layout.dims)) return;
    SampleWriter sink = destination.writer(path, sample);
    decode_stored_payload(file, sink);
}

}  // namespace volume_io_detail

BinaryVolume read_raw(const std::string& path, const RawVolumeLayout& layout, const ValueRange& range, const VolumeLimits& limits) {
    auto destination = VoxelDestination::mask(range);
    read_raw_voxels(path, layout, limits, destination);
    return destination.take_mask();
}

}  // namespace dsreg
