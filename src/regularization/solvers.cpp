#include "dsreg/solvers.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>

#include <algorithm>
#include <cstdio>
#include <limits>

#include "blas_threads.hpp"
#include "conjugate_gradient.hpp"
#include "dsreg/error.hpp"
#include "dsreg/progress.hpp"
#include "smoothed_aggregation.hpp"
#include "spd_system.hpp"

namespace dsreg {

namespace {

// auto: thresholds measured on goursat and spheres, see docs/solvers.md.
/// Up to this (400 vertices, amg's coarsest level) amg would factor R with CHOLMOD anyway. Above it
/// amg was faster at every size measured, down to 1 464 unknowns (goursat h = 2: 9–21 ms against
/// 18–35 ms; h = 1: 52 ms against 139 ms).
constexpr Eigen::Index kAutoDirectMaxUnknowns = 1200;
constexpr double kAutoMinDataWeight = 1e-6;  ///< below this α/diag, amg needs hundreds of iterations
constexpr int kAutoAmgMaxIterations = 200;   ///< auto falls back to CHOLMOD past this

std::string format_number(const char* format, double value) {
    char text[64];
    std::snprintf(text, sizeof text, format, value);
    return text;
}

SolveReport solve_cholmod(const detail::SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    const Eigen::SparseMatrix<double>& R = system.matrix();
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
    detail::factorize_with_cholmod(llt, R);
    if (llt.info() != Eigen::Success)
        throw Error("CHOLMOD could not factor the regularization matrix: it is not positive definite (alpha must be > 0)");
    x = llt.solve(b);
    if (llt.info() != Eigen::Success || !x.allFinite()) throw Error("CHOLMOD solve failed");
    SolveReport report;
    report.solver = "cholmod";
    report.factor_nonzeros = llt.cholmod().lnz;
    return report;
}

/// Progress of an iterative solve: the fraction is the share of the way (in log scale) from the
/// first residual to the one the stop needs; the detail gives the iteration and the error bound.
std::function<void(int, double, double)> progress_monitor(const SolverOptions& options, const std::string& solver) {
    if (!options.progress) return {};
    const bool voxels = options.max_error_voxels > 0 && options.max_error > 0;
    const double unit = voxels ? options.max_error / options.max_error_voxels : 1.0;
    const double lambda = options.smallest_eigenvalue;
    auto first = std::make_shared<double>(0.0);
    auto shown = std::make_shared<double>(0.0);
    return [=](int iteration, double residual, double target) {
        if (iteration == 1 || !(*first > 0)) *first = std::max(residual, target);
        const double span = std::log(*first / target);
        const double fraction = span > 0 ? std::clamp(std::log(*first / std::max(residual, target)) / span, 0.0, 1.0) : 1.0;
        *shown = std::max(*shown, fraction);
        std::string detail = solver + " iteration " + std::to_string(iteration);
        if (lambda > 0)
            detail += ", error bound " + format_number("%.1e", residual / lambda / unit) + (voxels ? " voxel" : "") + " (target " +
                      format_number("%.0e", target / lambda / unit) + ")";
        report_progress(options.progress, "solve", *shown, detail);
    };
}

detail::CgStop stop_rule(const SolverOptions& options, int max_iterations, const std::string& solver) {
    detail::CgStop stop;
    stop.relative_residual = options.tolerance;
    if (options.max_error > 0 && options.smallest_eigenvalue > 0) stop.absolute_residual = options.max_error * options.smallest_eigenvalue;
    stop.max_iterations = max_iterations;
    stop.monitor = progress_monitor(options, solver);
    return stop;
}

Error not_converged(const std::string& solver, const SolverOptions& options, int iterations) {
    const std::string target = options.max_error > 0 && options.smallest_eigenvalue > 0
                                   ? "the error bound " + format_number("%.1e", options.max_error)
                                   : "the relative residual " + format_number("%.1e", options.tolerance);
    return Error(solver + " did not reach " + target + " in " + std::to_string(iterations) + " iterations; use --solver cholmod");
}

detail::LinearOperator product(const detail::SpdSystem& system) {
    return [&system](const Eigen::VectorXd& in, Eigen::VectorXd& out) { system.multiply(in, out); };
}

/// CG with the inverse 3×3 diagonal blocks of R as preconditioner (block Jacobi).
SolveReport solve_block_jacobi_cg(const detail::SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                  const SolverOptions& options) {
    std::vector<Eigen::Matrix3d> inverse = system.diagonal_blocks();
    for (Eigen::Matrix3d& block : inverse) block = block.inverse().eval();
    const detail::Preconditioner jacobi = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
        z.resize(r.size());
#pragma omp parallel for schedule(static)
        for (std::int64_t i = 0; i < std::int64_t(inverse.size()); ++i) z.segment<3>(3 * i) = inverse[std::size_t(i)] * r.segment<3>(3 * i);
    };
    const detail::CgResult cg = detail::preconditioned_conjugate_gradient(
        product(system), system.infinity_norm(), b, x, jacobi, stop_rule(options, options.max_iterations, "cg"));
    if (!cg.converged) throw not_converged("conjugate gradient", options, cg.iterations);
    SolveReport report;
    report.solver = "cg";
    report.iterations = cg.iterations;
    return report;
}

/// CG preconditioned by one smoothed aggregation V-cycle per iteration. Returns false (x
/// unspecified) if the tolerance is not met within `max_iterations`.
bool solve_amg(const detail::SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x,
               const SolverOptions& options, int max_iterations, SolveReport& report) {
    return detail::solve_with_multigrid(system, *system.multigrid(detail::AmgSettings{}), b, x, options, max_iterations, report);
}

SolveReport solve_auto(const detail::SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                       const SolverOptions& options) {
    if (system.unknowns() <= kAutoDirectMaxUnknowns) {
        SolveReport report = solve_cholmod(system, b, x);
        report.note = "auto: small system";
        return report;
    }
    const double ratio = system.data_weight_ratio();
    if (ratio < kAutoMinDataWeight) {
        SolveReport report = solve_cholmod(system, b, x);
        report.note = "auto: data weight " + format_number("%.1e", ratio) + " of the diagonal is too small for amg";
        return report;
    }
    SolveReport report;
    const int cap = std::min(options.max_iterations, kAutoAmgMaxIterations);
    std::string why;
    try {
        if (solve_amg(system, b, x, options, cap, report)) {
            report.note = "auto: large system";
            return report;
        }
        why = "amg did not converge in " + std::to_string(cap) + " iterations";
    } catch (const Error& e) {  // e.g. a CG breakdown: the direct solver decides whether R is SPD
        why = std::string("amg failed (") + e.what() + ")";
    }
    report = solve_cholmod(system, b, x);  // a direct solve: x is only written
    report.note = "auto: " + why;
    return report;
}

}  // namespace

