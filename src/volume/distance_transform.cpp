// Exact Euclidean distance transform by 1D lower envelopes of parabolas, one axis at a time:
// after the pass along x, d(p) = min_q f(q) + s_x²(p_x − q_x)² over the row of p; the passes
// along y and z add the other two squared terms, so the result is the squared distance to the
// nearest target over the whole grid. Targets outside the grid (the background beyond the
// border) enter every pass as one extra site with value 0 at index −1 and at index n.
#include "dsreg/distance_transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// The squared distances along one line: out[p] = min(limit, min_q (in[q] + w·(p − q)²)) over the
/// n samples of `in` and, with `border_sites`, over q = −1 and q = n with value 0. Work space:
/// site, value, boundary.
void lower_envelope(const double* in, double* out, std::int64_t n, double w, bool border_sites, double limit,
                    std::vector<double>& site, std::vector<double>& value, std::vector<double>& boundary) {
    // Sites are indices q with in[q] < limit (plus the two border sites): one at or above the
    // limit puts no value below it anywhere. boundary[k] is where parabola k starts to be the lowest.
    std::int64_t k = -1;
    const auto intersection = [&](double q, double fq, std::int64_t j) {
        return ((fq + w * q * q) - (value[std::size_t(j)] + w * site[std::size_t(j)] * site[std::size_t(j)])) /
               (2.0 * w * (q - site[std::size_t(j)]));
    };
    const auto push = [&](double q, double fq) {
        double s = -kInfinity;
        while (k >= 0) {
            s = intersection(q, fq, k);
            if (s > boundary[std::size_t(k)]) break;
            --k;
        }
        ++k;
        site[std::size_t(k)] = q;
        value[std::size_t(k)] = fq;
        boundary[std::size_t(k)] = k == 0 ? -kInfinity : s;
    };
    // Inside a run of targets (value 0) only the run's two ends can be nearest to a point beyond
    // it, and the points of the run are at 0: the run enters as its two ends (the other sites are
    // strictly farther from every point where they would count, so the values are the same).
    const auto interior_target = [&](std::int64_t q) {
        const bool before = q > 0 ? in[q - 1] == 0 : border_sites;
        const bool after = q + 1 < n ? in[q + 1] == 0 : border_sites;
        return in[q] == 0 && before && after;
    };
    if (border_sites) push(-1.0, 0.0);
    for (std::int64_t q = 0; q < n; ++q)
        if (in[q] < limit && !interior_target(q)) push(double(q), in[q]);
    if (border_sites) push(double(n), 0.0);
    if (k < 0) {
        for (std::int64_t p = 0; p < n; ++p) out[p] = limit;
        return;
    }
    std::int64_t j = 0;
    for (std::int64_t p = 0; p < n; ++p) {
        while (j < k && boundary[std::size_t(j + 1)] < double(p)) ++j;
        const double d = double(p) - site[std::size_t(j)];
        out[p] = in[p] == 0 ? 0.0 : std::min(limit, value[std::size_t(j)] + w * d * d);  // in may be out
    }
}

