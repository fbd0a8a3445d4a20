// dsreg — normal vector fields on the digital surface: one unit vector per surfel (third stage).
//
// All fields are oriented outward (from object to background) and are returned as an m×3
// matrix whose row f is the normal of face f of the DigitalSurface.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// The axis-aligned normal of each surfel.
PointMatrix trivial_normals(const DigitalSurface& surface);

/// The unit vector nearest to u with u·n ≥ margin: u itself if it qualifies, else its tangential
/// direction tilted to u·n = margin (n itself when u = −n). n unit, margin in [0, 1).
Eigen::Vector3d lift_into_half_space(const Eigen::Vector3d& u, const Eigen::Vector3d& n, double margin);

/// What the voxels say of every face's normal: the segment from the centre of the object voxel
/// behind a surfel to the centre of the background voxel in front of it crosses the boundary
/// outwards, so where it crosses the true normal n has n·n_s ≥ 0 (n_s the surfel's trivial
/// normal). Each row u_f with u_f·n_s < margin (an estimate pointing into the object, or almost
/// along the face: noise, parts thinner than the estimator's reach) becomes
/// lift_into_half_space(u_f, n_s, margin); the others are left as they are, bit for bit. Returns
/// how many rows changed. The pipeline does this to the estimated fields with margin 0.05
/// (docs/accuracy.md, "Field lift"): the faces it changes are those that would fold in the solve.
/// Throws dsreg::Error for a field of the wrong size or a margin outside [0, 1).
std::int64_t lift_into_surfel_half_spaces(const DigitalSurface& surface, PointMatrix& normals, double margin);

/// Lifts row f alone, as lift_into_surfel_half_spaces() does; returns whether it changed.
bool lift_into_surfel_half_space(const DigitalSurface& surface, PointMatrix& normals, std::int64_t f, double margin);

/// The faces (ascending) whose field points into the object: u_f·n_s < 0. A good estimate of a
/// clean digitization has almost none (the voxels guarantee n·n_s ≥ 0, see above); where the
/// voxels are noisy, the bumps and pits of flipped voxels give many (about a fifth of the faces
/// of a sphere with a fifth of its boundary voxels flipped). Throws dsreg::Error for a field of
/// the wrong size.
std::vector<std::int32_t> faces_against_their_surfels(const DigitalSurface& surface, const PointMatrix& normals);

enum class IntegralInvariantKernel;

/// Convolved trivial normals: for each surfel, the normalized sum of the trivial normals of the
/// surfels whose centre lies within `radius` (physical units, closed ball) of its centre, itself
/// included, weighted by `kernel` (ball: 1; biweight: (1 − d²/r²)²). On a label complex only the
/// surfels between the same two labels count (the face's own interface). Where opposite sides of
/// a thin plate cancel out exactly, the trivial normal is kept. Cost: O(m log m + m·r²/h²)
/// (centres binned into cells of side r). Throws dsreg::Error if radius is not positive and
/// finite.
PointMatrix convolved_trivial_normals(const DigitalSurface& surface, double radius, IntegralInvariantKernel kernel);
PointMatrix convolved_trivial_normals(const DigitalSurface& surface, double radius);  ///< ball kernel

/// The weight of a voxel of the integral-invariant ball B_r(c), as a function of the distance d
/// of its centre to c.
enum class IntegralInvariantKernel {
    ball,      ///< 1 inside the ball: the paper's integral invariants (indicator of B_r)
    biweight,  ///< (1 − d²/r²)²: smooth, zero on the sphere. Voxels entering or leaving the
               ///< ball no longer jump the moments, and the nearer voxels count more: on goursat
               ///< at h = 0.25, r = 1.89, the field is 0.95° off the true normals instead of 1.32°
               ///< (docs/accuracy.md).
};

/// "ball" / "biweight", and back (throws dsreg::Error naming the accepted names).
std::string kernel_name(IntegralInvariantKernel kernel);
IntegralInvariantKernel parse_integral_invariant_kernel(const std::string& name);

