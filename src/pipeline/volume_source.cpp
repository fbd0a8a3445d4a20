#include "dsreg/pipeline.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "dsreg/error.hpp"
#include "dsreg/grid_placement.hpp"
#include "dsreg/value_histogram.hpp"
#include "dsreg/text.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg {

namespace {

constexpr double kFixedBytes = 16.0 * (1 << 20);
constexpr double kBytesPerVoxel = 1.0;
constexpr double kBytesPerSurfel = 3300.0;
constexpr double kFactorBytesPerSurfelLog = 640.0;

/// Bytes per voxel of the loaded volume: a mask, or label indices.
int bytes_per_voxel(const VolumeSource& o) { return o.is_multi_label() ? 4 : int(kBytesPerVoxel); }

/// The voxel count that --max-memory leaves room for (the mask or labels alone), or max_voxels.
std::int64_t memory_voxel_cap(const VolumeSource& o) {
    if (o.max_memory.empty()) return o.max_voxels;
    const double bytes = static_cast<double>(parse_memory_size("--max-memory", o.max_memory));
    if (bytes <= kFixedBytes)
        throw Error("--max-memory " + o.max_memory + " is below the " + human_bytes(kFixedBytes) + " any run needs");
    const double voxels = (bytes - kFixedBytes) / bytes_per_voxel(o);
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

namespace {

/// Faces between 6-neighbours of different labels (outside the grid is label 0), each once:
/// towards +x, +y, +z, and across the grid's lower borders. One pass, no allocation.
template <class LabelAt>
std::int64_t count_faces(const VoxelGrid& g, LabelAt label) {
    const std::int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
    std::int64_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count)
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                const std::uint32_t l = label(i, j, k);
                count += (l != label(i + 1, j, k)) + (l != label(i, j + 1, k)) + (l != label(i, j, k + 1));
                count += (i == 0 && l != 0) + (j == 0 && l != 0) + (k == 0 && l != 0);
            }
    return count;
}

}  // namespace

std::int64_t count_surfels(const BinaryVolume& volume) {
    return count_faces(volume.grid, [&](std::int64_t i, std::int64_t j, std::int64_t k) { return volume.inside(i, j, k) ? 1u : 0u; });
}

std::int64_t count_surfels(const LabelVolume& volume) {
    return count_faces(volume.grid, [&](std::int64_t i, std::int64_t j, std::int64_t k) { return volume.label(i, j, k); });
}

double estimate_run_memory(std::int64_t voxels, std::int64_t surfels, bool factorization, int bytes_per_voxel) {
    const double m = static_cast<double>(surfels);
    double bytes = kFixedBytes + bytes_per_voxel * static_cast<double>(voxels) + kBytesPerSurfel * m;
    if (factorization && m > 1) bytes += kFactorBytesPerSurfelLog * m * std::log2(m);
    return bytes;
}

void check_run_memory(const VolumeSource& o, std::int64_t voxels, std::int64_t surfels, bool factorization) {
    if (o.max_memory.empty()) return;
    const double limit = static_cast<double>(parse_memory_size("--max-memory", o.max_memory));
    const double estimate = estimate_run_memory(voxels, surfels, factorization, bytes_per_voxel(o));
    if (estimate <= limit) return;
    std::string advice = "use a coarser --h";
    if (o.shape.empty()) advice = "crop or subsample the volume";
    if (factorization) advice += ", --solver cg or amg (no factorization: " +
                                 human_bytes(estimate_run_memory(voxels, surfels, false, bytes_per_voxel(o))) + ")";
    throw Error("estimated peak memory " + human_bytes(estimate) + " (" + std::to_string(voxels) + " voxels, " +
                std::to_string(surfels) + " surfels" + (factorization ? ", sparse Cholesky factor" : "") +
                ") exceeds --max-memory " + o.max_memory + " (" + human_bytes(limit) + "): " + advice +
                ", or raise --max-memory");
}

double default_grid_step(const ImplicitShape& shape) { return (shape.upper - shape.lower).maxCoeff() / 64.0; }

