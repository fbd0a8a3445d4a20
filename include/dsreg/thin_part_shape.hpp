// dsreg — the shape of a thin part: a sheet (a plate, a shell, a membrane, a narrow gap between
// two walls) or a tube (a vessel, an arm, a wire, a narrow tunnel), for the thin-part data
// weights (thin_part_alpha, local_weights.hpp).
//
// Why it matters: a tube shrinks under the alignment term (its quads, bent around a radius ρ,
// lower their misalignment by getting smaller), so its data term is weighted up as ρ falls; a
// sheet is flat or gently curved along its surface, whatever its thickness, and has no such
// lever: the same weight there only pins the mesh to the staircase and bends its normals
// (docs/accuracy.md, "Sheets and tubes").
//
// How it is measured: at a surfel whose thinner side (the object's where its local reach is the
// smaller, the background's otherwise; local_reach.hpp) has reach ρ, take the voxels of that side
// inside the ball of radius k·ρ around the medial point c ∓ ρ·u (c the surfel centre, u the
// field), and the eigenvalues λ1 ≤ λ2 ≤ λ3 of the covariance of their centres:
//   * a tube of radius ρ:     λ1 ≈ λ2 ≈ ρ²/4, λ3 ≈ (kρ)²/3   — λ2/λ3 ≈ 3/(4k²) (0.08 at k = 3)
//   * a sheet 2ρ thick:       λ1 ≈ ρ²/3, λ2 ≈ λ3 ≈ (kρ)²/4   — λ2/λ3 ≈ 1, λ1/λ2 ≈ 4/(3k²) (0.15)
//   * a lump as wide as thick: λ1 ≈ λ2 ≈ λ3                  — neither: treated as a tube
// The sheetness is ramp(λ2/λ3; tube_ratio, tube_ratio + ramp_width) ·
// (1 − ramp(λ1/λ2; lump_ratio − ramp_width / 2, lump_ratio)), ramp rising linearly from 0 to 1
// between its two bounds; 0 on a tube or a lump, 1 on a sheet, in between at the rim of a plate
// (a half disc: λ2/λ3 ≈ 0.3) or where a sheet meets a tube.
#pragma once

#include <Eigen/Core>

#include "dsreg/digital_surface.hpp"
#include "dsreg/local_reach.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

struct SheetnessOptions {
    double ball_factor = 3.0;  ///< k: the ball's radius over the reach
    double tube_ratio = 0.35;  ///< λ2/λ3 at or below which the part is a tube
    double lump_ratio = 0.5;   ///< λ1/λ2 at or above which the part is a lump
    double ramp_width = 0.4;   ///< of the λ2/λ3 ramp; the λ1/λ2 ramp is half as wide
};

/// The sheetness in [0, 1] of the thin part at each surfel whose smaller reach (physical units)
/// is below `below`; 0 elsewhere. `directions`: the outward unit field the reach was measured
/// along (one row per surfel). On a label map the sides are the face's inner and outer labels.
/// Cost: O((kρ)²/h²) row look-ups per thin surfel. Throws dsreg::Error for a wrong number of
/// directions or reaches, or options out of range (k ≤ 0, ratios outside (0, 1), ramp ≤ 0).
Eigen::VectorXd thin_part_sheetness(const VoxelLabels& volume, const DigitalSurface& surface, const PointMatrix& directions,
                                    const SurfelReach& reach, double below, const SheetnessOptions& options = {});

}  // namespace dsreg
