// dsreg — repair of the regularized mesh until it is a valid solid: no self-intersection, no face
// folded against the field u (the definition is in mesh_validity.hpp; docs/validity.md has the
// method and the measurements).
//
// Why meshes go wrong. The data term of eq. (1) is weak (α = 3e-3 by default against β = 1), so vertices
// slide along the surface, often by more than a voxel, wherever that helps the alignment; where u
// varies quickly (noise, high curvature, parts thinner than the integral-invariant ball, where u
// is wrong and may even point into the object) neighbouring faces slide over each other, turn
// over, or the two sides of a thin part pass through each other. Nothing in E keeps a face on its
// side: alignment only asks the edges to be perpendicular to u, which a face turned over
// satisfies as well.
//
// Method: a stronger data term where the mesh is invalid, until it is valid.
//  * Each vertex i has a target t_i: its digital position p_i, except that the copies of a split
//    pointel (digital_surface.hpp), which sit at the same place and so touch, are moved
//    `split_offset` voxel (along each axis, times the spacing) towards the centroid of their own
//    faces. The targets form a valid mesh (tested on random volumes, both connectivities).
//  * E' = E + Σ_i (m_i − 1) α α_i w0_i |x_i − t_i|² (eq. 1 and its weights; m_i = 1 at first).
//  * Round k: the mesh x is checked (check_mesh_validity with the field, incrementally: only the
//    triangles that moved and those near them are tested again). The invalid vertices are the
//    corners of the intersecting (or degenerate) faces and, of a folded quad, the apex of each
//    corner triangle turned against u — the vertex that lies on the wrong side of the diagonal
//    between its two neighbours; its target, a corner of the digital square, lies on the right
//    side — or all four corners once those apexes are held. Each invalid vertex
//    gets m_i ← max(m_i·`alpha_step`, `alpha_start`), or, once m_i reached `alpha_cap`, is held
//    at its target; the `grade_rings` rings around get at least m_i / `alpha_grade` per ring, so
//    that the pulled vertices join the rest smoothly (pulling single vertices makes their
//    neighbours fold). The region U grows by these vertices and their `region_rings` rings. Then
//    E' is minimized over the free vertices of U within `window_rings` of them, everything else
//    held (the rows of R and b of eq. 22 plus the terms above, each connected part of the
//    window solved on its own: small parts by sparse Cholesky, large ones by multigrid CG from
//    the current positions, the box QP with `clamp_half_width`).
//    On a label complex, a vertex at the inner corner of a turn of a junction curve
//    (junction_turn_vertices, label_surface.hpp) is strengthened alone, its rings not graded: its
//    fold is a sliver between the smoothed curve and its staircase, which a small move of that
//    vertex alone undoes (grading spread the repair over most of a packed label map).
//    Rings are taken across every edge of the mesh (on a label complex, from a junction vertex
//    into the sheets that meet there, which the junction-aware fairness links leave out).
//  * A face whose u points into the object or nearly along the face (u·n_s < `field_margin`, n_s
//    its surfel's outward axis normal, which the voxels make certain) cannot be unfolded by
//    pulling vertices to their digital positions, where its normal is n_s. When such a face is
//    folded, its u is replaced by the nearest unit vector with u·n_s = field_margin (same
//    tangential direction): E' uses it, and the result carries the corrected field.
//  * Once valid, E' is minimized over the whole of U at once (every vertex outside U at p*, the
//    held ones at their targets) and checked again, back to the rounds if that undid anything.
// Each round raises the data weight of what is still invalid, so in the limit all of it is held on
// its (valid) targets: the repair always ends with a valid mesh, after few rounds in practice.
// What it costs is measured by E: energy_before = E(p*), energy_after = E(x), both with the input
// weights and field. x is the exact minimizer of E' over U (report.max_kkt_residual: the relative
// residual of that problem at x), so the rise is what the stronger data term on the invalid
// vertices costs, and nothing outside U changes.
// With the reversible mode (clamped_regularization.hpp) every solve keeps the vertices in their
// clamp boxes (box QP, box_qp.hpp), so the repaired mesh still re-digitizes to the input.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "dsreg/box_qp.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/mesh_validity.hpp"
#include "dsreg/normals.hpp"  // lift_into_half_space
#include "dsreg/progress.hpp"
#include "dsreg/regularization.hpp"

