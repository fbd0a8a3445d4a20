// dsreg — clamped ("reversible") regularization (beyond the paper; DESIGN.md "Regularization").
//
// The exact minimizer of the energy of eq. (1) (regularization.hpp) subject to box constraints
//
//   |p̂_i,d − p_i,d| ≤ half_width · s_d     for every vertex i and axis d,
//
// s = the grid spacing (physical units, may differ per axis). With half_width = ½ each vertex
// stays in the cube whose corners are the 8 voxel centres around its pointel. With any
// half_width < ½ (default 0.499) the regularized surface never meets a voxel centre, and it
// can be deformed back to the digital surface without meeting one, so every voxel centre keeps
// its side: re-digitizing the result gives back the input volume exactly, whatever the normal
// field and the weights (docs/clamped.md; classify_voxel_centres measures it).
//
// Solved as a box-constrained convex QP (box_qp.hpp), component by component (each component's
// QP is independent, mesh_parts.hpp): the unconstrained minimizer of R p* = α W0 p first (the
// answer where it is inside the boxes), then primal–dual active set iterations to the requested
// KKT residual. Small components (and every one with --solver cholmod, or when `auto` would
// factor) use CHOLMOD on one symbolic analysis of their R, with ADMM on one factorization of
// R + ρI before the active set iterations. The others are solved without any factor: the
// unconstrained minimizer by amg, each active set step by conjugate gradients on the free
// coordinates preconditioned by the same multigrid hierarchy (docs/clamped.md).
#pragma once

#include <cstdint>

#include "dsreg/box_qp.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/volume.hpp"

namespace dsreg {

struct ClampOptions {
    BoxQpOptions qp;  ///< KKT tolerance, ADMM and active set limits
    /// The solver of the unconstrained minimizer and how the components are solved: cholmod
    /// factors every component, auto and amg (and cg, which means amg here) use the iterative
    /// QP on components that auto would give to amg. Its progress callback sees the unconstrained
    /// solve ("solve") and each active set iteration ("clamp").
    SolverOptions solver;
    /// Half-width of each box, per axis, in units of that axis' spacing (> 0). ½ = the closed
    /// cube of the 8 voxel centres around the pointel, whose corners are voxel centres: the
    /// minimizer then often puts vertices exactly on voxel centres, making re-digitization
    /// ambiguous there. Any value below ½ keeps every voxel centre strictly on its side of the
    /// surface (docs/clamped.md); the default leaves a margin of 1/1000 voxel, far above the
    /// rounding of coordinates even in float32 files.
    double half_width = 0.499;
};

struct ClampReport {
    BoxQpReport qp;  ///< KKT residual, constraint violation, iterations, times
    /// The unconstrained minimizer (what regularize() returns): how many vertices leave their
    /// box, and by how much at most, in units of the spacing along that axis (0 if none).
    std::int64_t unclamped_vertices_outside = 0;
    double unclamped_max_excess = 0;
    EnergyTerms unclamped_energy;
    std::int64_t clamped_vertices = 0;  ///< vertices with at least one coordinate on its box
};

/// A RegularizationResult (positions inside the boxes, energies before and after; `solve`
/// describes the unconstrained solve that started the QP, as regularize() reports it) plus the
/// clamp report (KKT figures of the whole system; iterations of the largest component).
struct ClampedRegularizationResult : RegularizationResult {
    ClampReport clamp;
    PointMatrix unclamped_positions;  ///< the unconstrained minimizer, for comparison
};

/// Box bounds of every coordinate, interleaved like flatten_points (3i + d):
/// p_i,d ∓ half_width · spacing_d.
void clamp_bounds(const DigitalSurface& surface, double half_width, Eigen::VectorXd& lower, Eigen::VectorXd& upper);

/// The clamped minimizer. Throws dsreg::Error for invalid weights or options, a failed
/// factorization; the KKT residual actually reached is in result.clamp.qp (converged flag).
ClampedRegularizationResult regularize_clamped(const DigitalSurface& surface, const PointMatrix& normals,
                                               const RegularizationWeights& weights, const ClampOptions& options = {});

/// How a closed mesh re-digitizes `volume`: each voxel centre is inside or outside the mesh
/// (triangulated along the shorter diagonal of each quad, ray parity; evaluation.hpp's
/// voxel_centres_inside), compared with the voxel's mask value.
struct VoxelAgreement {
    std::int64_t total = 0;               ///< voxels of the grid
    std::int64_t correct = 0;             ///< inside ⇔ object voxel
    std::int64_t object_outside = 0;      ///< object voxels whose centre is outside the mesh
    std::int64_t background_inside = 0;   ///< background voxels whose centre is inside the mesh
    std::int64_t wrong() const { return object_outside + background_inside; }
    double share() const { return total > 0 ? double(correct) / double(total) : 0.0; }
};

VoxelAgreement classify_voxel_centres(const BinaryVolume& volume, const PointMatrix& positions, const FaceMatrix& quads);

}  // namespace dsreg
