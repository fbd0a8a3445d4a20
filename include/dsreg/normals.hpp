// dsreg — normal vector fields on the digital surface: one unit vector per surfel (third stage).
//
// All fields are oriented outward (from object to background) and are returned as an m×3
// matrix whose row f is the normal of face f of the DigitalSurface.
#pragma once

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// The axis-aligned normal of each surfel.
PointMatrix trivial_normals(const DigitalSurface& surface);

/// Convolved trivial normals: for each surfel, the normalized sum of the trivial normals of the
/// surfels whose centre lies within `radius` (physical units, closed ball) of its centre, itself
/// included. Where opposite sides of a thin plate cancel out exactly, the trivial normal is kept.
/// Cost: O(m log m + m·r²/h²) (centres binned into cells of side r). Throws dsreg::Error if
/// radius is not positive and finite.
PointMatrix convolved_trivial_normals(const DigitalSurface& surface, double radius);

/// Integral-invariant normals (Pottmann et al.; the paper's ref. [5]): for each surfel centre c,
/// the covariance matrix of the centres of the object voxels whose centre lies in the ball
/// B_r(c) (radius in physical units). The normal is the eigenvector of its smallest eigenvalue,
/// oriented from the centroid of those voxels towards c. Cost: O(r²/h²) per surfel (the ball is
/// cut into voxel rows, each row summed in closed form over its runs of object voxels).
/// Throws dsreg::Error if radius is not positive and finite.
PointMatrix integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface, double radius);

/// Ground truth for digitized implicit shapes: the true normal ∇F/|∇F| at the closest point of
/// {F = 0} to each surfel centre (positions in the shape's physical coordinates).
PointMatrix exact_normals(const ImplicitShape& shape, const DigitalSurface& surface);

}  // namespace dsreg