namespace {

std::string format_number(double x) { return format("%g", x); }

/// A --shape source without its voxels: shape, grid step, grid, description (--max-voxels checked).
LoadedVolume shape_header(const VolumeSource& o) {
    LoadedVolume loaded;
    if (o.h && (!(*o.h > 0) || !std::isfinite(*o.h))) throw Error("--h must be positive (got " + format_number(*o.h) + ")");
    loaded.shape = make_shape(o.shape, o.box);
    loaded.h = o.h ? *o.h : default_grid_step(*loaded.shape);
    const Eigen::Vector3d cells = (loaded.shape->upper - loaded.shape->lower) / loaded.h + Eigen::Vector3d::Constant(3);
    if (cells.prod() > double(o.max_voxels))
        throw Error("--shape " + o.shape + " at --h " + format_number(loaded.h) + " needs about " +
                    format_number(cells.prod()) + " voxels, more than --max-voxels " + std::to_string(o.max_voxels));
    loaded.description = o.shape + " at h=" + format_number(loaded.h);
    return loaded;
}

LoadedVolume digitize_shape(const VolumeSource& o) {
    LoadedVolume loaded = shape_header(o);
    const Eigen::Vector3d cells = (loaded.shape->upper - loaded.shape->lower) / loaded.h + Eigen::Vector3d::Constant(3);
    const std::int64_t memory_cap = memory_voxel_cap(o);
    if (cells.prod() > double(memory_cap))
        throw Error("--shape " + o.shape + " at --h " + format_number(loaded.h) + " needs about " +
                    format_number(cells.prod()) + " voxels, more than --max-memory " + o.max_memory + " leaves room for (" +
                    std::to_string(memory_cap) + " voxels)");
    loaded.volume = digitize(*loaded.shape, loaded.h);
    return loaded;
}

/// The object's values: --label N, or --min/--max (default value > 0).
ValueRange object_range(const VolumeSource& o) {
    ValueRange range;
    if (o.label) {
        if (o.min_value || o.max_value) throw Error("--label selects one value: it cannot be combined with --min or --max");
        if (!std::isfinite(*o.label)) throw Error("--label must be a finite number");
        range.has_min = range.has_max = true;
        range.min = range.max = *o.label;
        return range;
    }
    if (o.min_value) range.has_min = true, range.min = *o.min_value;
    if (o.max_value) range.has_max = true, range.max = *o.max_value;
    return range;
}

void check_spacing(const Eigen::Vector3d& spacing) {
    if (!(spacing.array() > 0).all() || !spacing.allFinite())
        throw Error("--spacing: every voxel size must be positive and finite");
}

/// --spacing, checked, on a grid read from a file.
void apply_spacing(const VolumeSource& o, VoxelGrid& grid) {
    if (!o.spacing) return;
    check_spacing(*o.spacing);
    grid.spacing = *o.spacing;
}

/// Runs a reader with the voxel limit of the options, naming --max-memory when it is the bound.
template <typename Read>
auto read_within_limits(const VolumeSource& o, Read&& read) {
    VolumeLimits limits;
    limits.max_voxels = memory_voxel_cap(o);
    const bool memory_bound = limits.max_voxels < o.max_voxels;
    try {
        return read(limits);
    } catch (const Error& error) {
        const std::string message = error.what();
        if (memory_bound && message.find("exceed the limit of") != std::string::npos)
            throw Error(message + " that --max-memory " + o.max_memory + " leaves room for");
        throw;
    }
}

LoadedVolume read_file(const VolumeSource& o) {
    LoadedVolume loaded;
    loaded.volume = read_within_limits(o, [&](const VolumeLimits& limits) {
        return read_volume(o.input_path, object_range(o), o.raw_layout ? &*o.raw_layout : nullptr, limits, &loaded.file);
    });
    loaded.description = o.input_path;
    apply_spacing(o, loaded.volume.grid);
    loaded.h = loaded.volume.grid.spacing.maxCoeff();
    return loaded;
}

/// The grid of an array: placed by its affine, or by its spacing and origin.
VoxelGrid array_grid(const VolumeSource& o) {
    if (o.affine) {
        if (o.spacing || o.origin) throw Error("affine gives the spacing and the origin: do not give them too");
        return grid_from_affine(o.array->dims, *o.affine, o.affine_space);
    }
    VoxelGrid grid;
    grid.dims = o.array->dims;
    if (o.spacing) check_spacing(*o.spacing), grid.spacing = *o.spacing;
    if (o.origin) {
        if (!o.origin->allFinite()) throw Error("origin: every coordinate must be finite");
        grid.origin = *o.origin;
    }
    return grid;
}

/// An array input, checked against the voxel limits (a mask or label indices per voxel, as the
/// options ask), with its grid, description and file information; the voxels are the caller's.
LoadedVolume array_header(const VolumeSource& o) {
    const VoxelArray& array = *o.array;
    check_voxel_array(array);
    const double voxels = double(array.dims[0]) * double(array.dims[1]) * double(array.dims[2]);
    const std::int64_t cap = memory_voxel_cap(o);
    if (voxels > double(cap))
        throw Error(array.description + ": " + format_number(voxels) + " voxels exceed the limit of " +
                    std::to_string(cap) + (cap < o.max_voxels ? " that --max-memory " + o.max_memory + " leaves room for"
                                                              : " (--max-voxels)"));
    LoadedVolume loaded;
    loaded.volume.grid = array_grid(o);
    loaded.description = array.description;
    loaded.h = loaded.volume.grid.spacing.maxCoeff();
    loaded.file.format = "array";
    loaded.file.value_type = value_type_name(array);
    loaded.file.world_geometry = o.affine.has_value();
    return loaded;
}

LoadedVolume threshold_array(const VolumeSource& o) {
    LoadedVolume loaded = array_header(o);
    loaded.volume.mask = threshold_voxel_array(*o.array, object_range(o));
    return loaded;
}

/// The label map of an array, placed as its mask would be (affine, or spacing and origin).
LoadedVolume label_array(const VolumeSource& o) {
    LoadedVolume loaded = array_header(o);
    loaded.labels = label_voxel_array(*o.array, VolumeLimits{}.max_labels);
    loaded.labels->grid = loaded.volume.grid;
    return loaded;
}

/// The values that make a voxel of a file part of the object, as the options give them:
/// "value > 0", "value >= 300", "40 <= value <= 200", "0 < value <= 50".
std::string object_value_range(const VolumeSource& o) {
    if (o.label) return "value = " + format_number(*o.label);
    const std::string low = o.min_value ? format_number(*o.min_value) + " <= " : "0 < ";
    const std::string high = o.max_value ? " <= " + format_number(*o.max_value) : "";
    if (!o.max_value) return o.min_value ? "value >= " + format_number(*o.min_value) : "value > 0";
    return low + "value" + high;
}

/// "its values range from A to B" for the input file (read again, 4 bytes per voxel) or array, or
/// "" when that cannot be read within the limits. For messages about an empty object.
std::string input_value_range(const VolumeSource& o) {
    std::optional<std::pair<double, double>> range;
    try {
        if (o.array) {
            range = voxel_array_value_range(*o.array);
        } else {
            const ScalarVolume values = load_volume_values(o);
            if (!values.values.empty()) {
                const auto [low, high] = std::minmax_element(values.values.begin(), values.values.end());
                range = std::make_pair(double(*low), double(*high));
            }
        }
    } catch (const std::exception&) {
        return "";  // only a hint: a file too large for the limits, say
    }
    if (!range) return "";
    return "its values range from " + format_number(range->first) + " to " + format_number(range->second);
}

/// Exactly one input; no placement where it does not apply.
void check_input_choice(const VolumeSource& o) {
    const int inputs = int(!o.input_path.empty()) + int(!o.shape.empty()) + int(o.array.has_value());
    if (inputs == 0) throw Error("no input: give a volume file or --shape NAME");
    if (inputs > 1)
        throw Error(o.array ? "give either an array, a volume file or --shape, not several"
                            : "give either a volume file or --shape, not both");
    if (!o.array && (o.affine || o.origin)) throw Error("affine and origin apply to arrays only");
}

/// The object takes most of the volume: say so, with the value histogram's main modes for a file
/// (read twice more, streaming, nothing kept per voxel).
std::string most_of_the_volume_warning(const VolumeSource& o, double fraction) {
    std::string modes;
    try {
        if (!o.array) {
            VolumeLimits limits;
            limits.max_voxels = memory_voxel_cap(o);
            const ValueHistogram histogram = read_value_histogram(o.input_path, o.raw_layout ? &*o.raw_layout : nullptr, limits);
            modes = describe_modes(histogram_modes(histogram), histogram.integral);
        }
    } catch (const std::exception&) {
        // only a hint
    }
    return "the object (" + object_value_range(o) + ") takes " + format("%.0f", 100 * fraction) +
           "% of the volume: probably the background or the scanner's field of view rather than the intended object" +
           (modes.empty() ? "" : "; the values' main modes are " + modes) + " (choose the object with --label, --min, --max)";
}

void check_source(const VolumeSource& o) {
    check_input_choice(o);
    if (o.max_voxels <= 0) throw Error("--max-voxels must be positive (got " + std::to_string(o.max_voxels) + ")");
}

/// --multi-label: the label map of the file or array (every distinct value a label), or the
/// shape's digitization as the label map {0, 1}; --labels keeps some; --spacing applies.
LoadedVolume load_label_map(const VolumeSource& o) {
    LoadedVolume loaded;
    if (o.array) {
        loaded = label_array(o);
    } else if (!o.shape.empty()) {
        loaded = digitize_shape(o);
        loaded.labels = label_volume_from_mask(loaded.volume);
    } else {
        loaded.labels = read_within_limits(o, [&](const VolumeLimits& limits) {
            return read_label_volume(o.input_path, o.raw_layout ? &*o.raw_layout : nullptr, limits, &loaded.file);
        });
        loaded.description = o.input_path;
        if (o.spacing) {
            check_spacing(*o.spacing);
            loaded.labels->grid.spacing = *o.spacing;
        }
        loaded.h = loaded.labels->grid.spacing.maxCoeff();
    }
    if (!o.labels.empty()) keep_labels(*loaded.labels, o.labels, "--labels");
    loaded.volume = BinaryVolume{loaded.labels->grid, {}};  // the grid only: the labels are the data
    const std::vector<std::int64_t> counts = loaded.labels->voxel_counts();
    std::int64_t labelled = 0, present = 0;
    for (std::size_t l = 1; l < counts.size(); ++l) labelled += counts[l], present += counts[l] > 0;
    if (labelled == 0) {
        const std::string values = o.shape.empty() ? input_value_range(o) : "";
        throw Error((o.array ? o.array->description : o.shape.empty() ? o.input_path : o.shape) + ": no voxel has a label (with --multi-label every non-zero value is one)" +
                    (values.empty() ? "" : "; " + values));
    }
    loaded.description += " (" + std::to_string(present) + (present == 1 ? " label)" : " labels)");
    return loaded;
}

}  // namespace

