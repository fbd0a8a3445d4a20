// dsreg — piecewise-smooth normal vector field that keeps sharp features: Ambrosio–Tortorelli
// (AT) regularization of an input field (the paper's ref. [4] and Fig. 5; DESIGN.md, "Normal
// vector fields").
//
// Cells of the digital surface: F faces (surfels), E edges (each quad side shared by two faces,
// counted once), V vertices. Edge e runs from vertex a(e) to vertex b(e) counter-clockwise in its
// left face l(e); its right face r(e) is the face across it.
//
//   g  (F×3)  input field, unit vectors (integral invariants by default)
//   u  (F×3)  output field, a 2-form: one 3-vector per face
//   v  (V)    feature map, a 0-form: ≈ 1 where u is smooth, ≈ 0 on sharp features
//   A  (E×F)  face-to-edge difference   (A u)_e  = u_l(e) − u_r(e)
//   d0 (E×V)  vertex-to-edge difference (d0 v)_e = v_b(e) − v_a(e)
//   M  (E×V)  vertex-to-edge average    (M v)_e  = (v_a(e) + v_b(e)) / 2
//
// Energy at a fixed ε (W are the diagonal metric weights below, all exactly 1 on isotropic grids):
//
//   AT_ε(u, v) = a Σ_f W2_f |u_f − g_f|²                  (attachment to the input field)
//              + Σ_e Wu_e (M v)_e² |(A u)_e|²              (smoothness of u, switched off where v ≈ 0)
//              + λ ε Σ_e Wv_e (d0 v)_e²                    (smoothness of the feature map)
//              + λ/(4ε) Σ_i W0_i (1 − v_i)²               (features cost length: v prefers 1)
//
// Each step minimizes AT_ε exactly in one unknown, the other fixed (DESIGN.md's two systems):
//
//   u-step, the same matrix for x, y, z:  (a W2 + Aᵀ diag(Wu (M v)²) A) u = a W2 g,  then u_f ← u_f/|u_f|
//   v-step:  (λ/(4ε) W0 + λε d0ᵀ Wv d0 + Mᵀ diag(Wu Σ_xyz (A u)²) M) v = λ/(4ε) W0 1
//
// Schedule: u = g, v = 1; for ε = ε1, ε1/ρ, ε1/ρ², … while above ε2, then ε2 itself: alternate
// u-step and v-step until ‖Δv‖∞ < tolerance (at most max_rounds rounds per ε). Both matrices are
// symmetric positive definite with a pattern that never changes (the face adjacency graph, the
// vertex adjacency graph), so each is analysed once (CHOLMOD, METIS ordering; simplicial or
// supernodal factor by size) and only refactorized numerically; one factorization serves the
// three components of u. Between refactorizations a new matrix is solved by conjugate gradients
// preconditioned with the factor of an earlier round, started from the previous solution, when
// that reaches a relative residual of 1e-10 within 8 iterations (the later rounds of an ε, where
// the matrices change little); otherwise it is refactorized and solved directly.
//
// Units. The equations of DESIGN.md are written for unit grid spacing and dsreg keeps a, λ, ε in
// grid units, as the paper does (Fig. 5: a = 0.006, λ = 0.03, ε from 2 to 0.25): ε is a width in
// voxels, 1/√a is the smoothing length of u in voxels, λ the cost of a feature per voxel of
// length. A digital surface therefore gets the same (u, v) whatever its voxel size. With h the
// grid step, the corresponding physical parameters of the continuous functional
// ∫ a'|u − g|² + v²|∇u|² + λ'ε'|∇v|² + λ'/(4ε')(1 − v)² dA are a' = a/h² (1/length²),
// λ' = λ/h (1/length) and ε' = ε·h (length). For --shape inputs at step h this means ε' = ε·h.
// On anisotropic grids (spacing sx, sy, sz), h = (sx·sy·sz)^(1/3) and diagonal Hodge-star weights
// make the discrete energy a discretization of that physical functional:
//   W2_f = |f| / h²                 (face area)
//   W0_i = mean |f| around i / h²   (vertex area)
//   Wu_e = ℓ_e / ℓ*_e,  Wv_e = ℓ*_e / ℓ_e
// with ℓ_e the length of edge e and ℓ*_e the length of its dual edge (from the centre of l(e)
// through the middle of e to the centre of r(e), measured in the faces). On an isotropic grid
// (sx = sy = sz) every weight is exactly 1 and the systems are literally those of DESIGN.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"

