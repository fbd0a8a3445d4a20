// dsreg — the distribution of a volume file's values, to help choose the object (--min, --max,
// --label) when a threshold selects far more than intended (e.g. the scanner's cylinder of a CT).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/volume_io.hpp"

namespace dsreg {

/// Counts of a file's voxel values in equal bins: bins[b] counts the values in
/// [min + b·bin_width, min + (b+1)·bin_width), the last bin closed at max.
struct ValueHistogram {
    std::int64_t count = 0;  ///< values seen (the voxel count)
    double min = 0, max = 0;
    bool integral = true;    ///< every value is an integer
    double bin_width = 1;
    std::vector<std::int64_t> bins;
    /// While `bins` is empty, and as long as every value is an integer and they span at most
    /// `exact_limit` values: the count of each value min + i (empty otherwise), so that integer
    /// data needs no second pass (read_value_histogram).
    std::vector<std::int64_t> exact_counts;
    std::int64_t exact_limit = 0;
    /// The last value added and its slot (in exact_counts, then in bins; −1: none), so that a run
    /// of equal values, the bulk of a label map or a mask, costs one increment per value.
    double last_value = 0;
    std::int64_t last_slot = -1;

    /// While `bins` is empty: extends min, max, integral, count, exact_counts. Then: counts
    /// `value` in its bin.
    void add(double value);
};

/// The histogram of the values of `path` (any format read_volume accepts; same checks, same
/// errors), streamed: once for the range (and the counts, for integers spanning at most
/// `max_bins` values), once more for the counts of other data; nothing per voxel is kept.
/// Integer values spanning at most `max_bins` values get one bin each, others `max_bins` equal
/// bins. NaN values are not counted.
ValueHistogram read_value_histogram(const std::string& path, const RawVolumeLayout* raw_layout = nullptr,
                                    const VolumeLimits& limits = {}, int max_bins = 256);

/// A peak of a histogram: the values [low, high] hold `fraction` of the voxels.
struct HistogramMode {
    double low = 0, high = 0;
    double fraction = 0;
};

/// The main modes, largest first: the histogram is regrouped into at most 64 bins; every bin
/// climbs to its highest neighbour until a local maximum, and the bins reaching the same maximum
/// form its mode (disjoint intervals between minima). Modes holding at least 1% of the voxels,
/// at most `count` of them.
std::vector<HistogramMode> histogram_modes(const ValueHistogram& histogram, int count = 4);

/// "0 (41%), 12 to 40 (35%), 200 to 255 (3%)": modes for messages.
std::string describe_modes(const std::vector<HistogramMode>& modes, bool integral);

}  // namespace dsreg