Error empty_object_error(const VolumeSource& o, bool read_value_range) {
    if (!o.shape.empty()) return Error(o.shape + ": the object is empty");
    const std::string values = read_value_range ? input_value_range(o) : "";
    return Error((o.array ? o.array->description : o.input_path) + ": the object is empty: no voxel has " + object_value_range(o) +
                 (values.empty() ? "" : "; " + values) + " (choose the object's values with --label, --min and --max)");
}

LoadedVolume load_volume(const VolumeSource& o) {
    check_source(o);
    if (o.is_multi_label()) return load_label_map(o);
    if (!o.shape.empty()) return digitize_shape(o);
    LoadedVolume loaded = o.array ? threshold_array(o) : read_file(o);
    const std::int64_t object = loaded.volume.object_voxel_count();
    if (object == 0) throw empty_object_error(o, true);
    const double fraction = double(object) / double(loaded.volume.grid.voxel_count());
    if (fraction > kMostOfTheVolume) loaded.warnings.push_back(most_of_the_volume_warning(o, fraction));
    return loaded;
}

LoadedVolume probe_volume(const VolumeSource& o) {
    check_source(o);
    if (o.array) throw Error(o.array->description + ": block-wise runs read a volume file or a --shape, not an array");
    if (!o.shape.empty()) {
        LoadedVolume loaded = shape_header(o);
        loaded.volume.grid = digitization_grid(*loaded.shape, loaded.h);
        return loaded;
    }
    VolumeLimits limits;
    limits.max_voxels = o.max_voxels;
    LoadedVolume loaded;
    loaded.volume.grid = read_volume_grid(o.input_path, o.raw_layout ? &*o.raw_layout : nullptr, limits, &loaded.file);
    loaded.description = o.input_path;
    apply_spacing(o, loaded.volume.grid);
    loaded.h = loaded.volume.grid.spacing.maxCoeff();
    return loaded;
}

