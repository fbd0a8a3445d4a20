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
#pragma once

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

struct ShrinkCorrection {
    PointMatrix positions;   ///< the corrected vertices
    double mean_shift = 0;   ///< mean |shift| of the vertices (physical units)
    double max_shift = 0;    ///< largest |shift|
};

/// `positions`: the regularized vertices of `surface`; `normals`: its field u (one unit vector
/// per face); `steps`: averaging steps (each spreads the average by one face; 0 returns the
/// positions unchanged). The vertex normal is the normalized sum of u over the vertex's faces.
/// `local_share` (empty, or one value in [0, 1] per face) blends each face's averaged offset
/// towards its average over `local_steps` (< steps) instead: where a thin tube's drift is not
/// uniform around it (its convex outer side drifts in further than its inner side), the wide
/// average, which spans the tube's whole circumference, takes only the mean (docs/accuracy.md,
/// "Local shrink on thin tubes"). Throws dsreg::Error for sizes that do not match the surface or a
/// negative step count.
ShrinkCorrection correct_shrink(const DigitalSurface& surface, const PointMatrix& positions, const PointMatrix& normals,
                                int steps, const Eigen::VectorXd& local_share = {}, int local_steps = 0);

}  // namespace dsreg
