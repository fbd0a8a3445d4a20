// dsreg — integral-invariant normals whose radius follows the object (third stage).
//
// A fixed integral-invariant (II) radius cannot serve both the thin parts of an object and its
// thick smooth parts: where the ball reaches across a part thinner than itself (a tube, a plate,
// a narrow gap of background) it sees both sides and the normal is wrong; where the object is
// thick and smooth a larger ball averages out more digitization noise. Here every surfel gets
// its own radius: no larger than the local reach of the object and of the background at the
// surfel (from Euclidean distance transforms), as large as `max_radius` elsewhere.
// docs/accuracy.md gives the measurements behind every choice and default.
#pragma once

#include <Eigen/Core>

#include "dsreg/digital_surface.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

/// Local reach of the object and of the background at every surfel, physical units. With c the
/// surfel centre, n its (outward) direction, v its object voxel and w its background voxel:
///  * inner reach: the largest D_bg(y) over the centres y of the object voxels met by the ray
///    c − t·n (t ≥ 0, until it leaves the object) such that |y − v| < D_bg(y), D_bg being the
///    distance to the nearest background voxel centre: the radius of the largest ball centred
///    on the inward ray that holds only object voxel centres and contains v;
///  * outer reach: the same for the background, along c + t·n, containing w.
/// Both are at most `cap` (rays stop there) and at least the spacing (the radius of the voxel's
/// own ball). So each is at most half the local thickness (the diameter of the largest such
/// ball containing v, resp. w) of the object, resp. of the background.
struct SurfelReach {
    Eigen::VectorXd inner, outer;
};
SurfelReach surfel_reach(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& directions,
                         double cap);

struct AdaptiveNormalOptions {
    double max_radius = 0;      ///< physical units: the radius where the object is thick
    double min_radius = 0;      ///< physical units: floor of the radius (thinnest parts)
    double reach_factor = 1.0;  ///< r ≤ reach_factor · min(inner, outer reach)
    int reach_passes = 1;       ///< reach recomputed along the adapted field this many more times
    int levels_per_octave = 4;  ///< radii are rounded down to max_radius·2^(−l/levels_per_octave)
    bool extrapolate = false;   ///< Richardson: 2·n(r/√2) − n(r) where r ≥ extrapolation_min_radius
    double extrapolation_min_radius = 0;      ///< physical units
    double extrapolation_agreement_deg = 30;  ///< faces whose two scales differ more keep n(r/√2)
    double extrapolation_threshold_deg = 0;   ///< soft threshold on the correction: below it, n(r)
    IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight;
};

struct AdaptiveNormalField {
    PointMatrix normals;    ///< m×3, outward unit normals
    Eigen::VectorXd radius;  ///< the II radius each surfel used (physical units; the wider one if extrapolated)
    SurfelReach reach;      ///< the reach the radii were chosen from
};

/// The adaptive field. Throws dsreg::Error for radii that are not positive and finite or with
/// min_radius > max_radius.
AdaptiveNormalField adaptive_integral_invariant_normals(const BinaryVolume& volume, const DigitalSurface& surface,
                                                        const AdaptiveNormalOptions& options);

}  // namespace dsreg
