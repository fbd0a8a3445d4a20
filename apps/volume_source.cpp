#include "volume_source.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"
#include "stage_clock.hpp"

namespace dsreg::cli {

void add_volume_source_options(CLI::App& command, VolumeSourceOptions& o) {
    command.add_option("input", o.input_path, "Volume file: .vol .longvol .pgm3d .raw");
    command.add_option("--shape", o.shape,
                       "Implicit shape instead of a file: a named shape (sphere1 sphere9 ellipsoid cylinder torus "
                       "rcube goursat goursat-hole distel leopold diabolo heart crixxi) or a polynomial such as "
                       "\"x^2+y^2+z^2-25\" (F <= 0 inside)");
    command.add_option("--h", o.h, "Grid step for --shape, physical units (default: 1/64 of the shape's extent)");
    command.add_option("--box", o.box, "Half-size of the domain of a polynomial --shape")->capture_default_str();
    command.add_option("--min", o.min_value, "Object = voxels with value >= MIN (default: value > 0)");
    command.add_option("--max", o.max_value, "Object = voxels with value <= MAX");
    command.add_option("--raw-dims", o.raw_dims, "Dimensions X,Y,Z of a .raw volume")->expected(3)->delimiter(',');
    command.add_option("--raw-type", o.raw_type, "Voxel type of a .raw volume: uint8 int8 uint16 int16 uint32 int32 "
                                                 "uint64 int64 float32 float64")
        ->capture_default_str();
    command.add_flag("--raw-big-endian", o.raw_big_endian, "Values of the .raw volume are big-endian");
    command.add_option("--raw-header-bytes", o.raw_header_bytes, "Bytes to skip at the start of the .raw volume");
    command.add_option("--spacing", o.spacing, "Voxel size SX,SY,SZ in physical units (overrides the file's)")
        ->expected(3)
        ->delimiter(',');
    command.add_option("--max-voxels", o.max_voxels, "Refuse volumes with more voxels than this")->capture_default_str();
    command.add_option("--max-memory", o.max_memory,
                       "Refuse runs whose estimated peak memory exceeds this, e.g. 4G, 512M (K/M/G/T: powers of 1024)");
}

namespace {

constexpr double kFixedBytes = 16.0 * (1 << 20);
constexpr double kBytesPerVoxel = 1.0;
constexpr double kBytesPerSurfel = 3300.0;
constexpr double kFactorBytesPerSurfelLog = 640.0;

/// The voxel count that --max-memory leaves room for (the mask alone), or max_voxels.
std::int64_t memory_voxel_cap(const VolumeSourceOptions& o) {
    if (o.max_memory.empty()) return o.max_voxels;
    const double bytes = static_cast<double>(parse_memory_size("--max-memory", o.max_memory));
    if (bytes <= kFixedBytes)
        throw Error("--max-memory " + o.max_memory + " is below the " + human_bytes(kFixedBytes) + " any run needs");
    const double voxels = (bytes - kFixedBytes) / kBytesPerVoxel;
    return voxels < double(o.max_voxels) ? static_cast<std::int64_t>(voxels) : o.max_voxels;
}

}  // namespace

std::uint64_t parse_memory_size(const std::string& option, const std::string& text) {
    const auto bad = [&] {
        return Error(option + ": '" + text + "' is not a memory size (a positive number of bytes, or with a suffix K, M, G or T, e.g. 4G)");
    };
    if (text.empty() || !(std::isdigit(static_cast<unsigned char>(text[0])) || text[0] == '.')) throw bad();
    char* end = nullptr;
    const double number = std::strtod(text.c_str(), &end);
    std::string suffix(end);
    std::transform(suffix.begin(), suffix.end(), suffix.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    double scale = 1;
    if (!suffix.empty() && std::string("kmgt").find(suffix[0]) != std::string::npos) {
        scale = std::pow(1024.0, 1 + static_cast<double>(std::string("kmgt").find(suffix[0])));
        suffix.erase(0, 1);
        if (suffix == "ib" || suffix == "b") suffix.clear();
    } else if (suffix == "b") {
        suffix.clear();
    }
    const double bytes = number * scale;
    if (!suffix.empty() || !std::isfinite(bytes) || !(bytes >= 1) || bytes >= 9.2e18) throw bad();
    return static_cast<std::uint64_t>(bytes);
}

std::int64_t count_surfels(const BinaryVolume& volume) {
    const VoxelGrid& g = volume.grid;
    const std::int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
    std::int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count)
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                if (!volume.inside(i, j, k)) continue;
                count += !volume.inside(i - 1, j, k) + !volume.inside(i + 1, j, k) + !volume.inside(i, j - 1, k) +
                         !volume.inside(i, j + 1, k) + !volume.inside(i, j, k - 1) + !volume.inside(i, j, k + 1);
            }
    return count;
}

double estimate_run_memory(std::int64_t voxels, std::int64_t surfels, bool factorization) {
    const double m = static_cast<double>(surfels);
    double bytes = kFixedBytes + kBytesPerVoxel * static_cast<double>(voxels) + kBytesPerSurfel * m;
    if (factorization && m > 1) bytes += kFactorBytesPerSurfelLog * m * std::log2(m);
    return bytes;
}

void check_run_memory(const VolumeSourceOptions& o, std::int64_t voxels, std::int64_t surfels, bool factorization) {
    if (o.max_memory.empty()) return;
    const double limit = static_cast<double>(parse_memory_size("--max-memory", o.max_memory));
    const double estimate = estimate_run_memory(voxels, surfels, factorization);
    if (estimate <= limit) return;
    std::string advice = "use a coarser --h";
    if (o.shape.empty()) advice = "crop or subsample the volume";
    if (factorization) advice += ", --solver cg or amg (no factorization: " +
                                 human_bytes(estimate_run_memory(voxels, surfels, false)) + ")";
    throw Error("estimated peak memory " + human_bytes(estimate) + " (" + std::to_string(voxels) + " voxels, " +
                std::to_string(surfels) + " surfels" + (factorization ? ", sparse Cholesky factor" : "") +
                ") exceeds --max-memory " + o.max_memory + " (" + human_bytes(limit) + "): " + advice +
                ", or raise --max-memory");
}

