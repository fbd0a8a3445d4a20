#include "volume_source.hpp"

#include <cmath>
#include <sstream>

#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"

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
}

double default_ii_radius(const LoadedVolume& loaded) {
    return loaded.shape ? 3.0 * std::cbrt(loaded.h) : 3.0 * loaded.volume.grid.spacing.maxCoeff();
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
    loaded.volume = digitize(*loaded.shape, loaded.h);
    loaded.description = o.shape + " at h=" + format_number(loaded.h);
    return loaded;
}

LoadedVolume read_file(const VolumeSourceOptions& o) {
    ValueRange range;
    if (o.min_value) range.has_min = true, range.min = *o.min_value;
    if (o.max_value) range.has_max = true, range.max = *o.max_value;
    VolumeLimits limits;
    limits.max_voxels = o.max_voxels;
    RawVolumeLayout layout;
    if (!o.raw_dims.empty()) {
        layout.dims = {o.raw_dims[0], o.raw_dims[1], o.raw_dims[2]};
        layout.type = parse_raw_voxel_type(o.raw_type);
        layout.big_endian = o.raw_big_endian;
        layout.header_bytes = o.raw_header_bytes;
    }
    LoadedVolume loaded;
    loaded.volume = read_volume(o.input_path, range, o.raw_dims.empty() ? nullptr : &layout, limits);
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
    return o.shape.empty() ? read_file(o) : digitize_shape(o);
}

}  // namespace dsreg::cli
