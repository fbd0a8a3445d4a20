// dsreg — correction of the systematic shift of a regularized surface along its normals.
//
// The alignment term of the regularization (eq. 1) is a sum of squared edge lengths projected on
// u, so a part that shrinks lowers it: the minimizer ends up inside the digital surface, by an
// amount that the data term α alone holds back (on goursat at h = 0.25 the mesh is 0.05 h inside,
// on a leopold arm 0.2 h). A Gauss digitization is not biased that way: the surfel centres lie,
// on average over a few voxels, on the true surface. So the correction measures, per face, how far
// the regularized surface moved along u from the surfel centre (the surfel's mean point), against
// the mean over the quad of the smooth surface through its corners: its centroid plus two thirds
// of the sagitta that the curvature between the neighbouring faces gives (the centroid lies
// inside a convex surface by the sagitta, 0.08 voxel on a tube 1.5 voxels in radius; the apex of
// the patch, the full sagitta, lies beyond its mean and made small round objects shrink),
// averages that offset over the surface (a low-pass filter: repeated averaging with the
// four edge-adjacent faces, which keeps the removal of the staircase, a pattern of one or two
// voxels, and takes only the drift), and moves every vertex back along its normal by the mean of
// its faces' averaged offsets.
//
// The average's width trades noise for locality. The offsets carry the staircase's residue, which
// the 40-step average (about 6 faces around) leaves as a ripple of a few thousandths of a voxel,
// enough to tilt the faces of a smooth surface by tenths of a degree; a wider average removes it
// but spreads a drift that varies (at an edge, on a small part) over regions that do not share
// it. So a wide average is taken where it agrees with the narrow one: the narrow average
// soft-thresholded towards the wide one, wide + sign(d)·max(0, |d| − τ) with d = narrow − wide,
// so that a difference at the level of the ripple (τ) is no evidence of a varying drift
// (docs/accuracy.md, "A wide shrink average where the drift agrees").
#pragma once

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

struct ShrinkCorrection {
    PointMatrix positions;   ///< the corrected vertices
    double mean_shift = 0;   ///< mean |shift| of the vertices (physical units)
    double max_shift = 0;    ///< largest |shift|
};

/// How the drift is averaged (steps: each spreads the average by one face).
struct ShrinkAveraging {
    int steps = 40;  ///< the narrow average; 0: no correction
    /// The wide average, taken where it agrees with the narrow one within `wide_tolerance` (see
    /// above); at most `steps`: none.
    int wide_steps = 160;
    double wide_tolerance = 0.01;  ///< τ, in units of the grid's smallest spacing
    /// Empty, or one value in [0, 1] per face: blends each face's averaged offset towards its
    /// average over `local_steps` (< steps) instead: where a thin tube's drift is not uniform
    /// around it (its convex outer side drifts in further than its inner side), the narrow
    /// average, which spans the tube's whole circumference, takes only the mean (docs/accuracy.md,
    /// "Local shrink on thin tubes").
    Eigen::VectorXd local_share;
    int local_steps = 0;
};

/// `positions`: the regularized vertices of `surface`; `normals`: its field u (one unit vector
/// per face). The vertex normal is the normalized sum of u over the vertex's faces; offsets and
/// shifts are in the units of the positions. Throws dsreg::Error for sizes that do not match the
/// surface, a negative step count or a negative or non-finite tolerance.
ShrinkCorrection correct_shrink(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals,
                                const ShrinkAveraging& averaging);

}  // namespace dsreg
