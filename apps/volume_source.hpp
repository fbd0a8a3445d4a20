// dsreg CLI — where the binary volume comes from: a file, or an implicit shape digitized at h.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/implicit_shape.hpp"
#include "dsreg/volume.hpp"

namespace dsreg::cli {

struct VolumeSourceOptions {
    std::string input_path;  ///< .vol .longvol .pgm3d .raw
    std::string shape;       ///< named shape or polynomial in x, y, z
    std::optional<double> h;  ///< grid step for --shape; unset = automatic
    double box = 10;         ///< half-size of the box of a polynomial shape
    std::optional<double> min_value, max_value;
    std::vector<std::int64_t> raw_dims;
    std::string raw_type = "uint8";
    bool raw_big_endian = false;
    std::uint64_t raw_header_bytes = 0;
    std::vector<double> spacing;  ///< overrides the file's voxel size (3 values)
    std::int64_t max_voxels = std::int64_t(1) << 34;
};

/// Registers INPUT and the --shape/--h/--min/--max/--raw-*/--spacing options on `command`.
void add_volume_source_options(CLI::App& command, VolumeSourceOptions& options);

struct LoadedVolume {
    BinaryVolume volume;
    std::string description;             ///< e.g. "bunny.vol" or "goursat at h=0.25"
    std::optional<ImplicitShape> shape;  ///< set for --shape inputs
    double h = 1;                        ///< grid step (largest spacing for files)
};

/// Reads or digitizes the volume. Throws dsreg::Error on any problem.
LoadedVolume load_volume(const VolumeSourceOptions& options);

/// The default integral-invariant radius: 3 voxels for files; for shapes the multigrid-convergent
/// r = 3·h^(1/3) (DESIGN.md), which is also 3 voxels at h = 1.
double default_ii_radius(const LoadedVolume& loaded);

/// The automatic grid step: 1/64 of the largest extent of the shape's box.
double default_grid_step(const ImplicitShape& shape);

}  // namespace dsreg::cli
