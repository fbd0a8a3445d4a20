// dsreg — payloads of NRRD and MetaImage files (see image_payload.hpp).
#include "image_payload.hpp"

#include "image_geometry.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// ITK must read the same number of values of the same type as dsreg's parse says.
void check_itk_agrees(const std::string& path, const PayloadLayout& layout, const ImageHeader& itk) {
    std::int64_t header_values = layout.components, itk_values = itk.components;
    for (const std::int64_t size : layout.sizes) header_values *= size;
    for (const std::int64_t size : itk.sizes) itk_values *= size;
    if (header_values != itk_values)
        fail(path, "ITK reads " + std::to_string(itk_values) + " values, the header's " + layout.sizes_field + " give " +
                       std::to_string(header_values));
    if (itk.value_type_supported && (itk.sample.bytes != layout.sample.bytes || itk.sample.kind != layout.sample.kind))
        fail(path, "ITK reads the values as " + itk.value_type + ", the header says " + layout.value_type);
}

/// Positions `data` at the payload and checks that the file can hold it.
void locate_payload(InputFile& data, const PayloadLayout& layout, std::uint64_t bytes, const std::string& description) {
    if (layout.skip == -1) {
        if (data.remaining() < bytes) data.fail("truncated payload: " + description + ", file holds " + std::to_string(data.size()) + " bytes");
        data.skip(data.remaining() - bytes);
    } else {
        data.skip(static_cast<std::uint64_t>(layout.skip));
    }
    if (!layout.compressed) {
        if (data.remaining() < bytes)
            data.fail("truncated payload: " + description + ", file holds " + std::to_string(data.remaining()) + " bytes of data");
        return;
    }
    if (layout.compressed_size > 0 && static_cast<std::uint64_t>(layout.compressed_size) > data.remaining())
        data.fail("truncated payload: the compressed data size is " + std::to_string(layout.compressed_size) +
                  " bytes, the file holds " + std::to_string(data.remaining()) + " bytes of data");
    const std::uint64_t compressed = layout.compressed_size > 0 ? static_cast<std::uint64_t>(layout.compressed_size) : data.remaining();
    if (bytes + layout.inflated_skip > max_inflated_size(compressed))
        data.fail("truncated or lying header: " + description + ", but the " + std::to_string(compressed) +
                  "-byte compressed payload can inflate to at most " + std::to_string(max_inflated_size(compressed)) + " bytes");
}

}  // namespace

void read_image_payload(const std::string& path, ItkFormat format, const PayloadLayout& layout, InputFile& data,
                        const VolumeLimits& limits, VoxelDestination& destination) {
    check_sizes_within_limits(path, layout.sizes, layout.components, limits);
    const ImageHeader itk = read_itk_header(path, format);
    check_itk_agrees(path, layout, itk);
    const Index3 dims = image_dims(path, itk);
    const std::int64_t voxels = checked_voxel_count(path, dims, limits);
    const std::uint64_t bytes = payload_bytes(path, voxels, layout.sample.bytes);
    const std::string description = "header says " + describe_payload(dims, voxels, layout.sample.bytes);
    locate_payload(data, layout, bytes, description);

    VolumeFileInfo info;
    info.format = layout.format;
    info.value_type = layout.value_type;
    info.world_geometry = true;
    const VoxelGrid geometry = image_geometry(path, itk, info);
    const bool wanted = destination.allocate(path, dims);
    destination.set_geometry(geometry);
    destination.info() = info;
    if (!wanted) return;
    SampleWriter sink = destination.writer(data.path(), layout.sample);
    if (!layout.compressed) return decode_stored_prefix(data, sink);
    InflateStream stream(data, layout.container);
    stream.skip(layout.inflated_skip, description);
    stream.decode(bytes, sink, description);
}

}  // namespace dsreg::volume_io_detail