BinaryVolume load_volume_box(const VolumeSource& o, const LoadedVolume& header, const VoxelBox& box) {
    if (header.shape) return digitize_box(*header.shape, header.h, box);
    VolumeLimits limits;
    limits.max_voxels = o.max_voxels;
    BinaryVolume volume = read_volume_box(o.input_path, box, object_range(o), o.raw_layout ? &*o.raw_layout : nullptr, limits);
    const VoxelGrid& grid = header.volume.grid;  // the file's, with --spacing applied
    volume.grid.spacing = grid.spacing;
    volume.grid.origin = grid.voxel_center(box.lo[0], box.lo[1], box.lo[2]);
    volume.grid.direction = grid.direction;
    return volume;
}

ScalarVolume load_volume_values(const VolumeSource& o, VolumeFileInfo* info) {
    if (o.input_path.empty()) throw Error("no input: give a volume file");
    if (o.max_voxels <= 0) throw Error("--max-voxels must be positive (got " + std::to_string(o.max_voxels) + ")");
    ScalarVolume values = read_within_limits(o, [&](const VolumeLimits& limits) {
        return read_volume_values(o.input_path, o.raw_layout ? &*o.raw_layout : nullptr, limits, info);
    });
    apply_spacing(o, values.grid);
    return values;
}

}  // namespace dsreg