/// Integral-invariant normals (Pottmann et al.; the paper's ref. [5]): for each surfel centre c,
/// the weighted covariance matrix of the centres of the object voxels whose centre lies in the
/// ball B_r(c) (radius in physical units; weights given by `kernel`). The normal is the
/// eigenvector of its smallest eigenvalue λ1, oriented from the weighted centroid of those voxels
/// towards c; where the object is thinner than the ball across two directions (a wire, a bar, a
/// thin tube, an isolated voxel: λ1 ≈ λ2, the eigenvector is any direction of their plane), the
/// unit direction from the centroid to c, blended in linearly as the relative gap (λ2 − λ1)/λ2
/// falls from 0.1 to 0 (a half ball has 0.70). Only the voxels of the face's own part of the
/// object count: voxels joined to its voxel through faces, or through edges and corners where the
/// surface joins them (another fragment a voxel away is not in its ball). Cost: O(r²/h²) per
/// surfel (the ball is cut into voxel rows that carry running sums of the weights; each row is
/// summed over its runs of object voxels with two look-ups per run), plus tables of O(r³/h³)
/// entries. Throws dsreg::Error if radius is not positive and finite, or spans so many voxels
/// (about 100) that the tables would exceed 768 MiB.
PointMatrix integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface, double radius,
                                       IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight);

/// The same on the complex of a label map (extract_digital_surface of `volume`): each face gets
/// the normal of the indicator of its inner label, oriented towards its outer label. One pass
/// over the volume for all labels (runs of equal labels along the rows).
PointMatrix integral_invariant_normals(const LabelVolume& volume, const DigitalSurface& surface, double radius,
                                       IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight);

/// The faces of a label map's complex whose ball B_r(centre) (radius in physical units) holds a
/// voxel of a third label, neither of the face's two (outside the grid is background): the faces
/// within r of a junction. All 0 for a map of one label. O(r²/h²) per face, like the integral
/// invariants (one pass over the volume for the row runs).
std::vector<char> faces_near_junctions(const LabelVolume& volume, const DigitalSurface& surface, double radius);

/// On a label map's complex, replaces the field `normals` of the faces near a junction
/// (faces_near_junctions) by the convolved trivial normals of their own interface (biweight
/// kernel, same radius) and returns how many. The indicator of either label bends where the
/// third one starts, so its integral invariants round the junction off; the faces of the
/// interface itself do not bend there (a flat sheet stays flat up to the junction curve). On the
/// known shapes of label_shapes.hpp this brings the junction vertices 2–3 times closer to the
/// true junction curves (docs/multi-label.md). Leaves a binary complex alone.
std::int64_t use_interface_normals_near_junctions(const LabelVolume& volume, const DigitalSurface& surface, double radius,
                                                  PointMatrix& normals);

/// Integral-invariant normals with their O(r²) bias removed: n = 2·n(r/√2) − n(r), normalized
/// (Richardson extrapolation of integral_invariant_normals to r = 0), except on faces where the
/// two scales disagree by more than 30° (sharp edges, thin parts), which keep n(r/√2). The bias
/// of n(r) comes from the variation of the curvature across the ball and grows like r²; the
/// extrapolation cancels it, so a larger r (less digitization noise) can be afforded: on goursat
/// at h = 0.25, r = 3.5 gives a field 0.52° off the true normals, against 0.95° for the best
/// single scale (docs/accuracy.md). Costs two integral_invariant_normals.
PointMatrix extrapolated_integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface,
                                                    double radius,
                                                    IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight);

/// The same on the complex of a label map (see integral_invariant_normals above).
PointMatrix extrapolated_integral_invariant_normals(const LabelVolume& volume, const DigitalSurface& surface,
                                                    double radius,
                                                    IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight);

/// Ground truth for digitized implicit shapes: the true normal ∇F/|∇F| at the closest point of
/// {F = 0} to each surfel centre (positions in the shape's physical coordinates).
PointMatrix exact_normals(const ImplicitShape& shape, const DigitalSurface& surface);

}  // namespace dsreg
