// The local reach of the object and of the background at each surfel, along rays through the
// distance maps, and the local thickness at a voxel (include/dsreg/local_reach.hpp).
#include "dsreg/local_reach.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "dsreg/distance_transform.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

constexpr double kStepsPerVoxel = 16;  // stored distances: 1/16 of the smallest spacing

/// A length in steps of the maps, rounded down. Lengths between voxel centres are often whole
/// steps (3 voxels: 48), which the round-off of the spacing (a float32 affine) puts on either side
/// of the integer: a length within 1e-3 step below a whole number counts as that number (the
/// round-off is below 1e-4 step up to 4000 voxels), so that the reach and every comparison with
/// it are the same for spacings that differ by round-off.
std::int64_t length_in_steps(const ReachMaps& maps, double length) {
    return std::int64_t(std::floor(length / maps.unit + 1e-3));
}

/// Whether the ball of radius `steps` (stored distance) centred at a voxel centre contains a
/// point at `squared_length` (physical, squared) from it, strictly: whether the length in steps
/// (length_in_steps) is below `steps`. For a whole number s, ⌊x + 10⁻³⌋ < s is x < s − 10⁻³, so
/// the test is a comparison of squares, without the root and the division of the length (the
/// inner loop of the rays and of the thickness search).
bool ball_contains(const ReachMaps& maps, std::uint16_t steps, double squared_length) {
    const double radius = (double(steps) - 1e-3) * maps.unit;
    return steps > 0 && squared_length < radius * radius;
}

/// The grown-grid voxel whose box contains the physical point p, or false outside the grown grid.
bool voxel_at(const VoxelGrid& grid, const Eigen::Vector3d& p, Index3& voxel) {
    for (int a = 0; a < 3; ++a) {
        voxel[std::size_t(a)] = std::int64_t(std::floor((p[a] - grid.origin[a]) / grid.spacing[a] + 0.5));
        if (voxel[std::size_t(a)] < 0 || voxel[std::size_t(a)] >= grid.dims[std::size_t(a)]) return false;
    }
    return true;
}

/// The label of map voxel y (0 beyond the volume).
std::uint32_t label_at(const VoxelLabels& volume, const ReachMaps& maps, const Index3& y) {
    const Index3 v = maps.volume_voxel(y);
    return volume.at(v[0], v[1], v[2]);
}

/// The reach along one ray from `from` (local_reach.hpp) through the voxels of `label`, `anchor`
/// the voxel centre the balls must contain.
double reach_along(const VoxelLabels& volume, const ReachMaps& maps, std::uint32_t label, const Eigen::Vector3d& from,
                   const Eigen::Vector3d& direction, const Eigen::Vector3d& anchor) {
    const double step = 0.5 * maps.grid.spacing.minCoeff();
    double best = maps.grid.spacing.minCoeff();
    Index3 previous{-1, -1, -1};
    for (double t = 0.5 * step; t <= maps.cap; t += step) {
        Index3 y;
        if (!voxel_at(maps.grid, from + t * direction, y)) break;
        if (y == previous) continue;  // half-voxel steps: the same voxel, the same test
        previous = y;
        if (label_at(volume, maps, y) != label) break;
        const std::uint16_t steps = maps.distance[std::size_t(maps.grid.linear_index(y[0], y[1], y[2]))];
        if (maps.unit * steps > best &&
            ball_contains(maps, steps, (maps.grid.voxel_center(y[0], y[1], y[2]) - anchor).squaredNorm()))
            best = maps.unit * steps;
        if (best >= maps.cap) break;
    }
    return std::min(best, maps.cap);
}

std::uint16_t stored_distance(const ReachMaps& maps, float distance) {
    const std::int64_t largest = std::numeric_limits<std::uint16_t>::max();
    return std::uint16_t(std::min(largest, length_in_steps(maps, distance)));
}

/// Bounding boxes [lo, hi] of the voxels of every label index (index 0 unused); hi < lo where absent.
using LabelBoxes = std::vector<std::array<Index3, 2>>;