/// The first pass, along x, on the initial values, which are binary (a target 0, the others
/// ±limit): the lower envelope of parabolas of value 0 is that of the nearest target, so two
/// sweeps give each voxel its nearest target along the line and the value w·d² the envelope gives
/// (the same double expression, capped the same; limit where the line holds no target). Kind 1
/// voxels take the background as target, the border included: object voxels of other_kind
/// (negative) and the non-targets of DistanceTarget::background; kind 0 voxels take the object, no
/// border: background voxels of other_kind and the non-targets of DistanceTarget::object.
void binary_line(double* line, std::int64_t n, double w, DistanceTarget target, double limit, std::vector<double>& before) {
    constexpr double kFar = std::numeric_limits<double>::infinity();
    const bool two_kinds = target == DistanceTarget::other_kind;
    const auto kind_of = [&](std::int64_t q) { return two_kinds ? int(std::signbit(line[q])) : int(target == DistanceTarget::background); };
    const auto is_target_of = [&](std::int64_t q, int kind) { return two_kinds ? int(std::signbit(line[q])) != kind : line[q] == 0; };
    double last[2] = {-kFar, -1.0};  // the last target of each kind so far; kind 1 sees the border at −1
    before.resize(std::size_t(n));
    for (std::int64_t q = 0; q < n; ++q) {
        for (int kind = 0; kind < 2; ++kind)
            if (is_target_of(q, kind)) last[kind] = double(q);
        before[std::size_t(q)] = double(q) - last[kind_of(q)];
    }
    double next[2] = {kFar, double(n)};
    for (std::int64_t q = n - 1; q >= 0; --q) {
        for (int kind = 0; kind < 2; ++kind)
            if (is_target_of(q, kind)) next[kind] = double(q);
        const int kind = kind_of(q);
        const double d = std::min(before[std::size_t(q)], next[kind] - double(q));
        const double squared = std::min(limit, w * d * d);  // 0 on a target, limit where there is none
        line[q] = two_kinds && kind == 1 ? -squared : squared;
    }
}

/// Lines gathered together in a pass along y or z: consecutive lines along x, so that every
/// cache line read from the volume serves them all (one line at a stride of nx or nx·ny floats
/// would use 4 bytes of each 64-byte cache line).
constexpr std::int64_t kLinesPerTile = 16;

/// Two envelopes for DistanceTarget::other_kind, whose values carry the voxel's kind in their sign
/// (object voxels negative): the object voxels' squared distances to the background (the
/// background voxels its sites of value 0, the border too), the background voxels' to the object.
/// A voxel's own value is never 0 (the other kind is a voxel away at least), so the sign survives.
void two_sided_envelope(double* line, double* to_background, double* to_object, std::int64_t n, double w, double limit,
                        std::vector<double>& site, std::vector<double>& value, std::vector<double>& boundary) {
    bool objects = false, backgrounds = false;
    for (std::int64_t p = 0; p < n; ++p) {
        const bool object = std::signbit(line[p]);
        to_background[p] = object ? -line[p] : 0.0;
        to_object[p] = object ? 0.0 : line[p];
        (object ? objects : backgrounds) = true;
    }
    // A line of one kind keeps the zeros of the other kind's transform.
    if (objects) lower_envelope(to_background, to_background, n, w, true, limit, site, value, boundary);
    if (backgrounds) lower_envelope(to_object, to_object, n, w, false, limit, site, value, boundary);
    for (std::int64_t p = 0; p < n; ++p) line[p] = std::signbit(line[p]) ? -to_background[p] : to_object[p];
}

