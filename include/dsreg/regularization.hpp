// dsreg — regularization of the digital surface by normal vector field alignment (fourth stage;
// the paper's §3–4).
//
// Unknowns p̂ (one 3D point per vertex). With u_f the unit normal of face f, the energy is (eq. 1)
//
//   E(p̂) = α Σ_i w0_i |p̂_i − p_i|²                                   (data attachment, eq. 3)
//        + β Σ_f w2_f Σ_{edges (a,b) of f} ((p̂_a − p̂_b)·u_f)²          (alignment, eq. 5–10)
//        + γ Σ_i w0_i |p̂_i − mean_{j ∈ link(i)} p̂_j|²                   (fairness, eq. 11–14)
//
// and its minimizer solves R p* = α W0 p (eq. 22–23). Vectors of unknowns are interleaved:
// entry 3i + d is coordinate d of vertex i, so R is made of 3×3 blocks. All positions are in
// physical units; α, β, γ are dimensionless weights (the terms all scale as length²).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/solvers.hpp"

namespace dsreg {

struct RegularizationWeights {
    double alpha = 1e-3;  ///< data attachment
    double beta = 1.0;    ///< normal alignment
    double gamma = 1e-2;  ///< fairness
    Eigen::VectorXd vertex_weights;  ///< diagonal of W0 (one per vertex), empty = identity
    Eigen::VectorXd face_weights;    ///< diagonal of W2 (one per face), empty = identity
};

/// The sparse quadratic problem R x = b, with R symmetric positive definite (3n×3n, both
/// triangles stored) and b = α W0 p.
struct RegularizationSystem {
    Eigen::SparseMatrix<double> matrix;
    Eigen::VectorXd rhs;
    double constant = 0;  ///< α pᵀ W0 p, so that E(x) = xᵀ R x − 2 bᵀ x + constant
};

/// The three unweighted sums of eq. (1) at positions p̂ (α, β, γ not applied; W0, W2 applied).
struct EnergyTerms {
    double data = 0;
    double alignment = 0;
    double fairness = 0;
    double total(const RegularizationWeights& w) const { return w.alpha * data + w.beta * alignment + w.gamma * fairness; }
};

/// Checks the weights (α > 0, β ≥ 0, γ ≥ 0, finite; per-element weights positive and of the
/// right size). Throws dsreg::Error naming the offending parameter.
void validate_weights(const RegularizationWeights& weights, std::int64_t vertex_count, std::int64_t face_count);

/// Assembles R and b of eq. (22–23) for the quad mesh (vertices p, faces, links) and the field u.
RegularizationSystem assemble_regularization_system(const PointMatrix& positions, const FaceMatrix& quads,
                                                     const VertexLinks& links, const PointMatrix& normals,
                                                     const RegularizationWeights& weights);

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
    double assembly_seconds = 0;  ///< wall time to build R and b
    double solve_seconds = 0;     ///< wall time of the solver (factorization included)
};

/// The whole fourth stage: links, assembly of eq. (22–23), solve, energies before and after.
RegularizationResult regularize(const DigitalSurface& surface, const PointMatrix& normals,
                                const RegularizationWeights& weights, const SolverOptions& solver);

}  // namespace dsreg