void grow_box(LabelBoxes& boxes, std::uint32_t l, const Index3& lo, const Index3& hi, const Index3& dims) {
    if (l >= boxes.size()) boxes.resize(l + 1, {dims, Index3{-1, -1, -1}});
    for (std::size_t a = 0; a < 3; ++a) {
        boxes[l][0][a] = std::min(boxes[l][0][a], lo[a]);
        boxes[l][1][a] = std::max(boxes[l][1][a], hi[a]);
    }
}

LabelBoxes label_boxes(const VoxelLabels& volume) {
    const Index3& d = volume.grid().dims;
    std::vector<LabelBoxes> per_slice(static_cast<std::size_t>(d[2]));  // one slice k each, merged below
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < d[2]; ++k)
        for (std::int64_t j = 0; j < d[1]; ++j) {
            const std::int64_t row = volume.grid().linear_index(0, j, k);
            for (std::int64_t i = 0; i < d[0]; ++i) {
                const std::uint32_t l = volume.at_linear(row + i);
                if (l == 0) continue;
                std::int64_t last = i;  // the run of label l from i
                while (last + 1 < d[0] && volume.at_linear(row + last + 1) == l) ++last;
                grow_box(per_slice[std::size_t(k)], l, {i, j, k}, {last, j, k}, d);
                i = last;
            }
        }
    LabelBoxes boxes;
    for (const LabelBoxes& slice : per_slice)
        for (std::uint32_t l = 1; l < slice.size(); ++l)
            if (slice[l][1][0] >= 0) grow_box(boxes, l, slice[l][0], slice[l][1], d);
    return boxes;
}

/// Voxels lo..hi (inclusive) of `volume` as a binary volume placed in its physical frame: a voxel
/// is set where keep(its label).
template <class Keep>
BinaryVolume cropped_indicator(const VoxelLabels& volume, const Index3& lo, const Index3& hi, Keep keep) {
    BinaryVolume crop;
    crop.grid = volume.grid();
    for (std::size_t a = 0; a < 3; ++a) {
        crop.grid.dims[a] = hi[a] - lo[a] + 1;
        crop.grid.origin[Eigen::Index(a)] += double(lo[a]) * crop.grid.spacing[Eigen::Index(a)];
    }
    crop.mask.resize(std::size_t(crop.grid.voxel_count()));
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < crop.grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < crop.grid.dims[1]; ++j) {
            const std::int64_t from = volume.grid().linear_index(lo[0], lo[1] + j, lo[2] + k);
            std::uint8_t* to = crop.mask.data() + crop.grid.linear_index(0, j, k);
            for (std::int64_t i = 0; i < crop.grid.dims[0]; ++i) to[i] = keep(volume.at_linear(from + i)) ? 1 : 0;
        }
    return crop;
}

/// D to the other labels on the voxels of label l ≥ 1: the distance transform of its indicator
/// on its bounding box grown by one voxel (clipped to the grid, whose outside counts as another
/// label). One voxel is enough, and gives the distances of the whole grid exactly: the nearest
/// voxel y of another label to a voxel x of l, clamped onto the grown box, is a voxel outside
/// the bounding box (so of another label) no farther from x.
void fill_label_distances(const VoxelLabels& volume, std::uint32_t l, const std::array<Index3, 2>& box, double saturation,
                          ReachMaps& maps) {
    Index3 lo, hi;
    for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = std::max<std::int64_t>(0, box[0][a] - 1);
        hi[a] = std::min<std::int64_t>(volume.grid().dims[a] - 1, box[1][a] + 1);
    }
    const BinaryVolume crop = cropped_indicator(volume, lo, hi, [l](std::uint32_t label) { return label == l; });
    const std::vector<float> distance = euclidean_distance_transform(crop, DistanceTarget::background, saturation);
#pragma omp parallel for schedule(static)
    for (std::int64_t k = 0; k < crop.grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < crop.grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < crop.grid.dims[0]; ++i) {
                const std::int64_t c = crop.grid.linear_index(i, j, k);
                if (!crop.mask[std::size_t(c)]) continue;
                const Index3 y = maps.map_voxel({lo[0] + i, lo[1] + j, lo[2] + k});
                const std::int64_t g = maps.grid.linear_index(y[0], y[1], y[2]);
                maps.distance[std::size_t(g)] = stored_distance(maps, distance[std::size_t(c)]);
            }
}