namespace dsreg {

struct ValidityRepairOptions {
    double alpha_start = 10;   ///< first factor of α_i on a vertex of an invalid face
    double alpha_step = 10;    ///< then × this each round it is still invalid (> 1)
    double alpha_cap = 1000;   ///< a vertex whose factor reached this and is still invalid is held
    /// Fairness first, at the vertices marked in smooth_first (empty: none): the first
    /// fairness_steps rounds that find such a vertex invalid multiply the weight of its fairness
    /// term (eq. 11–14; fairness_start, then × fairness_step) instead of its data weight, which
    /// untangles a fold without pulling the vertex back towards its voxels; then the data term as
    /// below, so the repair still ends valid. The pipeline marks the noisy vertices (those of the
    /// noise fairness, docs/accuracy.md "Noisy voxels"), where the voxels are the wrong target.
    std::vector<char> smooth_first;
    int fairness_steps = 2;
    double fairness_start = 10;
    double fairness_step = 10;
    double alpha_grade = 3;    ///< the rings around a strengthened vertex get its factor / this per ring
    int grade_rings = 2;       ///< rings graded so
    /// Label complexes: grade the rings of the junction turns' vertices too (false: they are
    /// strengthened alone, see above; true was the behaviour until 2026-12-04, kept for comparison).
    bool grade_junction_turns = false;
    int region_rings = 2;      ///< the region U: the strengthened vertices and this many rings (≥ grade_rings)
    int window_rings = 4;      ///< each round re-solves the region within this many rings of them
    double split_offset = 0.1;  ///< voxels: the targets of the copies of a split pointel move apart
    double field_margin = 0.2;  ///< corrected faces get u·n_s = this (about 78° from n_s at most)
    int max_rounds = 100;       ///< the rounds of the tail fix a few faces each and cost little (lobster.vol: 36)
    BoxQpOptions qp;            ///< KKT tolerance of the solves in the reversible mode
    /// Reversible mode: the clamp half-width (voxels, < ½); every local solve keeps the clamp boxes.
    std::optional<double> clamp_half_width;
    /// The input volume, to put every voxel centre back on its side (null: not asked; ignored in
    /// the reversible mode, which keeps them all; its grid must be the surface's). Each round,
    /// where the mesh has an object voxel's centre outside or a background voxel's inside (ray
    /// parity, voxel_centres_inside), every vertex i within `voxel_reach` voxels of that voxel
    /// (its pointel a with i − reach ≤ a ≤ i + 1 + reach on each axis) is bounded on the axis a
    /// of each of its faces: |x_i,a − p_i,a| ≤ voxel_half_width·s_a, the coordinate of the
    /// reversible mode's box that keeps a face's triangles off every voxel centre
    /// (docs/clamped.md), in the plane directions free. The windows around the bounded vertices
    /// are re-solved (box QP), and a voxel still wrong the next round bounds one voxel further,
    /// so the repair ends with every such centre on its side (docs/validity.md, "Voxel centres").
    /// A voxel with a `noisy_voxels` vertex within `voxel_reach` is left as it is: where the
    /// voxels are noise the surface should not follow them.
    const BinaryVolume* voxels = nullptr;
    /// With `voxels`: the centres are put back only when the object voxels among the wrong ones
    /// (noise included) are at least this share of all object voxels of `voxels` (0: always);
    /// below it they are counted and reported (wrong_voxels_before/after) and the repair is that
    /// of validity alone. The pipeline's default, kVoxelPutBackShare.
    double put_back_from_share = 0;
    std::vector<char> noisy_voxels;  ///< per vertex (empty: none)
    double voxel_half_width = 0.499;
    int voxel_reach = 1;
    int voxel_region_rings = 2;  ///< the region U grows this many rings around the bounded vertices (≥ region_rings)
};

struct ValidityRepairReport {
    MeshValidity before;  ///< of p*, with the input field
    MeshValidity after;   ///< of the mesh returned, with the field returned
    int rounds = 0;       ///< rounds that solved something (0: p* was valid)
    std::int64_t region_vertices = 0;        ///< |U|
    std::int64_t strengthened_vertices = 0;  ///< vertices whose α_i was multiplied
    std::int64_t smoothed_vertices = 0;      ///< vertices whose fairness weight was multiplied (fairness_steps)
    std::int64_t held_vertices = 0;          ///< of which held at their target
    std::int64_t field_corrections = 0;      ///< faces whose u was replaced
    std::int64_t parts_solved = 0;           ///< local solves, over all rounds
    bool converged = true;                   ///< every box QP (reversible mode) reached its tolerance
    /// x minimizes E' over the whole region (false: the last exact solve undid part of the repair,
    /// so x is the valid state before it, which minimizes E' over the last windows only).
    bool exact = false;
    double max_kkt_residual = 0;             ///< largest relative (KKT) residual of the final solve of a part
    double max_displacement_voxels = 0;      ///< max_i |x_i − p*_i| / smallest spacing
    EnergyTerms energy_before;               ///< E(p*), input weights and field
    EnergyTerms energy_after;                ///< E(x), input weights and field
    double check_seconds = 0;                ///< validity checks
    double solve_seconds = 0;                ///< local solves
    /// With options.voxels: voxel centres on the wrong side of p* and of x, and the vertices
    /// bounded to put them back (−1, 0 when not asked).
    std::int64_t wrong_voxels_before = -1;
    std::int64_t wrong_voxels_after = -1;
    std::int64_t bounded_vertices = 0;
    std::int64_t noisy_wrong_voxels = 0;     ///< of wrong_voxels_after, left as noise (noisy_voxels)
    /// With options.voxels: the object voxels of wrong_voxels_before (centre outside p*), what
    /// put_back_from_share is compared with; and whether the centres were put back.
    std::int64_t outside_object_voxels_before = -1;
    bool voxels_put_back = false;
};

struct ValidityRepairResult {
    PointMatrix positions;  ///< x
    PointMatrix normals;    ///< the field with its corrections (the input field where none)
    Eigen::VectorXd alpha_factors;     ///< m_i of E' (1 outside the strengthened vertices)
    Eigen::VectorXd fairness_factors;  ///< n_i of E' (1 outside the smoothed vertices; smooth_first)
    PointMatrix targets;               ///< t (repair_targets), empty if nothing was repaired
    std::vector<std::int32_t> region;  ///< U, sorted
    std::vector<std::int32_t> held;    ///< vertices held at their target, sorted
    ValidityRepairReport report;
};

/// Checks p* and repairs it as above. `weights` are those of the solve. Reports each round to
/// `progress` (stage "repair"). Throws dsreg::Error for inconsistent sizes or options.
ValidityRepairResult repair_validity(const DigitalSurface& surface, const PointMatrix& normals,
                                     const RegularizationWeights& weights, const PointMatrix& positions,
                                     const ValidityRepairOptions& options = {}, const ProgressCallback& progress = {});

/// The targets t of the repair: the digital positions, the copies of each split pointel moved
/// `split_offset` voxel (along each axis, times the spacing) towards the centroid of their faces.
PointMatrix repair_targets(const DigitalSurface& surface, double split_offset);

}  // namespace dsreg
