// dsreg — the payload of a NRRD or MetaImage file (not public API): where dsreg's own header
// parse says it is, checked against the data file, decoded as it streams; the geometry from
// ITK's reading of the same header, which must agree on the number and type of the values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "itk_bridge.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

/// What a header parsed by dsreg says of its payload.
struct PayloadLayout {
    std::string format;                ///< "NRRD", "MetaImage" (info, messages)
    std::string sizes_field;           ///< the header's name for the sizes: "sizes", "DimSize"
    std::vector<std::int64_t> sizes;   ///< every dimension, as the header gives them
    std::int64_t components = 1;       ///< values per voxel the header announces
    SampleFormat sample;
    std::string value_type;
    std::int64_t skip = 0;             ///< stored bytes before the payload; −1: the payload ends the file
    bool compressed = false;
    CompressedContainer container = CompressedContainer::Gzip;
    std::int64_t compressed_size = -1;  ///< bytes of the compressed stream; −1: the rest of the file
    std::uint64_t inflated_skip = 0;    ///< inflated bytes before the payload
};

/// Checks `layout.sizes` against the limits, reads ITK's header of `path` (geometry, dims; 4-D
/// and vector images rejected) and checks that it agrees with `layout`, checks the payload
/// against the rest of `data` (a stored payload must fit; a compressed one must be able to
/// inflate to its size), then allocates `destination` and decodes the payload into it.
void read_image_payload(const std::string& path, ItkFormat format, const PayloadLayout& layout, InputFile& data,
                        const VolumeLimits& limits, VoxelDestination& destination);

}  // namespace dsreg::volume_io_detail