/// The union of the label boxes (index 0 unused; a box with hi < lo absent), hi < lo if none.
std::array<Index3, 2> union_box(const LabelBoxes& boxes) {
    constexpr std::int64_t kLarge = std::numeric_limits<std::int64_t>::max();
    std::array<Index3, 2> box{Index3{kLarge, kLarge, kLarge}, Index3{-1, -1, -1}};
    for (std::size_t l = 1; l < boxes.size(); ++l)
        if (boxes[l][1][0] >= 0)
            for (std::size_t a = 0; a < 3; ++a) {
                box[0][a] = std::min(box[0][a], boxes[l][0][a]);
                box[1][a] = std::max(box[1][a], boxes[l][1][a]);
            }
    return box;
}

/// The labelled voxels (any label) of `box` as a binary volume placed in the volume's physical
/// frame, or nothing when the box grown by `padding` would hold more than kCropAbove of the grown
/// grid's voxels (the copy would cost more than it saves), or is empty.
constexpr double kCropAbove = 0.7;
std::optional<BinaryVolume> labelled_box(const VoxelLabels& volume, const std::array<Index3, 2>& box, std::int64_t padding) {
    const Index3& d = volume.grid().dims;
    if (box[1][0] < 0) return std::nullopt;
    double box_voxels = 1, grid_voxels = 1;
    for (std::size_t a = 0; a < 3; ++a) {
        box_voxels *= double(box[1][a] - box[0][a] + 1 + 2 * padding);
        grid_voxels *= double(d[a] + 2 * padding);
    }
    if (box_voxels > kCropAbove * grid_voxels) return std::nullopt;
    return cropped_indicator(volume, box[0], box[1], [](std::uint32_t label) { return label != 0; });
}

}  // namespace

ReachMaps reach_maps(const VoxelLabels& volume, double cap) {
    if (!(cap > 0) || !std::isfinite(cap)) throw Error("reach maps: the cap must be positive and finite");
    const VoxelGrid& grid = volume.grid();
    ReachMaps maps;
    maps.unit = grid.spacing.minCoeff() / kStepsPerVoxel;
    if (cap / maps.unit > 0.5 * std::numeric_limits<std::uint16_t>::max())
        throw Error("reach maps: a cap of " + std::to_string(cap) + " spans too many voxels");
    maps.cap = cap;
    maps.padding = std::int64_t(std::ceil(cap / grid.spacing.minCoeff())) + 1;
    // Every length compared with a distance of the maps is below √3·(cap + one voxel) (the corners
    // of half_local_thickness's box), so distances saturated above this compare the same.
    const double saturation = 2.0 * (cap + grid.spacing.maxCoeff());
    const LabelBoxes boxes = label_boxes(volume);
    {
        // The background (label 0, the padding included): D to the nearest labelled voxel; on a
        // binary volume, whose one label is the object, its voxels' D to the background too.
        // On the labelled voxels' box only, when it is much smaller than the grid: beyond it is
        // background.
        const DistanceTarget target = volume.is_binary() ? DistanceTarget::other_kind : DistanceTarget::object;
        const std::array<Index3, 2> labelled = union_box(boxes);
        const std::optional<BinaryVolume> box = labelled_box(volume, labelled, maps.padding);
        if (box) maps.first = labelled[0];
        const PaddedDistanceMap map =
            padded_distance_transform(box ? VoxelLabels(*box) : volume, target, maps.padding, saturation);
        maps.grid = map.grid;
        maps.distance.resize(map.distance.size());
        const auto voxels = static_cast<std::int64_t>(map.distance.size());
#pragma omp parallel for schedule(static)
        for (std::int64_t v = 0; v < voxels; ++v) {
            const float distance = map.distance[std::size_t(v)];
            maps.distance[std::size_t(v)] = distance > 0 ? stored_distance(maps, distance) : 0;
        }
    }
    if (volume.is_binary()) return maps;
    // Every label: D to the nearest voxel of another label (the background included).
    for (std::uint32_t l = 1; l < boxes.size(); ++l)
        if (boxes[l][1][0] >= 0) fill_label_distances(volume, l, boxes[l], saturation, maps);
    return maps;
}

