// dsreg — a caller's array of voxel values, read where it lies (e.g. a numpy array handed over by
// the Python module): any integer or floating-point type, either byte order, any strides.
//
// The array is indexed like a grid of volume.hpp: voxel (i, j, k) with i along x. Its values are
// read through `byte_strides`, so a transposed, sliced or reversed view needs no copy; the mask
// made of it is the one copy (1 byte per voxel, x fastest) that the pipeline works on.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// How one value of a VoxelArray is stored.
enum class ValueKind { Unsigned, Signed, Float };

struct VoxelArray {
    const std::uint8_t* data = nullptr;  ///< first byte of the value of voxel (0, 0, 0)
    Index3 dims{0, 0, 0};                ///< voxels along x, y, z
    /// Bytes from voxel (i,j,k) to (i+1,j,k), (i,j+1,k) and (i,j,k+1); any sign, any alignment.
    std::array<std::int64_t, 3> byte_strides{0, 0, 0};
    ValueKind kind = ValueKind::Unsigned;  ///< booleans are 1-byte unsigned values 0 and 1
    int bytes = 1;                         ///< 1, 2, 4 or 8 for integers; 2, 4 or 8 for floats (IEEE 754)
    bool big_endian = false;               ///< byte order of the values
    std::string description = "array";     ///< what messages and the report call it
};

/// Throws dsreg::Error (naming the array) unless the dimensions are positive, the data address
/// is set and `bytes` is a size of `kind`.
void check_voxel_array(const VoxelArray& array);

/// The mask of the array, x fastest: 1 where `range` contains the value (converted to double, as
/// the file readers do), else 0. One pass over the values, in parallel over the rows.
std::vector<std::uint8_t> threshold_voxel_array(const VoxelArray& array, const ValueRange& range);

/// The label map of the array, as read_label_volume makes one of a file (volume_io.hpp): every
/// distinct value a label, 0 the background, label indices compact and increasing with the value;
/// grid dims only (spacing 1, origin 0: the caller places it). Throws dsreg::Error naming the
/// array and the voxel (its linear index, x fastest) for a value that is not an integer of
/// magnitude below 2^53 (2.5, NaN) or for more than `max_labels` distinct labels. One pass over
/// the values on the calling thread (the label table is shared), in the array's memory order.
LabelVolume label_voxel_array(const VoxelArray& array, std::int64_t max_labels);

/// The smallest and largest value (NaN left out), or nothing if every value is NaN.
std::optional<std::pair<double, double>> voxel_array_value_range(const VoxelArray& array);

/// "uint8", "int16", "float32", ... for messages.
std::string value_type_name(const VoxelArray& array);

}  // namespace dsreg
