// dsreg — how one voxel value is encoded in a payload (not public API; no Eigen, no zlib, so
// that the ITK translation unit can include it: ITK bundles its own Eigen).
#pragma once

namespace dsreg::volume_io_detail {

enum class SampleKind { Unsigned, Signed, Float };

struct SampleFormat {
    int bytes = 1;  ///< 1, 2, 4 or 8
    SampleKind kind = SampleKind::Unsigned;
    bool big_endian = false;
};

}  // namespace dsreg::volume_io_detail
