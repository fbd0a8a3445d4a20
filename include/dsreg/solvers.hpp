// dsreg — sparse symmetric positive definite solvers for the regularization system R x = b of
// eq. (22–23). R is 3n×3n, made of 3×3 blocks (one block row per vertex, interleaved unknowns).
//
// Which solver (measured figures in docs/solvers.md):
//   amg      CG preconditioned by smoothed aggregation algebraic multigrid. Work and memory grow
//            linearly with the surface; 25–30 iterations with the paper's weights at every size.
//            The choice for large surfaces unless α is tiny.
//   cholmod  CHOLMOD supernodal Cholesky with a fill-reducing ordering: exact, insensitive to α,
//            but its factor grows like n log n and its time like n^1.5 (4 s and 0.25 GiB at
//            37.6K surfels with γ > 0, 124 s and 3.8 GiB at 236K). The reference solver; the
//            choice for small surfaces and for tiny α (e.g. the paper's Fig. 7, α = 1e-5·h²).
//   cg       CG preconditioned by the inverse 3×3 diagonal blocks: no setup, little memory, but
//            hundreds to thousands of iterations. Kept as a baseline.
//   auto     picks one of the above from the size of R and from α (read off R, see below).
//
// The iterative solvers also rely on the structure of eq. (23), R = αW0 ⊗ I3 + K with K positive
// semi-definite and K·(translation) = 0: then the smallest eigenvalue of R is at least α·min w0,
// and ‖x − x*‖₂ ≤ ‖R x − b‖₂ / (α min w0) = relative residual · ‖W0 p‖₂ / min w0 whatever α.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "dsreg/progress.hpp"

namespace dsreg {

enum class SolverKind {
    Cholmod,            ///< CHOLMOD supernodal Cholesky with a fill-reducing ordering (reference)
    ConjugateGradient,  ///< CG preconditioned by the 3×3 diagonal blocks, warm-started at the initial guess
    Amg,                ///< CG preconditioned by smoothed aggregation multigrid, warm-started
    Auto,               ///< cholmod for small systems and tiny α, amg otherwise (falls back to cholmod)
};

/// "cholmod", "cg", "amg" or "auto"; throws dsreg::Error listing the choices otherwise.
SolverKind parse_solver_kind(const std::string& name);
std::string solver_name(SolverKind kind);
std::vector<std::string> solver_names();

struct SolverOptions {
    SolverKind kind = SolverKind::Auto;
    /// Iterative solvers stop once ‖Rx − b‖ ≤ tolerance·‖b‖, or once the residual reaches
    /// rounding level (‖Rx − b‖ ≤ 1e-15·(‖R‖∞‖x‖ + ‖b‖), which is what ends them when α is tiny).
    /// With W0 = identity the error is then at most tolerance·‖p‖₂ (see above): 1e-10 keeps every
    /// vertex within 1e-4 voxel of the exact solution for objects up to ~1000 voxels across.
    double tolerance = 1e-10;
    int max_iterations = 20000;
    /// Accuracy target in length units (0: use `tolerance`). With it, iterative solvers stop as
    /// soon as ‖Rx − b‖₂ / smallest_eigenvalue ≤ max_error instead: that quotient bounds ‖x − x*‖₂,
    /// so every vertex is then within max_error of the exact solution (unless the rounding floor
    /// above stops them first, as with tiny α; the reported error_bound says so).
    double max_error = 0;
    /// A lower bound on the smallest eigenvalue of R (α·min α_i w0_i for eq. 23; 0 = unknown).
    /// Needed by max_error; also turns the residual into the reported error bound.
    double smallest_eigenvalue = 0;
    /// For regularize(): if > 0 (and max_error is 0), max_error = this × the smallest voxel side.
    /// regularize() always fills smallest_eigenvalue from the weights.
    double max_error_voxels = 0;
    /// Iterative solvers report each iteration here (stage "solve": fraction of the way to the
    /// stop, in log scale of the residual; detail "amg iteration 12, error bound 3.1e-04 voxel
    /// (target 5e-05)", in voxels when max_error_voxels is set, else in length units). Called
    /// from the calling thread; may throw (e.g. dsreg::Interrupted) to abandon the solve.
    ProgressCallback progress;
};

/// The accuracy the dsreg command asks of iterative solvers (max_error_voxels): 5e-5 voxel, half
/// the 1e-4 voxel agreement with the direct solve that dsreg promises. About 20 % fewer
/// iterations than the relative residual 1e-10 at 37K–10^6 surfels.
constexpr double kDefaultMaxErrorVoxels = 5e-5;

struct SolveReport {
    std::string solver;            ///< the solver that produced x ("auto" names its choice)
    std::string note;              ///< why auto chose it, or empty
    double relative_residual = 0;  ///< ‖R x − b‖ / ‖b‖ of the returned x
    /// ‖R x − b‖₂ / smallest_eigenvalue: a bound on the distance (length units) of every vertex of
    /// x to the exact solution; −1 if SolverOptions::smallest_eigenvalue was not given.
    double error_bound = -1;
    int iterations = 0;            ///< 0 for direct solvers
    double factor_nonzeros = 0;    ///< entries of the Cholesky factor (direct solvers)
    int multigrid_levels = 0;      ///< amg: levels of the hierarchy
    double operator_complexity = 0;  ///< amg: stored entries of all levels / entries of R
};

/// Solves R x = b (R SPD, both triangles stored). `x` holds the initial guess on entry (used by
/// iterative solvers) and the solution on exit. Throws dsreg::Error if the solve fails (e.g. R
/// not positive definite) or an iterative solver does not reach the tolerance.
SolveReport solve_spd(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                      const SolverOptions& options);

}  // namespace dsreg