/// One pass along `axis` over every line of the grid, in place on `squared`. Along y and z, the
/// lines are taken in tiles of kLinesPerTile neighbours along x, copied to contiguous work space.
/// `initial_values`: the volume's binary values, not yet passed along any axis (binary_line).
void pass_along(std::vector<float>& squared, const VoxelGrid& grid, int axis, DistanceTarget target, double limit,
                bool initial_values) {
    const Index3& d = grid.dims;
    const std::int64_t n = d[std::size_t(axis)];
    const std::int64_t stride = axis == 0 ? 1 : axis == 1 ? d[0] : d[0] * d[1];
    const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;  // the two other axes; a1 = x unless axis = x
    const std::int64_t width = axis == 0 ? 1 : kLinesPerTile;  // lines per tile, neighbours along a1
    const std::int64_t tiles_across = (d[std::size_t(a1)] + width - 1) / width;
    const std::int64_t tiles = tiles_across * d[std::size_t(a2)];
    const double w = grid.spacing[axis] * grid.spacing[axis];
#pragma omp parallel
    {
        const auto length = static_cast<std::size_t>(n);
        std::vector<double> in(length * std::size_t(width)), out(length), other(length), site(length + 2),
            value(length + 2), boundary(length + 2);
#pragma omp for schedule(static)
        for (std::int64_t tile = 0; tile < tiles; ++tile) {
            Index3 start{0, 0, 0};
            start[std::size_t(a1)] = (tile % tiles_across) * width;
            start[std::size_t(a2)] = tile / tiles_across;
            const std::int64_t lines = std::min(width, d[std::size_t(a1)] - start[std::size_t(a1)]);
            const std::int64_t first = grid.linear_index(start[0], start[1], start[2]);
            const std::int64_t line_step = axis == 0 ? 0 : 1;  // along x when the tile has several lines
            for (std::int64_t p = 0; p < n; ++p)
                for (std::int64_t l = 0; l < lines; ++l)
                    in[std::size_t(l * n + p)] = squared[std::size_t(first + l * line_step + p * stride)];
            for (std::int64_t l = 0; l < lines; ++l) {
                double* line = in.data() + l * n;
                if (initial_values) {
                    binary_line(line, n, w, target, limit, other);
                    continue;
                }
                if (target == DistanceTarget::other_kind) {
                    two_sided_envelope(line, out.data(), other.data(), n, w, limit, site, value, boundary);
                    continue;
                }
                // The background beyond the grid: border sites of the transform to the background.
                lower_envelope(line, out.data(), n, w, target == DistanceTarget::background, limit, site, value, boundary);
                std::copy(out.begin(), out.end(), line);
            }
            for (std::int64_t p = 0; p < n; ++p)
                for (std::int64_t l = 0; l < lines; ++l)
                    squared[std::size_t(first + l * line_step + p * stride)] = float(in[std::size_t(l * n + p)]);
        }
    }
}

}  // namespace

std::vector<float> euclidean_distance_transform(const BinaryVolume& volume, DistanceTarget target, double cap) {
    return padded_distance_transform(volume, target, 0, cap).distance;
}

PaddedDistanceMap padded_distance_transform(const VoxelLabels& volume, DistanceTarget target, std::int64_t padding,
                                            double cap) {
    if (padding < 0) throw Error("padded_distance_transform: the padding must not be negative");
    if (!(cap > 0)) throw Error("padded_distance_transform: the cap must be positive");
    PaddedDistanceMap map;
    map.padding = padding;
    map.grid = volume.grid();
    for (int a = 0; a < 3; ++a) map.grid.dims[std::size_t(a)] += 2 * padding;
    map.grid.origin -= double(padding) * volume.grid().spacing;
    // Squared distances in place (float: exact for integer squared distances below 2^24),
    // square roots at the end. The padding is background.
    // Capping commutes with every pass (min(cap², f) enveloped is min(cap², envelope of f)), so
    // the cap enters as the value of non-targets, and sites at or above it drop out of the lines.
    // Both kinds for other_kind: an object voxel starts at −cap² (the sign marks its kind).
    const float target_value = 0.0f, other = float(cap * cap);
    const double limit = double(other);
    const auto initial = [&](bool object) {
        switch (target) {
            case DistanceTarget::background: return object ? other : target_value;
            case DistanceTarget::object: return object ? target_value : other;
            case DistanceTarget::other_kind: return object ? -other : other;
        }
        return other;
    };
    map.distance.assign(std::size_t(map.grid.voxel_count()), initial(false));
    const Index3& d = volume.grid().dims;
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j) {
            const std::int64_t first = volume.grid().linear_index(0, j, k);
            float* row = map.distance.data() + map.grid.linear_index(padding, j + padding, k + padding);
            for (std::int64_t i = 0; i < d[0]; ++i) row[i] = initial(volume.at_linear(first + i) != 0);
        }
    for (int axis = 0; axis < 3; ++axis) pass_along(map.distance, map.grid, axis, target, limit, axis == 0);
    const auto voxels = static_cast<std::int64_t>(map.distance.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < voxels; ++v) map.distance[std::size_t(v)] = std::sqrt(std::abs(map.distance[std::size_t(v)]));
    return map;
}

}  // namespace dsreg
