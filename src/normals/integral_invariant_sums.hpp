// dsreg — internal: the integral-invariant sums shared by the fixed-radius and adaptive fields.
//
// For a surfel of voxel v with normal sign·e_a, the voxel centres inside the ball B_r(c) of its
// centre c = centre(v) + sign·(s_a/2)·e_a are, relative to v, the same lattice offsets for every
// surfel of the same direction; an IntegralInvariantBall holds those offsets once per direction,
// cut into rows with running sums of the kernel weights, and sums a surfel's ball over the runs
// of object voxels of each row (RowRuns) with two table look-ups per run: O(r²/h²) per surfel.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/volume.hpp"

namespace dsreg::detail {

/// The object voxels of each row (j,k) as runs [first, last] of consecutive x indices.
struct RowRuns {
    std::vector<std::int64_t> row_first;  ///< size ny·nz + 1, into `runs`
    std::vector<std::array<std::int32_t, 2>> runs;
};

RowRuns build_row_runs(const BinaryVolume& volume);

/// Weighted sums over a prefix of a stencil row: Σ w, Σ w·t, Σ w·t².
struct RowSums {
    double w = 0, wt = 0, wtt = 0;
};

/// One row of a ball stencil: offsets (dj, dk), the x offsets t ∈ [t_lo, t_hi] inside the ball,
/// and `prefix` such that prefix[i] sums t_lo … t_lo + i − 1 (t_hi − t_lo + 2 entries).
struct StencilRow {
    std::int32_t dj, dk, t_lo, t_hi;
    std::int64_t prefix;  ///< index of the row's first entry in Stencil::prefix_sums
};

struct Stencil {
    std::vector<StencilRow> rows;
    std::vector<RowSums> prefix_sums;
};

/// The integral-invariant ball of one radius (physical units) and kernel on a grid's spacing:
/// its six stencils, one per surfel direction.
class IntegralInvariantBall {
public:
    /// Throws dsreg::Error if radius is not positive and finite, or its tables would exceed
    /// 768 MiB (about 100 voxels).
    IntegralInvariantBall(const Eigen::Vector3d& spacing, double radius, IntegralInvariantKernel kernel);

    /// The normal of surfel s: eigenvector of the smallest eigenvalue of the weighted covariance
    /// of the object voxel centres in its ball, oriented from their centroid towards the surfel
    /// centre (the trivial normal when the ball holds no weight).
    Eigen::Vector3d normal(const BinaryVolume& volume, const RowRuns& rows, const Surfel& s) const;

    double radius() const { return radius_; }

private:
    Eigen::Vector3d spacing_;
    double radius_;
    Stencil stencils_[3][2];  ///< [axis][sign > 0]
};

}  // namespace dsreg::detail