double default_ii_radius(const LoadedVolume& loaded) {
    if (!loaded.shape) return 3.0 * loaded.volume.grid.spacing.maxCoeff();
    return std::min(3.0 * std::cbrt(loaded.h), (loaded.shape->upper - loaded.shape->lower).maxCoeff() / 8.0);
}

double default_grid_step(const ImplicitShape& shape) { return (shape.upper - shape.lower).maxCoeff() / 64.0; }

namespace {

std::string format_number(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
}

LoadedVolume digitize_shape(const VolumeSourceOptions& o) {
    LoadedVolume loaded;
    if (o.h && (!(*o.h > 0) || !std::isfinite(*o.h))) throw Error("--h must be positive (got " + format_number(*o.h) + ")");
    loaded.shape = make_shape(o.shape, o.box);
    loaded.h = o.h ? *o.h : default_grid_step(*loaded.shape);
    const Eigen::Vector3d cells = (loaded.shape->upper - loaded.shape->lower) / loaded.h + Eigen::Vector3d::Constant(3);
    if (cells.prod() > double(o.max_voxels))
        throw Error("--shape " + o.shape + " at --h " + format_number(loaded.h) + " needs about " +
                    format_number(cells.prod()) + " voxels, more than --max-voxels " + std::to_string(o.max_voxels));
    const std::int64_t memory_cap = memory_voxel_cap(o);
    if (cells.prod() > double(memory_cap))
        throw Error("--shape " + o.shape + " at --h " + format_number(loaded.h) + " needs about " +
                    format_number(cells.prod()) + " voxels, more than --max-memory " + o.max_memory + " leaves room for (" +
                    std::to_string(memory_cap) + " voxels)");
    loaded.volume = digitize(*loaded.shape, loaded.h);
    loaded.description = o.shape + " at h=" + format_number(loaded.h);
    return loaded;
}

/// The layout of a .raw input given by the --raw-* options (unused for other formats).
RawVolumeLayout raw_layout(const VolumeSourceOptions& o) {
    RawVolumeLayout layout;
    if (!o.raw_dims.empty()) {
        layout.dims = {o.raw_dims[0], o.raw_dims[1], o.raw_dims[2]};
        layout.type = parse_raw_voxel_type(o.raw_type);
        layout.big_endian = o.raw_big_endian;
        layout.header_bytes = o.raw_header_bytes;
    }
    return layout;
}

LoadedVolume read_file(const VolumeSourceOptions& o) {
    ValueRange range;
    if (o.min_value) range.has_min = true, range.min = *o.min_value;
    if (o.max_value) range.has_max = true, range.max = *o.max_value;
    VolumeLimits limits;
    limits.max_voxels = memory_voxel_cap(o);
    const bool memory_bound = limits.max_voxels < o.max_voxels;
    const RawVolumeLayout layout = raw_layout(o);
    LoadedVolume loaded;
    try {
        loaded.volume = read_volume(o.input_path, range, o.raw_dims.empty() ? nullptr : &layout, limits);
    } catch (const Error& error) {
        const std::string message = error.what();
        if (memory_bound && message.find("exceed the limit of") != std::string::npos)
            throw Error(message + " that --max-memory " + o.max_memory + " leaves room for");
        throw;
    }
    loaded.description = o.input_path;
    if (!o.spacing.empty()) {
        for (double s : o.spacing)
            if (!(s > 0) || !std::isfinite(s)) throw Error("--spacing: every voxel size must be positive and finite");
        loaded.volume.grid.spacing = Eigen::Vector3d(o.spacing[0], o.spacing[1], o.spacing[2]);
    }
    loaded.h = loaded.volume.grid.spacing.maxCoeff();
    return loaded;
}

}  // namespace

LoadedVolume load_volume(const VolumeSourceOptions& o) {
    if (o.input_path.empty() == o.shape.empty())
        throw Error(o.shape.empty() ? "no input: give a volume file or --shape NAME" : "give either a volume file or --shape, not both");
    if (o.max_voxels <= 0) throw Error("--max-voxels must be positive (got " + std::to_string(o.max_voxels) + ")");
    return o.shape.empty() ? read_file(o) : digitize_shape(o);
}

std::string object_value_range(const VolumeSourceOptions& o) {
    const std::string low = o.min_value ? format_number(*o.min_value) + " <= " : "0 < ";
    const std::string high = o.max_value ? " <= " + format_number(*o.max_value) : "";
    if (!o.max_value) return o.min_value ? "value >= " + format_number(*o.min_value) : "value > 0";
    return low + "value" + high;
}

std::string file_value_range(const VolumeSourceOptions& o) {
    try {
        const RawVolumeLayout layout = raw_layout(o);
        VolumeLimits limits;
        limits.max_voxels = memory_voxel_cap(o);
        const ScalarVolume values = read_volume_values(o.input_path, o.raw_dims.empty() ? nullptr : &layout, limits);
        if (values.values.empty()) return "";
        const auto [low, high] = std::minmax_element(values.values.begin(), values.values.end());
        return "its values range from " + format_number(*low) + " to " + format_number(*high);
    } catch (const std::exception&) {
        return "";  // only a hint: a file too large for the limits, say
    }
}

}  // namespace dsreg::cli
