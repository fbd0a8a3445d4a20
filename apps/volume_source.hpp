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
    std::string max_memory;  ///< --max-memory as given ("4G"); empty = no limit
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

/// Parses a memory size: a number of bytes with an optional suffix K, M, G or T (powers of 1024,
/// optionally followed by "iB" or "B", any case), e.g. "4G", "512MiB", "1.5g", "1000000".
/// Throws dsreg::Error naming `option` unless it is a positive finite size below 2^63 bytes.
std::uint64_t parse_memory_size(const std::string& option, const std::string& text);

/// The number of surfels of the object of `volume` (6-neighbour object/background voxel faces,
/// the border counting as background), counted without building the surface: one pass over
/// the voxels, no allocation.
std::int64_t count_surfels(const BinaryVolume& volume);

/// Estimated peak memory (bytes) of `dsreg regularize` on `voxels` voxels whose object has
/// `surfels` surfels: a fixed 16 MiB, 1 byte per voxel (the mask), 3300 bytes per surfel (the
/// surface, its normals, the sparse system and solver vectors) and, when a sparse Cholesky
/// factorization may run (cholmod, auto), 640·m·log2(m) bytes for the factor (about 64·m·log2(m)
/// nonzeros of ~10 bytes). Fitted on goursat h = 0.5 … 0.125 and bunny-128 (measured peaks
/// 105 MiB … 1.86 GiB), it overestimates by 10–30%. Local weight maps (4 bytes per voxel each)
/// and Ambrosio–Tortorelli normals are not counted.
double estimate_run_memory(std::int64_t voxels, std::int64_t surfels, bool factorization);

/// Throws dsreg::Error if `options.max_memory` is set and the estimate above exceeds it. The
/// message gives the estimate, the counts it is made of, and what to change.
void check_run_memory(const VolumeSourceOptions& options, std::int64_t voxels, std::int64_t surfels,
                      bool factorization);

/// The values that make a voxel of a file part of the object, as the options give them:
/// "value > 0", "value >= 300", "40 <= value <= 200", "0 < value <= 50".
std::string object_value_range(const VolumeSourceOptions& options);

/// "its values range from A to B" for the input file (read again, 4 bytes per voxel), or "" when
/// that cannot be read within the limits. For messages about an empty object.
std::string file_value_range(const VolumeSourceOptions& options);

/// The default integral-invariant radius: 3 voxels for files; for shapes the multigrid-convergent
/// r = 3·h^(1/3) (DESIGN.md), which is also 3 voxels at h = 1, but at most 1/8 of the largest
/// side of the shape's box: 3·h^(1/3) suits shapes about 10 across, and on smaller ones (sphere1,
/// heart) it would make a ball as wide as the shape.
double default_ii_radius(const LoadedVolume& loaded);

/// The automatic grid step: 1/64 of the largest extent of the shape's box.
double default_grid_step(const ImplicitShape& shape);

}  // namespace dsreg::cli