SurfelReach surfel_reach(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         const ReachMaps& maps) {
    if (directions.rows() != surface.face_count())
        throw Error("surfel_reach: one direction per surfel expected (got " + std::to_string(directions.rows()) +
                    " for " + std::to_string(surface.face_count()) + " surfels)");
    SurfelReach reach;
    reach.inner.resize(surface.face_count());
    reach.outer.resize(surface.face_count());
    const VoxelGrid& grid = volume.grid();
#pragma omp parallel for schedule(dynamic, 1024)
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        const Eigen::Vector3d v = grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        Eigen::Vector3d w = v, c = v;
        w[s.axis] += s.sign * grid.spacing[s.axis];
        c[s.axis] += 0.5 * s.sign * grid.spacing[s.axis];
        const Eigen::Vector3d n = directions.row(f).transpose();
        const FaceLabels labels = surface.face_labels.empty() ? FaceLabels{1, 0} : surface.face_labels[std::size_t(f)];
        reach.inner[f] = reach_along(volume, maps, labels.inner, c, -n, v);
        reach.outer[f] = reach_along(volume, maps, labels.outer, c, n, w);
    }
    return reach;
}

SurfelReach surfel_reach(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap) {
    return surfel_reach(volume, surface, directions, reach_maps(volume, cap));
}

double half_local_thickness(const VoxelLabels& volume, const ReachMaps& maps, const Index3& v, double limit) {
    limit = std::min(limit, maps.cap);
    const std::uint32_t kind = volume.at(v[0], v[1], v[2]);
    const Eigen::Vector3d& s = maps.grid.spacing;
    const Index3 centre = maps.map_voxel(v);
    Index3 reach;  // a ball of radius ≤ limit containing v has its centre within limit of v
    for (int a = 0; a < 3; ++a) reach[std::size_t(a)] = std::int64_t(std::ceil(limit / s[a]));
    // The result is the largest min(D(y), limit) over the balls that contain v, whatever the
    // order: the offsets are taken from the centre out (0, −1, 1, −2, 2, …), so that large balls
    // come first and most voxels are passed over on their distance alone.
    const auto offset = [](std::int64_t n) { return n % 2 == 0 ? n / 2 : -(n + 1) / 2; };
    double best = 0;
    for (std::int64_t nk = 0; nk <= 2 * reach[2]; ++nk) {
        const std::int64_t k = centre[2] + offset(nk);
        for (std::int64_t nj = 0; nj <= 2 * reach[1]; ++nj) {
            const std::int64_t j = centre[1] + offset(nj);
            for (std::int64_t ni = 0; ni <= 2 * reach[0]; ++ni) {
                const std::int64_t i = centre[0] + offset(ni);
                if (!maps.grid.contains(i, j, k)) continue;
                const std::uint16_t steps = maps.distance[std::size_t(maps.grid.linear_index(i, j, k))];
                const double d = maps.unit * steps;
                if (d <= best || label_at(volume, maps, {i, j, k}) != kind) continue;
                const Eigen::Vector3d to_v(double(i - centre[0]) * s.x(), double(j - centre[1]) * s.y(),
                                           double(k - centre[2]) * s.z());
                if (ball_contains(maps, steps, to_v.squaredNorm())) best = std::min(d, limit);
                if (best >= limit) return limit;
            }
        }
    }
    return best;
}

Eigen::VectorXd max_over_rings(const DigitalSurface& surface, Eigen::VectorXd values, int rings) {
    for (int ring = 0; ring < rings; ++ring) {
        Eigen::VectorXd next = values;
#pragma omp parallel for schedule(static)
        for (std::int64_t f = 0; f < surface.face_count(); ++f)
            for (int e = 0; e < 4; ++e) next[f] = std::max(next[f], values[surface.adjacent_face(f, e)]);
        values.swap(next);
    }
    return values;
}

}  // namespace dsreg