SolverKind parse_solver_kind(const std::string& name) {
    if (name == "cholmod") return SolverKind::Cholmod;
    if (name == "cg") return SolverKind::ConjugateGradient;
    if (name == "amg") return SolverKind::Amg;
    if (name == "auto") return SolverKind::Auto;
    throw Error("unknown solver '" + name + "' (choose cholmod, cg, amg or auto)");
}

std::string solver_name(SolverKind kind) {
    switch (kind) {
        case SolverKind::Cholmod: return "cholmod";
        case SolverKind::ConjugateGradient: return "cg";
        case SolverKind::Amg: return "amg";
        case SolverKind::Auto: return "auto";
    }
    return "auto";
}

std::vector<std::string> solver_names() { return {"cholmod", "auto", "amg", "cg"}; }

namespace detail {

bool solve_with_multigrid(const SpdSystem& system, const Multigrid& amg, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                          const SolverOptions& options, int max_iterations, SolveReport& report) {
    const Preconditioner vcycle = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) { amg.apply(r, z); };
    const CgResult cg = preconditioned_conjugate_gradient(product(system), system.infinity_norm(), b, x, vcycle,
                                                          stop_rule(options, max_iterations, "amg"));
    report.solver = "amg";
    report.iterations = cg.iterations;
    report.multigrid_levels = amg.level_count();
    report.operator_complexity = amg.operator_complexity();
    return cg.converged;
}

SolveReport solve_system(const SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x, const SolverOptions& options) {
    if (system.unknowns() != b.size()) throw Error("solve_spd: inconsistent system sizes");
    if (x.size() != b.size()) x = Eigen::VectorXd::Zero(b.size());
    SolveReport report;
    switch (options.kind) {
        case SolverKind::Cholmod: report = solve_cholmod(system, b, x); break;
        case SolverKind::ConjugateGradient: report = solve_block_jacobi_cg(system, b, x, options); break;
        case SolverKind::Amg:
            if (!solve_amg(system, b, x, options, options.max_iterations, report))
                throw not_converged("amg", options, report.iterations);
            break;
        case SolverKind::Auto: report = solve_auto(system, b, x, options); break;
    }
    Eigen::VectorXd r;
    system.multiply(x, r);
    const double norm_r = (r - b).norm(), norm_b = b.norm();
    report.relative_residual = norm_b > 0 ? norm_r / norm_b : norm_r;
    report.error_bound = options.smallest_eigenvalue > 0 ? norm_r / options.smallest_eigenvalue : -1.0;
    return report;
}

}  // namespace detail

SolveReport solve_spd(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                      const SolverOptions& options) {
    if (R.rows() != R.cols() || R.rows() != b.size()) throw Error("solve_spd: inconsistent system sizes");
    if (!R.isCompressed()) {  // the iterative solvers read the compressed arrays directly
        Eigen::SparseMatrix<double> compressed = R;
        compressed.makeCompressed();
        return solve_spd(compressed, b, x, options);
    }
    return detail::solve_system(detail::AssembledSystem(R), b, x, options);
}

}  // namespace dsreg
