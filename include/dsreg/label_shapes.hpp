// dsreg — known partitions of space into labelled regions, to measure the multi-label pipeline
// against the truth (tests, bench/, docs/multi-label.md): the label of every point, and the exact
// distance from any point to the set where given labels meet (an interface for two labels, a
// junction curve or point for three or more).
//
// Shapes (physical units; label 0 outside the ball of radius 10 centred at c = (0.137, −0.241,
// 0.318), off every grid's lattice so that no interface passes through voxel centres; below,
// coordinates are relative to c):
//  * "sectors": the ball cut into three sectors around the tilted axis a = (1, 2, 3)/√14 by
//    half-planes through the axis at azimuths 0°, 110° and 235° (labels 1, 2, 3: dihedral angles
//    110°, 125°, 125°). Interfaces: three half-discs and three spherical lunes; junction curves:
//    the axis (labels 1 2 3) and three half great circles (k, k', 0); junction points: the poles.
//  * "layers": the ball cut by the parallel planes n·x = −3.43 and n·x = 4.57 (n = (2, −1, 2)/3)
//    into labels 1 (below), 2, 3 (above). Interfaces: two discs, two caps and a zone; junction
//    curves: two circles where the planes meet the sphere at 69° and 63°.
//  * "nested": label 2 = the ball of radius 5 centred at (1.5, −1, 0.5) inside label 1 (the rest
//    of the ball of radius 10). Interfaces: two spheres; no junction.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

struct LabelShape {
    std::string name;
    Eigen::Vector3d lower, upper;  ///< a box holding every labelled region
    /// Label of a point (0 outside every region).
    std::function<std::int64_t(const Eigen::Vector3d&)> label;
    /// Distance from a point to the closure of the set where all of `labels` (2 or more,
    /// increasing) meet; +∞ where they do not meet.
    std::function<double(const Eigen::Vector3d&, const std::vector<std::int64_t>&)> distance;
};

/// "sectors", "layers" or "nested"; throws dsreg::Error naming the known ones otherwise.
LabelShape make_label_shape(const std::string& name);
std::vector<std::string> label_shape_names();

/// Gauss digitization at step h, as digitize() does for implicit shapes (volume.hpp conventions):
/// voxel (i,j,k) gets the label of its centre h·(i,j,k) (in the shape's coordinates), over the
/// shape's box with one voxel of background margin; origin = h·(i_min, j_min, k_min). Label
/// indices are the label values (every region is non-empty at a sensible h). Throws
/// dsreg::Error for h ≤ 0 or a grid above 2^30 voxels.
LabelVolume digitize_labels(const LabelShape& shape, double h);

}  // namespace dsreg
