// dsreg — integral-invariant normals whose radius follows the object (third stage; the default
// field of the pipeline).
//
// A fixed integral-invariant (II) radius cannot serve both the thin parts of an object and its
// thick smooth parts: where the ball reaches across a part thinner than itself (a tube, a plate,
// a narrow gap of background) it sees both sides and the normal is wrong; where the object is
// thick and smooth a larger ball averages out more digitization noise, and two radii remove the
// bias that grows with the radius. So every surfel gets its own radius
//
//     r = min(max_radius, max(min_radius, reach_factor · reach), local thickness),  rounded down
//
// to a level, `reach` being its local reach (local_reach.hpp: the smaller of the object's and the
// background's, measured along a first field and made robust to one-voxel noise) and the local
// thickness that of the object at the surfel's object voxel and of the background at its
// background voxel wherever the reach limits r (so with min_radius ≤ 2 × the smallest spacing, r
// never exceeds it on a part thinner than max_radius; a voxel of noise on a thick part is thin
// itself but keeps the radius of its surroundings), and, where
// r is large enough, the Richardson extrapolation 2·n(r/√2) − n(r) of the II normal, which
// cancels its O(r²) bias; where r is small (thin parts, whose small balls see few voxels and are
// noisy), a few steps of averaging with the adjacent faces, which, unlike a larger ball, never
// reach across the part. docs/accuracy.md gives the measurements behind every default.
#pragma once

#include <Eigen/Core>
#include <memory>

#include "dsreg/digital_surface.hpp"
#include "dsreg/local_reach.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

struct AdaptiveNormalOptions {
    double max_radius = 0;      ///< physical units: the radius where the object is thick
    double min_radius = 0;      ///< physical units: the floor of the radius (the thinnest parts); see above
    double reach_factor = 1.0;  ///< r ≤ reach_factor · reach (where above min_radius)
    int reach_rings = 3;        ///< reach made robust: the largest within this many rings (local_reach.hpp)
    double reach_cap = 0;       ///< the reach is measured up to this (physical); at least max_radius/reach_factor + 1 voxel
    int levels_per_octave = 4;  ///< radii are rounded down to max_radius·2^(−l/levels_per_octave), l ≥ 0
    bool extrapolate = true;    ///< Richardson extrapolation where r ≥ extrapolation_min_radius
    double extrapolation_min_radius = 0;      ///< physical units
    double extrapolation_agreement_deg = 30;  ///< where n(r) and n(r/√2) differ more: keep n(r/√2)
    /// The correction is shrunk by this (soft threshold: a correction at the level of the
    /// digitization noise is no evidence of bias); 0.75° by the accuracy suite (docs/accuracy.md,
    /// "The extrapolation's threshold"): the noise of 2·(n(r/√2) − n(r)) roughened the smooth
    /// surfaces' faces at 0.5°.
    double extrapolation_threshold_deg = 0.75;
    IntegralInvariantKernel kernel = IntegralInvariantKernel::biweight;
    int smoothing_steps = 0;      ///< steps of averaging over the adjacent faces where r < smoothing_below
    double smoothing_below = 0;   ///< physical units
    double smoothing_power = 2;   ///< weight of a neighbour g of f: max(0, u_f·u_g)^power
    /// Noisy thin parts: after the smoothing above, a face with r < smoothing_below gets this
    /// many more steps where the share of faces around it whose normal points against their
    /// surfel (u·n < 0) is at least noisy_share. The share: that indicator averaged with the four
    /// edge-adjacent faces noisy_share_passes times (each pass reaches about one ring further).
    /// On a clean thin part the four steps leave next to no such face; among flipped voxels the
    /// small balls see the noise and only a long average over the surface removes it
    /// (docs/accuracy.md, "Noise on thin parts"). 0 = off.
    int noisy_smoothing_steps = 0;
    double noisy_share = 0.005;
    int noisy_share_passes = 8;
    /// Hand the distance maps of the reach to the caller (AdaptiveNormalField::reach_maps) rather
    /// than free them on return: for a later stage that needs the maps of the same cap (the
    /// pipeline's thin-part weights), which then need not compute them again.
    bool keep_reach_maps = false;
};

struct AdaptiveNormalField {
    PointMatrix normals;     ///< m×3, outward unit normals
    Eigen::VectorXd radius;  ///< the II radius of each surfel (physical; the wider one where extrapolated)
    Eigen::VectorXd extrapolated;  ///< 1 where the field is extrapolated, else 0
    SurfelReach reach;       ///< the robust reach the radii come from
    double reach_cap = 0;    ///< up to which it was measured (physical units)
    std::int64_t noisy_smoothed_faces = 0;  ///< faces given the noisy_smoothing_steps
    /// With AdaptiveNormalOptions::keep_reach_maps: the maps the reach was measured on (their
    /// cap: max(reach_cap, max_radius / 2)); 2 bytes per voxel of the grown grid, to be released
    /// once used.
    std::shared_ptr<const ReachMaps> reach_maps;
};

/// The adaptive field. Steps: II at the narrow radius of the thick parts, max_radius/√2, on every
/// surfel (the first field); the reach along it (cap max_radius/reach_factor + one voxel); II at
/// each surfel's radius; the narrow radius where missing and the extrapolation. Where the distance
/// maps make max_radius likely (thick on both sides), the first field and the one at max_radius
/// are summed in one pass over the larger ball's rows; the guess decides the work, not the field.
/// Cost: about that of extrapolated_integral_invariant_normals at max_radius plus two distance
/// transforms.
/// Throws dsreg::Error for radii that are not positive and finite, min_radius > max_radius, a
/// reach factor that is not positive, or fewer than two levels per octave.
/// On a label map's complex each face's field is that of its inner label's indicator, and its
/// reach and thicknesses those of its inner and outer labels (local_reach.hpp).
AdaptiveNormalField adaptive_integral_invariant_normals(const VoxelLabels& volume, const DigitalSurface& surface,
                                                        const AdaptiveNormalOptions& options);

}  // namespace dsreg