namespace dsreg {

struct AmbrosioTortorelliParameters {
    double alpha = 0.006;         ///< a: weight of the attachment to g (grid units, see above)
    double lambda = 0.03;         ///< λ: cost of features (grid units)
    double epsilon_start = 2.0;   ///< ε1, voxels
    double epsilon_end = 0.25;    ///< ε2 ≤ ε1, voxels
    double epsilon_ratio = 2.0;   ///< ρ > 1: ε ← ε/ρ between levels
    double tolerance = 1e-4;      ///< a level ends when ‖Δv‖∞ < tolerance …
    int max_rounds = 10;          ///< … or after this many rounds
};

/// Throws dsreg::Error naming the parameter unless a > 0, λ > 0, 0 < ε2 ≤ ε1, ρ > 1,
/// tolerance > 0, max_rounds ≥ 1 and everything finite.
void validate_at_parameters(const AmbrosioTortorelliParameters& parameters);

/// The ε of each level: ε1, ε1/ρ, … (each > ε2), then ε2.
std::vector<double> at_epsilon_levels(const AmbrosioTortorelliParameters& parameters);

/// The cell complex of the digital surface as AT sees it: edges with their faces and vertices,
/// and the metric weights (see the header comment).
struct AtComplex {
    std::int64_t face_count = 0;
    std::int64_t vertex_count = 0;
    std::vector<std::array<std::int32_t, 2>> edge_faces;     ///< (l(e), r(e))
    std::vector<std::array<std::int32_t, 2>> edge_vertices;  ///< (a(e), b(e))
    Eigen::VectorXd face_weights;    ///< W2, one per face
    Eigen::VectorXd vertex_weights;  ///< W0, one per vertex
    Eigen::VectorXd edge_u_weights;  ///< Wu = ℓ/ℓ*, one per edge
    Eigen::VectorXd edge_v_weights;  ///< Wv = ℓ*/ℓ, one per edge

    std::int64_t edge_count() const { return std::int64_t(edge_faces.size()); }
};

AtComplex build_at_complex(const DigitalSurface& surface);

/// The operators A (E×F), d0 (E×V) and M (E×V) as sparse matrices (for checks and experiments;
/// the solver works on the edge lists directly).
struct AtOperators {
    Eigen::SparseMatrix<double> A, d0, M;
};
AtOperators at_operators(const AtComplex& complex);

/// The four terms of AT_ε (weights a, λ applied), and their sum.
struct AtEnergy {
    double attachment = 0;  ///< a Σ W2 |u − g|²
    double smoothness = 0;  ///< Σ Wu (Mv)² |Au|²
    double feature_gradient = 0;  ///< λε Σ Wv (d0 v)²
    double feature_length = 0;    ///< λ/(4ε) Σ W0 (1 − v)²
    double total() const { return attachment + smoothness + feature_gradient + feature_length; }
};

AtEnergy at_energy(const AtComplex& complex, const PointMatrix& g, const PointMatrix& u, const Eigen::VectorXd& v,
                   const AmbrosioTortorelliParameters& parameters, double epsilon);

/// How the linear systems were solved.
struct AtSolveStats {
    int factorizations = 0;         ///< numeric Cholesky factorizations (u and v)
    int refined_solves = 0;         ///< solves done by preconditioned CG with an earlier factor
    int refinement_iterations = 0;  ///< CG iterations, including attempts that fell back
};

/// The AT alternation with its two factorizations kept between rounds. Use
/// ambrosio_tortorelli_normals() for the whole schedule; this class exposes single steps.
class AtSolver {
public:
    /// g: one unit vector per face of `surface`. Throws dsreg::Error for a field of the wrong
    /// size, with non-finite or zero rows, or invalid parameters.
    AtSolver(const DigitalSurface& surface, const PointMatrix& g, const AmbrosioTortorelliParameters& parameters);
    ~AtSolver();
    AtSolver(const AtSolver&) = delete;
    AtSolver& operator=(const AtSolver&) = delete;

