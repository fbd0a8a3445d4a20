// dsreg — voxel grids and binary volumes (the first stage of the pipeline).
//
// Coordinate conventions (shared by every stage, see docs/conventions.md):
//  * A grid has dims = (nx, ny, nz) voxels, spacing = (sx, sy, sz) physical units per voxel and
//    origin = the physical position of the centre of voxel (0,0,0).
//  * Voxel (i,j,k) is the box of size `spacing` centred at origin + spacing ⊙ (i,j,k).
//  * Voxels are stored with x varying fastest: linear index = i + nx·(j + ny·k).
//  * Pointel (a,b,c), a ∈ [0, nx], is the voxel corner at origin + spacing ⊙ (a−½, b−½, c−½).
//  * Everything outside the grid is background.
//  * The grid frame above is axis-aligned: it is where every stage works (surface, normals,
//    regularization, evaluation, clamp boxes). A medical image also has direction cosines: the
//    world position of grid-frame point p is origin + direction·(p − origin) (ITK's convention:
//    world = origin + direction·(spacing ⊙ index), world in LPS). Because `direction` is
//    orthonormal, distances, balls and radii are the same in both frames; meshes are mapped to
//    the output space only when written (dsreg/world_space.hpp).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace dsreg {

using Index3 = std::array<std::int64_t, 3>;

struct VoxelGrid {
    Index3 dims{0, 0, 0};
    Eigen::Vector3d spacing{1.0, 1.0, 1.0};  ///< physical size of a voxel along x, y, z
    Eigen::Vector3d origin{0.0, 0.0, 0.0};   ///< physical centre of voxel (0,0,0)
    /// Direction cosines: column c is the unit world (LPS) vector along which index c grows.
    /// Always orthonormal (readers reject or orthonormalize other matrices); its determinant is
    /// −1 for a left-handed index frame. Identity for the DGtal formats and digitized shapes.
    Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();

    std::int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
    std::int64_t linear_index(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return i + dims[0] * (j + dims[1] * k);
    }
    bool contains(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
    }
    /// Physical centre of voxel (i,j,k).
    Eigen::Vector3d voxel_center(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return origin + spacing.cwiseProduct(Eigen::Vector3d(double(i), double(j), double(k)));
    }
    /// Physical position of pointel (a,b,c).
    Eigen::Vector3d pointel_position(std::int64_t a, std::int64_t b, std::int64_t c) const {
        return origin + spacing.cwiseProduct(Eigen::Vector3d(a - 0.5, b - 0.5, c - 0.5));
    }
};

/// Voxels lo ≤ (i,j,k) < hi of a grid (half-open on each axis).
struct VoxelBox {
    Index3 lo{0, 0, 0};
    Index3 hi{0, 0, 0};

    bool empty() const { return hi[0] <= lo[0] || hi[1] <= lo[1] || hi[2] <= lo[2]; }
    Index3 size() const { return {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}; }
    std::int64_t voxel_count() const { return empty() ? 0 : size()[0] * size()[1] * size()[2]; }
    bool contains(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return i >= lo[0] && j >= lo[1] && k >= lo[2] && i < hi[0] && j < hi[1] && k < hi[2];
    }
    /// Whether `box` lies inside (an empty box lies inside any box).
    bool contains(const VoxelBox& box) const;
    /// Grown by `margin` voxels on every side (shrunk if negative).
    VoxelBox grown(std::int64_t margin) const;
    /// Grown by margin[a] voxels on both sides of axis a.
    VoxelBox grown(const Index3& margin) const;
    /// The part inside a grid of `dims` voxels.
    VoxelBox clipped(const Index3& dims) const;
    bool operator==(const VoxelBox& other) const { return lo == other.lo && hi == other.hi; }
};

/// A binary image: mask[linear_index] != 0 for object voxels.
struct BinaryVolume {
    VoxelGrid grid;
    std::vector<std::uint8_t> mask;

    bool inside(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return grid.contains(i, j, k) && mask[static_cast<std::size_t>(grid.linear_index(i, j, k))] != 0;
    }
    std::int64_t object_voxel_count() const;
};

/// A label map: every voxel carries a label index, 0 being the background (as is everything
/// outside the grid). Indices are compact, 0 … label_count() − 1, in increasing order of the
/// voxel values they stand for: values[index] is the value of label `index` in the input
/// (values[0] = 0, the background, even when no voxel has it). 4 bytes per voxel.
struct LabelVolume {
    VoxelGrid grid;
    std::vector<std::uint32_t> labels;  ///< label index of each voxel (linear_index order)
    std::vector<std::int64_t> values;   ///< input value of each label index; values[0] = 0

    std::uint32_t label(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return grid.contains(i, j, k) ? labels[static_cast<std::size_t>(grid.linear_index(i, j, k))] : 0u;
    }
    std::int64_t label_count() const { return static_cast<std::int64_t>(values.size()); }
    /// Voxels of each label index (index 0: background voxels of the grid).
    std::vector<std::int64_t> voxel_counts() const;
};

/// A read-only view of the label index of every voxel, of a binary volume (object 1,
/// background 0) or of a label map, for the stages that treat both alike (the adaptive normals,
/// the local reach). It points to the volume it was made from, which must outlive it.
class VoxelLabels {
public:
    VoxelLabels(const BinaryVolume& volume) : grid_(&volume.grid), mask_(volume.mask.data()) {}  // NOLINT: implicit
    VoxelLabels(const LabelVolume& volume) : grid_(&volume.grid), labels_(volume.labels.data()) {}  // NOLINT: implicit

    const VoxelGrid& grid() const { return *grid_; }
    /// Label index of voxel (i,j,k); 0 outside the grid.
    std::uint32_t at(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return grid_->contains(i, j, k) ? at_linear(grid_->linear_index(i, j, k)) : 0u;
    }
    std::uint32_t at_linear(std::int64_t index) const {
        return labels_ ? labels_[index] : (mask_[index] != 0 ? 1u : 0u);
    }
    bool is_binary() const { return labels_ == nullptr; }

private:
    const VoxelGrid* grid_;
    const std::uint8_t* mask_ = nullptr;
    const std::uint32_t* labels_ = nullptr;
};

/// The binary volume as a label map: label 1 (value 1) for the object, 0 elsewhere.
LabelVolume label_volume_from_mask(const BinaryVolume& volume);

/// Keeps the labels whose value is listed (each must occur in the volume) and turns every other
/// voxel into background; the indices are renumbered compactly. Throws dsreg::Error naming
/// `option` for a listed value that is 0 or absent.
void keep_labels(LabelVolume& volume, const std::vector<std::int64_t>& values, const std::string& option);

/// Which voxel values form the object. Default: value > 0. With `min` set the test is
/// value ≥ min; with `max` set, value ≤ max (both inclusive, as `--min/--max` in the CLI).
struct ValueRange {
    bool has_min = false;
    double min = 0.0;
    bool has_max = false;
    double max = 0.0;

    bool contains(double value) const {
        const bool above = has_min ? value >= min : value > 0.0;
        const bool below = has_max ? value <= max : true;
        return above && below;
    }
};

}  // namespace dsreg
