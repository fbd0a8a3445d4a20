// dsreg — sparse symmetric positive definite solvers for the regularization system.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

namespace dsreg {

enum class SolverKind {
    Cholmod,            ///< CHOLMOD supernodal Cholesky with a fill-reducing ordering (reference)
    ConjugateGradient,  ///< Jacobi-preconditioned CG, warm-started at the initial guess
};

/// "cholmod" or "cg"; throws dsreg::Error listing the choices otherwise.
SolverKind parse_solver_kind(const std::string& name);
std::string solver_name(SolverKind kind);
std::vector<std::string> solver_names();

struct SolverOptions {
    SolverKind kind = SolverKind::Cholmod;
    double tolerance = 1e-10;   ///< iterative solvers: target relative residual ‖Rx − b‖/‖b‖
    int max_iterations = 20000;
};

struct SolveReport {
    std::string solver;
    double relative_residual = 0;  ///< ‖R x − b‖ / ‖b‖ of the returned x
    int iterations = 0;            ///< 0 for direct solvers
    double factor_nonzeros = 0;    ///< entries of the Cholesky factor (direct solvers)
};

/// Solves R x = b (R SPD, both triangles stored). `x` holds the initial guess on entry (used by
/// iterative solvers) and the solution on exit. Throws dsreg::Error if the solve fails (e.g. R
/// not positive definite) or an iterative solver does not reach the tolerance.
SolveReport solve_spd(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                      const SolverOptions& options);

}  // namespace dsreg