    void set_epsilon(double epsilon);
    /// Assembles and solves the u-system for the current v (u is left unnormalized). Returns the
    /// largest relative residual ‖K u − a W2 g‖/‖a W2 g‖ over x, y, z.
    double solve_u();
    /// u_f ← u_f/|u_f| (g_f where u_f = 0).
    void normalize_u();
    /// Assembles and solves the v-system for the current u. Returns the relative residual.
    double solve_v();
    /// One round: solve_u, normalize_u, solve_v. Returns ‖Δv‖∞.
    double round();

    const PointMatrix& u() const { return u_; }
    const Eigen::VectorXd& v() const { return v_; }
    const PointMatrix& g() const { return g_; }
    const AtComplex& complex() const { return complex_; }
    double epsilon() const { return epsilon_; }
    AtEnergy energy() const;
    double max_u_residual() const { return max_u_residual_; }
    double max_v_residual() const { return max_v_residual_; }
    const AtSolveStats& solve_stats() const { return stats_; }

    /// Current u- and v-matrices (lower triangle stored; symmetric) and right-hand sides.
    const Eigen::SparseMatrix<double>& u_matrix() const;
    const Eigen::SparseMatrix<double>& v_matrix() const;
    Eigen::MatrixXd u_rhs() const;  ///< F×3: a W2 g
    Eigen::VectorXd v_rhs() const;  ///< λ/(4ε) W0 1

    /// Entries of the Cholesky factors (0 before the first solve).
    double u_factor_nonzeros() const;
    double v_factor_nonzeros() const;

private:
    struct Systems;
    AmbrosioTortorelliParameters parameters_;
    AtComplex complex_;
    PointMatrix g_, u_;
    Eigen::VectorXd v_;
    double epsilon_;
    double max_u_residual_ = 0, max_v_residual_ = 0;
    AtSolveStats stats_;
    std::unique_ptr<Systems> systems_;
};

/// What happened at one ε.
struct AtLevelReport {
    double epsilon = 0;
    int rounds = 0;
    double v_change = 0;     ///< ‖Δv‖∞ of the last round
    bool converged = false;  ///< v_change < tolerance
    double energy = 0;       ///< AT_ε at the end of the level
    double seconds = 0;
    AtSolveStats solves;     ///< solves of this level
};

struct AmbrosioTortorelliResult {
    PointMatrix normals;      ///< u, F×3 unit vectors
    Eigen::VectorXd features;  ///< v, one per vertex (≈ 0 on sharp features)
    std::vector<AtLevelReport> levels;
    double max_u_residual = 0;  ///< largest relative residual of all u-solves
    double max_v_residual = 0;  ///< … of all v-solves
    double u_factor_nonzeros = 0, v_factor_nonzeros = 0;
    AtSolveStats solves;  ///< all levels
    double seconds = 0;

    int total_rounds() const;
};

/// The whole schedule (see the header comment) from the input field g (F×3, unit rows).
AmbrosioTortorelliResult ambrosio_tortorelli_normals(const DigitalSurface& surface, const PointMatrix& g,
                                                     const AmbrosioTortorelliParameters& parameters);

/// The sharp-feature lines of a feature map: the mesh edges whose two vertices have v below
/// `threshold` (the edge lies in {v < threshold}), chained into polylines (each a list of vertex
/// indices; a closed loop repeats its first vertex at the end). Chains stop at vertices where
/// other than two feature edges meet.
std::vector<std::vector<std::int32_t>> feature_polylines(const FaceMatrix& quads, std::int64_t vertex_count,
                                                         const Eigen::VectorXd& v, double threshold = 0.5);

/// Writes polylines as an OBJ file: "v x y z" lines for the vertices they use (positions row i
/// for vertex i) and one "l i j k …" line (1-based) per polyline. Atomic write; throws
/// dsreg::Error naming `path` on failure.
void write_polylines_obj(const std::string& path, const PointMatrix& positions,
                         const std::vector<std::vector<std::int32_t>>& polylines);

}  // namespace dsreg
