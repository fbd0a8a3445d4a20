// dsreg — internal: the integral-invariant sums shared by the fixed-radius and adaptive fields.
//
// For a surfel of voxel v with normal sign·e_a, the voxel centres inside the ball B_r(c) of its
// centre c = centre(v) + sign·(s_a/2)·e_a are, relative to v, the same lattice offsets for every
// surfel of the same direction; an IntegralInvariantBall holds those offsets once per direction,
// cut into rows with running sums of the kernel weights, and sums a surfel's ball over the runs
// of voxels of one label in each row (RowRuns) with two table look-ups per run: O(r²/h²) per surfel.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/volume.hpp"

namespace dsreg::detail {

/// The labelled voxels of each row (j,k) as runs [first, last] of consecutive x indices with one
/// label: the object of a binary volume (label 1), or every non-background label of a label map,
/// so that one pass over the volume serves the indicators of all labels.
struct RowRuns {
    std::vector<std::int64_t> row_first;  ///< size ny·nz + 1, into `runs`
    std::vector<std::array<std::int32_t, 2>> runs;
    std::vector<std::uint32_t> labels;  ///< label index of each run
};

RowRuns build_row_runs(const VoxelLabels& volume);

/// The runs of the volume labelled by connected part instead of by label (1, 2, …): voxels of one
/// label are one part where they share a face, or where the surface joins them (their faces share
/// a vertex: the connectivity's pairings, less the pinches kept apart). The integral invariants of
/// a face sum the voxels of its own part only: another part a voxel or two away (a fragment of
/// debris beside the main object, two blobs a one-voxel gap apart) is not the shape of this one,
/// and seen through the ball it turned the normals of such fragments any way. The parts are those
/// of the volume given: block by block (--block-size, dsreg-mpi), of the block with its halo, so
/// two pieces within one ball that join only beyond the halo are apart there and one part in the
/// whole volume. Throws dsreg::Error if a face's voxel is not in the volume's object.
RowRuns build_part_runs(const VoxelLabels& volume, const DigitalSurface& surface);

/// The label of the run that holds voxel v (0: none, the background), in O(log runs of its row).
std::uint32_t run_label_at(const RowRuns& rows, const Index3& dims, const std::array<std::int32_t, 3>& v);

/// Weighted sums over a prefix of a stencil row: Σ w, Σ w·t, Σ w·t².
struct RowSums {
    double w = 0, wt = 0, wtt = 0;
};

/// One row of a ball stencil: offsets (dj, dk), the x offsets t ∈ [t_lo, t_hi] inside the ball,
/// and `prefix` such that prefix[i] sums t_lo … t_lo + i − 1 (t_hi − t_lo + 2 entries; the first
/// is zero, the last the row's total, kept here too: a run across the whole row or up to its end
/// reads no table entry, or one).
struct StencilRow {
    std::int32_t dj, dk, t_lo, t_hi;
    std::int64_t prefix;  ///< index of the row's first entry in Stencil::prefix_sums
    RowSums total;        ///< = prefix_sums[prefix + t_hi − t_lo + 1]
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
    /// of the centres of the voxels of `label` in its ball (rows of a grid of `dims`), oriented
    /// from their centroid towards the surfel centre, blended with the direction from the centroid
    /// where the two smallest eigenvalues are close (integral_invariant_normals, normals.hpp; the
    /// trivial normal when the ball holds no weight).
    Eigen::Vector3d normal(const Index3& dims, const RowRuns& rows, const Surfel& s, std::uint32_t label) const;

    double radius() const { return radius_; }

private:
    friend class NestedIntegralInvariantBalls;
    const Stencil& stencil(const Surfel& s) const { return stencils_[s.axis][s.sign > 0 ? 1 : 0]; }

    Eigen::Vector3d spacing_;
    double radius_;
    Stencil stencils_[3][2];  ///< [axis][sign > 0]
};

/// Two concentric balls of one kernel, radii outer > inner, summed in one pass: the inner ball's
/// rows are rows of the outer one (the same offsets (dj, dk), a sub-range of t), so each row's
/// runs are read once for both. The cost of the outer ball alone, for the two normals.
class NestedIntegralInvariantBalls {
public:
    /// Throws dsreg::Error as IntegralInvariantBall does, or if inner_radius ≥ outer_radius.
    NestedIntegralInvariantBalls(const Eigen::Vector3d& spacing, double outer_radius, double inner_radius,
                                 IntegralInvariantKernel kernel);

    /// The normals of surfel s in the outer and the inner ball: each the same, to the bit, as
    /// IntegralInvariantBall::normal of that ball (the same sums in the same order).
    std::pair<Eigen::Vector3d, Eigen::Vector3d> normals(const Index3& dims, const RowRuns& rows, const Surfel& s,
                                                        std::uint32_t label) const;

private:
    IntegralInvariantBall outer_, inner_;
    /// For each row of the outer stencil [axis][sign > 0], the index of the inner stencil's row
    /// with the same (dj, dk), or −1.
    std::vector<std::int32_t> inner_row_of_[3][2];
};

}  // namespace dsreg::detail
