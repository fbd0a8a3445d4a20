// dsreg — histograms of a volume file's values, and their main modes.
#include "dsreg/value_histogram.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dsreg/text.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace {

/// Counts an integer `value` in counts[value − min] (min already lowered to it if need be, the
/// counts of the previous minimum `old_min` shifted up), or gives the counts up when the values
/// stop being integers or span more than `limit`.
void count_exactly(std::vector<std::int64_t>& counts, double value, double old_min, double min, double max, bool integral,
                   std::int64_t limit) {
    if (!integral || max - min + 1 > double(limit)) {
        counts.clear();
        counts.shrink_to_fit();
        return;
    }
    if (min < old_min) counts.insert(counts.begin(), std::size_t(old_min - min), 0);
    const auto size = std::size_t(max - min + 1);
    if (counts.size() < size) counts.resize(size, 0);
    ++counts[std::size_t(value - min)];
}

}  // namespace

void ValueHistogram::add(double value) {
    if (last_slot >= 0 && value == last_value) {  // the same value again: the same slot, nothing else changes
        if (!bins.empty()) {
            ++bins[static_cast<std::size_t>(last_slot)];
            return;
        }
        ++count;
        if (!exact_counts.empty()) ++exact_counts[static_cast<std::size_t>(last_slot)];
        return;
    }
    if (std::isnan(value)) return;
    last_value = value;
    if (bins.empty()) {
        if (count == 0) min = max = value;
        const double old_min = min;
        const bool counting = count == 0 || !exact_counts.empty();
        min = std::min(min, value);
        max = std::max(max, value);
        integral = integral && value == std::floor(value);
        ++count;
        if (counting) count_exactly(exact_counts, value, old_min, min, max, integral, exact_limit);
        last_slot = exact_counts.empty() ? 0 : static_cast<std::int64_t>(value - min);
        return;
    }
    const double position = (value - min) / bin_width;
    const auto last = static_cast<std::int64_t>(bins.size()) - 1;
    last_slot = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(position)), 0, last);
    ++bins[static_cast<std::size_t>(last_slot)];
}

ValueHistogram read_value_histogram(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                                    int max_bins) {
    using volume_io_detail::VoxelDestination;
    ValueHistogram histogram;
    histogram.exact_limit = max_bins;
    {
        VoxelDestination range = VoxelDestination::statistics(histogram);
        volume_io_detail::read_volume_voxels(path, raw_layout, limits, range);
    }
    if (histogram.count == 0) return histogram;
    const double span = histogram.max - histogram.min;
    const bool one_per_value = histogram.integral && span + 1 <= max_bins;
    if (one_per_value && histogram.exact_counts.size() == std::size_t(span + 1)) {  // counted in the first pass
        histogram.bins.swap(histogram.exact_counts);
        return histogram;
    }
    histogram.exact_counts.clear();
    const std::size_t bins = one_per_value ? static_cast<std::size_t>(span + 1) : static_cast<std::size_t>(std::max(1, max_bins));
    histogram.bin_width = one_per_value ? 1.0 : std::max(span / double(bins), std::numeric_limits<double>::min());
    histogram.bins.assign(bins, 0);
    histogram.last_slot = -1;  // the slots of the first pass were those of exact_counts
    VoxelDestination counts = VoxelDestination::statistics(histogram);
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, counts);
    return histogram;
}

std::vector<HistogramMode> histogram_modes(const ValueHistogram& histogram, int count) {
    std::vector<HistogramMode> modes;
    if (histogram.bins.empty() || histogram.count == 0) return modes;
    // Regroup into at most 64 bins of `group` original bins each.
    const std::size_t group = (histogram.bins.size() + 63) / 64;
    std::vector<std::int64_t> coarse((histogram.bins.size() + group - 1) / group, 0);
    for (std::size_t b = 0; b < histogram.bins.size(); ++b) coarse[b / group] += histogram.bins[b];
    const auto total = static_cast<double>(histogram.count);
    // The values a mode spans: from its first to its last non-empty original bin.
    const auto value_of = [&](std::size_t b, bool upper) {
        const double low = histogram.min + double(b) * histogram.bin_width;
        if (histogram.integral && histogram.bin_width == 1.0) return low;  // one bin per integer value
        return upper ? std::min(low + histogram.bin_width, histogram.max) : low;
    };
    const auto span = [&](std::size_t first_coarse, std::size_t last_coarse) {
        std::size_t first = first_coarse * group, last = std::min((last_coarse + 1) * group, histogram.bins.size()) - 1;
        while (first < last && histogram.bins[first] == 0) ++first;
        while (last > first && histogram.bins[last] == 0) --last;
        return std::make_pair(value_of(first, false), value_of(last, true));
    };
    // Each non-empty bin climbs to its highest neighbour until a peak: the bins reaching one
    // peak (an interval between two minima) form its mode, so the modes do not overlap.
    const auto peak_of = [&](std::size_t c) {
        while (true) {
            const std::int64_t left = c > 0 ? coarse[c - 1] : -1, right = c + 1 < coarse.size() ? coarse[c + 1] : -1;
            if (right > coarse[c] && right >= left)
                ++c;
            else if (left > coarse[c])
                --c;
            else
                return c;
        }
    };
    std::size_t c = 0;
    while (c < coarse.size()) {
        if (coarse[c] == 0) {
            ++c;
            continue;
        }
        const std::size_t peak = peak_of(c), first = c;
        std::int64_t held = 0;
        while (c < coarse.size() && coarse[c] > 0 && peak_of(c) == peak) held += coarse[c++];
        if (double(held) >= 0.01 * total) {
            const auto [low, high] = span(first, c - 1);
            modes.push_back({low, high, double(held) / total});
        }
    }
    std::sort(modes.begin(), modes.end(), [](const HistogramMode& a, const HistogramMode& b) { return a.fraction > b.fraction; });
    if (static_cast<int>(modes.size()) > count) modes.resize(static_cast<std::size_t>(std::max(count, 0)));
    return modes;
}

std::string describe_modes(const std::vector<HistogramMode>& modes, bool integral) {
    std::string text;
    for (const HistogramMode& mode : modes) {
        const char* number = integral ? "%.0f" : "%.4g";
        std::string range = format(number, mode.low);
        if (mode.high != mode.low) range += " to " + format(number, mode.high);
        text += (text.empty() ? "" : ", ") + range + " (" + format("%.0f", 100 * mode.fraction) + "%)";
    }
    return text;
}

}  // namespace dsreg
