#include "dsreg/solvers.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

double relative_residual(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, const Eigen::VectorXd& x) {
    const double norm_b = b.norm();
    const double norm_r = (R * x - b).norm();
    return norm_b > 0 ? norm_r / norm_b : norm_r;
}

SolveReport solve_cholmod(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
    llt.compute(R);
    if (llt.info() != Eigen::Success)
        throw Error("CHOLMOD could not factor the regularization matrix: it is not positive definite (alpha must be > 0)");
    x = llt.solve(b);
    if (llt.info() != Eigen::Success || !x.allFinite()) throw Error("CHOLMOD solve failed");
    SolveReport report;
    report.solver = "cholmod";
    report.factor_nonzeros = llt.cholmod().lnz;
    return report;
}

SolveReport solve_conjugate_gradient(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                     const SolverOptions& options) {
    // R is symmetric, so its column-major arrays are also its row-major arrays; row-major with
    // Lower|Upper lets Eigen run the products on all cores.
    const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>> rows(
        R.rows(), R.cols(), R.nonZeros(), R.outerIndexPtr(), R.innerIndexPtr(), R.valuePtr());
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor>, Eigen::Lower | Eigen::Upper> cg;
    cg.setTolerance(options.tolerance);
    cg.setMaxIterations(options.max_iterations);
    cg.compute(rows);
    const Eigen::VectorXd guess = x;
    x = cg.solveWithGuess(b, guess);
    SolveReport report;
    report.solver = "cg";
    report.iterations = int(cg.iterations());
    if (cg.info() != Eigen::Success)
        throw Error("conjugate gradient did not reach the relative residual " + std::to_string(options.tolerance) + " in " +
                    std::to_string(options.max_iterations) + " iterations (error " + std::to_string(cg.error()) +
                    "); use --solver cholmod");
    return report;
}

}  // namespace

SolverKind parse_solver_kind(const std::string& name) {
    if (name == "cholmod") return SolverKind::Cholmod;
    if (name == "cg") return SolverKind::ConjugateGradient;
    throw Error("unknown solver '" + name + "' (choose cholmod or cg)");
}

std::string solver_name(SolverKind kind) { return kind == SolverKind::Cholmod ? "cholmod" : "cg"; }

std::vector<std::string> solver_names() { return {"cholmod", "cg"}; }

SolveReport solve_spd(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                      const SolverOptions& options) {
    if (R.rows() != R.cols() || R.rows() != b.size()) throw Error("solve_spd: inconsistent system sizes");
    if (x.size() != b.size()) x = Eigen::VectorXd::Zero(b.size());
    SolveReport report = options.kind == SolverKind::Cholmod ? solve_cholmod(R, b, x)
                                                             : solve_conjugate_gradient(R, b, x, options);
    report.relative_residual = relative_residual(R, b, x);
    return report;
}

}  // namespace dsreg
