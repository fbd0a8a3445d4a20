// dsreg — regularization of the digital surface by normal vector field alignment (fourth stage;
// the paper's §3–4).
//
// Unknowns p̂ (one 3D point per vertex). With u_f the unit normal of face f, the energy is (eq. 1)
//
//   E(p̂) = α Σ_i α_i w0_i |p̂_i − p_i|²                                (data attachment, eq. 3)
//        + β Σ_f β_f w2_f Σ_{edges (a,b) of f} ((p̂_a − p̂_b)·u_f)²       (alignment, eq. 5–10)
//        + γ Σ_i γ_i w0_i |p̂_i − mean_{j ∈ link(i)} p̂_j − t_i|²          (fairness, eq. 11–14)
//
// and its minimizer solves R p* = α W0_α p + γ Lᵀ Γ t (eq. 22–23, with W0_α = diag(α_i w0_i); the
// fairness targets t_i are 0 in the paper, so the second part vanishes there). w0_i, w2_f
// are the metrics W0, W2 of §3.4 (identity by default; area metrics in
// regularization_metrics.hpp); α_i, β_f, γ_i are optional local multipliers of the three global
// weights (beyond the paper; 1 by default). Vectors of unknowns are interleaved: entry 3i + d is
// coordinate d of vertex i, so R is made of 3×3 blocks. All positions are in physical units;
// α, β, γ and the multipliers are dimensionless, so the energy has the units of length² × the
// units of the metric (length² with identity metrics, length⁴ with area metrics).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/solvers.hpp"

namespace dsreg {

struct RegularizationWeights {
    double alpha = 1e-3;  ///< data attachment (the paper's; the pipeline's default is PipelineOptions::alpha)
    double beta = 1.0;    ///< normal alignment
    double gamma = 1e-2;  ///< fairness (the paper's; the pipeline's default is PipelineOptions::gamma)
    Eigen::VectorXd vertex_weights;  ///< diagonal of W0 (one per vertex, > 0), empty = identity
    Eigen::VectorXd face_weights;    ///< diagonal of W2 (one per face, > 0), empty = identity
    // Local multipliers (beyond the paper; empty = 1 everywhere). Added last, with default
    // member initializers, so that aggregate initialization {α, β, γ, W0, W2} stays valid and
    // warning-free.
    Eigen::VectorXd vertex_alpha{};  ///< α_i of the data term, one per vertex, each > 0
    Eigen::VectorXd face_beta{};     ///< β_f of the alignment term, one per face, each ≥ 0
    Eigen::VectorXd vertex_gamma{};  ///< γ_i of the fairness term, one per vertex, each ≥ 0
    /// t_i, the offset the fairness term asks of p̂_i from the mean of its links (n×3, physical
    /// units, finite; empty = 0 everywhere, the paper's). Ignored at vertices without links. The
    /// label pipeline sets it at the turns of junction curves (junction_turn_targets,
    /// label_surface.hpp); it changes b, not R.
    PointMatrix fairness_targets{};
};

/// The sparse quadratic problem R x = b, with R symmetric positive definite (3n×3n, both
/// triangles stored) and b = α W0_α p + γ Lᵀ Γ t (W0_α = diag(α_i w0_i), Γ = diag(γ_i w0_i),
/// L the fairness rows x_i − mean_{j ∈ link(i)} x_j, t the fairness targets).
struct RegularizationSystem {
    Eigen::SparseMatrix<double> matrix;
    Eigen::VectorXd rhs;
    double constant = 0;  ///< α pᵀ W0_α p + γ tᵀ Γ t, so that E(x) = xᵀ R x − 2 bᵀ x + constant
};

/// The three sums of eq. (1) at positions p̂ without the global α, β, γ (W0, W2 and the local
/// multipliers α_i, β_f, γ_i applied): data = Σ α_i w0_i |p̂_i − p_i|², and so on.
struct EnergyTerms {
    double data = 0;
    double alignment = 0;
    double fairness = 0;
    double total(const RegularizationWeights& w) const { return w.alpha * data + w.beta * alignment + w.gamma * fairness; }
};

/// Checks the weights: α > 0, β ≥ 0, γ ≥ 0, all finite; W0, W2 and α_i positive, β_f and γ_i
/// non-negative, each finite and of the right size (or empty); fairness targets finite, one row
/// per vertex (or none). Throws dsreg::Error naming the offending parameter (and element).
void validate_weights(const RegularizationWeights& weights, std::int64_t vertex_count, std::int64_t face_count);

/// Assembles R and b of eq. (22–23) for the quad mesh (vertices p, faces, links) and the field u.
RegularizationSystem assemble_regularization_system(const PointMatrix& positions, const FaceMatrix& quads,
                                                     const VertexLinks& links, const PointMatrix& normals,
                                                     const RegularizationWeights& weights);

/// b and the constant of that system without R (its matrix left empty): for solvers that apply R
/// without assembling it. The links are read only where the weights hold fairness targets.
RegularizationSystem regularization_right_hand_side(const PointMatrix& positions, const VertexLinks& links,
                                                    const RegularizationWeights& weights);

/// α · min_i α_i w0_i: the data term alone bounds the smallest eigenvalue of R from below (R is
/// αW0_α ⊗ I3 plus positive semi-definite terms, eq. 25).
double smallest_eigenvalue_bound(const RegularizationWeights& weights, std::int64_t vertex_count);

/// α · min of α_i w0_i over the vertices i with selected[i] (+∞ if none): the same bound for a
/// principal submatrix of R (the rows and columns of those vertices), or for a part of the
/// vertices whose minimum is combined with the others' (block-wise and MPI runs).
double smallest_eigenvalue_bound(const RegularizationWeights& weights, const std::vector<char>& selected);

/// Evaluates the terms of eq. (1) face by face and vertex by vertex (no matrices).
EnergyTerms regularization_energy(const PointMatrix& candidate, const PointMatrix& positions, const FaceMatrix& quads,
                                  const VertexLinks& links, const PointMatrix& normals, const RegularizationWeights& weights);

/// Interleaved vector (3i + d) ↔ n×3 point matrix.
Eigen::VectorXd flatten_points(const PointMatrix& points);
PointMatrix unflatten_points(const Eigen::VectorXd& x);

struct RegularizationResult {
    PointMatrix positions;  ///< p*, n×3, physical units
    SolveReport solve;
    EnergyTerms energy_before;  ///< terms at p̂ = p
    EnergyTerms energy_after;   ///< terms at p̂ = p*
    double assembly_seconds = 0;  ///< wall time to set up R (matrix-free operator, or assembly) and b
    double solve_seconds = 0;     ///< wall time of the solver (factorization included)
};

/// The whole fourth stage: links (fairness_links: the quad links of a binary surface, junction-aware
/// on a label complex, label_surface.hpp), assembly of eq. (22–23), solve, energies before and after.
RegularizationResult regularize(const DigitalSurface& surface, const PointMatrix& normals,
                                const RegularizationWeights& weights, const SolverOptions& solver);

}  // namespace dsreg
