// dsreg — box-constrained strictly convex QP: ADMM on one Cholesky factor, primal–dual active
// set iterations to the exact solution, projected Newton as a monotone fallback. The active set
// and Newton steps work with any HeldSolver (held_solver.hpp): CHOLMOD here, or conjugate
// gradients for the large components of the clamped mode.
#include "dsreg/box_qp.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "blas_threads.hpp"
#include "conjugate_gradient.hpp"
#include "dsreg/error.hpp"
#include "held_solver.hpp"

namespace dsreg {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

Eigen::VectorXd project(const Eigen::VectorXd& x, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
    return x.cwiseMax(lower).cwiseMin(upper);
}

/// Which bound holds a coordinate (exact comparisons: projection puts x_i exactly on its bound).
enum class Bound : std::int8_t { None, Lower, Upper, Both };

Bound bound_state(double x, double lower, double upper) {
    if (lower == upper) return Bound::Both;
    if (x <= lower) return Bound::Lower;
    if (x >= upper) return Bound::Upper;
    return Bound::None;
}

std::vector<Bound> bound_states(const Eigen::VectorXd& x, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
    std::vector<Bound> states(std::size_t(x.size()));
    for (Eigen::Index i = 0; i < x.size(); ++i) states[std::size_t(i)] = bound_state(x[i], lower[i], upper[i]);
    return states;
}

double reference_norm(const Eigen::VectorXd& b) {
    const double norm = b.norm();
    return norm > 0 ? norm : 1.0;
}

void check_problem(const SparseMatrix& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
    const Eigen::Index n = b.size();
    if (R.rows() != n || R.cols() != n || lower.size() != n || upper.size() != n)
        throw Error("box QP: inconsistent sizes (matrix " + std::to_string(R.rows()) + "x" + std::to_string(R.cols()) + ", " +
                    std::to_string(n) + " unknowns)");
    if (!b.allFinite()) throw Error("box QP: non-finite right-hand side");
    // Infinite bounds leave a coordinate free on that side; a bound of NaN, a lower bound of +∞
    // or an upper bound of −∞ admits no point.
    const double infinity = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < n; ++i)
        if (std::isnan(lower[i]) || std::isnan(upper[i]) || lower[i] == infinity || upper[i] == -infinity)
            throw Error("box QP: invalid bound at coordinate " + std::to_string(i));
    for (Eigen::Index i = 0; i < n; ++i)
        if (lower[i] > upper[i])
            throw Error("box QP: lower bound " + std::to_string(lower[i]) + " above upper bound " + std::to_string(upper[i]) +
                        " at coordinate " + std::to_string(i));
    if (!(R.diagonal().array() > 0).all()) throw Error("box QP: the matrix has a non-positive diagonal entry");
}

/// Largest absolute row sum: an upper bound of the largest eigenvalue of a symmetric matrix.
double gershgorin_bound(const SparseMatrix& R) {
    double largest = 0;
    for (Eigen::Index j = 0; j < R.outerSize(); ++j) {
        double sum = 0;
        for (SparseMatrix::InnerIterator it(R, j); it; ++it) sum += std::abs(it.value());
        largest = std::max(largest, sum);
    }
    return largest;
}

double automatic_rho(const SparseMatrix& R, const BoxQpOptions& options) {
    if (options.admm_rho > 0) return options.admm_rho;
    double low = options.smallest_eigenvalue_bound;
    if (!(low > 0)) low = R.diagonal().minCoeff() / 1000.0;
    return std::sqrt(low * gershgorin_bound(R));
}

/// Cholesky factorizations of matrices with the pattern of R (R + ρI, or R with some rows and
/// columns replaced by the identity), sharing one symbolic analysis (CHOLMOD supernodal).
class PatternFactorizer : public detail::HeldSolver {
public:
    explicit PatternFactorizer(const SparseMatrix& R) : R_(R), diagonal_(R.diagonal()) {
        R_.makeCompressed();
        work_ = R_;
        cholesky_.analyzePattern(R_);
        if (cholesky_.info() != Eigen::Success) throw Error("box QP: CHOLMOD could not analyze the matrix");
        flops_ = cholesky_.cholmod().fl;
    }

    /// Factorizes R + ρI.
    void factorize_shifted(double rho) {
        cholesky_.setShift(rho);
        factorize(R_, "R + rho I");
        cholesky_.setShift(0.0);
    }

    /// Factorizes R with the rows and columns of the held coordinates replaced by diag(R_ii):
    /// solving with it gives x_F = R_FF⁻¹ r_F and x_i = r_i / R_ii for held i.
    void factorize_held(const std::vector<bool>& held) {
        detail::mask_held(R_, held, work_);
        factorize(work_, "the free-variable submatrix R_FF");
    }

    Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const { return cholesky_.solve(rhs); }
    int factorizations() const override { return factorizations_; }
    double factor_nonzeros() { return double(cholesky_.cholmod().lnz); }
    const Eigen::VectorXd& diagonal() const override { return diagonal_; }

    // HeldSolver
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override { y = R_ * x; }
    void hold(const std::vector<bool>& held) override { factorize_held(held); }
    bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double) override {
        y = cholesky_.solve(rhs);
        return true;
    }
    bool exact() const override { return true; }

private:
    void factorize(const SparseMatrix& matrix, const std::string& what) {
        detail::use_blas_threads_for(flops_);
        cholesky_.factorize(matrix);
        ++factorizations_;
        if (cholesky_.info() != Eigen::Success) throw Error("box QP: CHOLMOD could not factor " + what + " (not positive definite)");
    }

    SparseMatrix R_;
    SparseMatrix work_;  ///< same pattern as R_, masked values
    Eigen::VectorXd diagonal_;
    Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> cholesky_;
    double flops_ = 0;  ///< of a factorization (the analysis's count; every one has the pattern of R)
    int factorizations_ = 0;
};

// ---------------------------------------------------------------------------------------------
// 1. ADMM: min q(x) + indicator_box(z) s.t. x = z, scaled dual w.
//   x ← (R + ρI)⁻¹ (b + ρ(z − w)),   z ← Π(x + w),   w ← w + x − z.
// One numeric factorization; stops when the coordinates at their bounds stay the same.

int run_admm(PatternFactorizer& factorizer, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
             const Eigen::VectorXd& upper, Eigen::VectorXd& x, double rho, const BoxQpOptions& options) {
    factorizer.factorize_shifted(rho);
    Eigen::VectorXd z = project(x, lower, upper);
    Eigen::VectorXd w = Eigen::VectorXd::Zero(x.size());
    std::vector<Bound> previous = bound_states(z, lower, upper);
    int stable = 0, iterations = 0;
    while (iterations < options.admm_max_iterations && stable < options.admm_stable_iterations) {
        x = factorizer.solve(b + rho * (z - w));
        z = project(x + w, lower, upper);
        w += x - z;
        ++iterations;
        std::vector<Bound> states = bound_states(z, lower, upper);
        stable = states == previous ? stable + 1 : 0;
        previous.swap(states);
    }
    x = z;
    return iterations;
}

// ---------------------------------------------------------------------------------------------
// 2. Primal–dual active set (semismooth Newton on min(x − l, max(x − u, x − g/D)) = 0).

/// Active-set estimate from (x, g): i goes to its lower (upper) bound when the scaled gradient
/// step x_i − g_i / R_ii falls below (above) it.
std::vector<Bound> active_set_estimate(const Eigen::VectorXd& x, const Eigen::VectorXd& g, const Eigen::VectorXd& diagonal,
                                       const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
    std::vector<Bound> states(std::size_t(x.size()));
    for (Eigen::Index i = 0; i < x.size(); ++i) {
        const double trial = x[i] - g[i] / diagonal[i];
        states[std::size_t(i)] = lower[i] == upper[i] ? Bound::Both
                                 : trial < lower[i]   ? Bound::Lower
                                 : trial > upper[i]   ? Bound::Upper
                                                      : Bound::None;
    }
    return states;
}

Eigen::VectorXd product(const detail::HeldSolver& solver, const Eigen::VectorXd& x) {
    Eigen::VectorXd y;
    solver.multiply(x, y);
    return y;
}

/// The KKT measures of box_qp_optimality from the projection of x and the gradient there.
BoxQpReport optimality_at(const Eigen::VectorXd& feasible, const Eigen::VectorXd& g, double violation, const Eigen::VectorXd& b,
                          const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, double tolerance) {
    BoxQpReport report;
    report.constraint_violation = violation;
    double free_sum = 0, sign_sum = 0;
    for (Eigen::Index i = 0; i < feasible.size(); ++i) {
        switch (bound_state(feasible[i], lower[i], upper[i])) {
        case Bound::None: free_sum += g[i] * g[i]; break;
        case Bound::Lower: ++report.at_lower; sign_sum += g[i] < 0 ? g[i] * g[i] : 0.0; break;
        case Bound::Upper: ++report.at_upper; sign_sum += g[i] > 0 ? g[i] * g[i] : 0.0; break;
        case Bound::Both: ++report.at_lower; ++report.at_upper; break;  // fixed: any multiplier
        }
    }
    const double scale = reference_norm(b);
    report.stationarity = std::sqrt(free_sum) / scale;
    report.multiplier_sign = std::sqrt(sign_sum) / scale;
    report.kkt_residual = std::sqrt(free_sum + sign_sum) / scale;
    report.converged = report.kkt_residual <= tolerance && report.constraint_violation == 0;
    return report;
}

BoxQpReport optimality(const detail::HeldSolver& solver, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const Eigen::VectorXd& x, double tolerance) {
    const Eigen::VectorXd feasible = project(x, lower, upper);
    return optimality_at(feasible, product(solver, feasible) - b, (x - feasible).lpNorm<Eigen::Infinity>(), b, lower, upper, tolerance);
}

/// x_A at its bounds, x_F = R_FF⁻¹ (b_F − R_FA x_A), solved to ‖residual‖ ≤ tolerance (iterative
/// solvers start from x).
void solve_on_active_set(detail::HeldSolver& solver, const Eigen::VectorXd& b, const std::vector<Bound>& states,
                         const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, double tolerance, Eigen::VectorXd& x) {
    const Eigen::Index n = b.size();
    std::vector<bool> held(static_cast<std::size_t>(n));
    Eigen::VectorXd fixed = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Bound s = states[std::size_t(i)];
        held[std::size_t(i)] = s != Bound::None;
        if (s == Bound::Lower || s == Bound::Both) fixed[i] = lower[i];
        if (s == Bound::Upper) fixed[i] = upper[i];
    }
    Eigen::VectorXd rhs = b - product(solver, fixed);
    for (Eigen::Index i = 0; i < n; ++i)
        if (held[std::size_t(i)]) rhs[i] = solver.diagonal()[i] * fixed[i];
    solver.hold(held);
    Eigen::VectorXd y = x;
    for (Eigen::Index i = 0; i < n; ++i)
        if (held[std::size_t(i)]) y[i] = fixed[i];
    solver.solve(rhs, y, tolerance);
    for (Eigen::Index i = 0; i < n; ++i)
        if (held[std::size_t(i)]) y[i] = fixed[i];  // exactly on the bound
    x = y;
}

/// Reports an iteration of step 2 or 3 to options.progress.
class QpProgress {
public:
    QpProgress(const BoxQpOptions& options, double first_residual) : options_(options), first_(first_residual) {}
    void report(const char* step, int iteration, double kkt_residual) {
        if (!options_.progress) return;
        const double span = std::log(first_ / options_.tolerance);
        const double reached = std::log(first_ / std::max(kkt_residual, options_.tolerance));
        shown_ = std::max(shown_, span > 0 ? std::clamp(reached / span, 0.0, 1.0) : 1.0);
        char detail[96];
        std::snprintf(detail, sizeof detail, "%s iteration %d, KKT residual %.1e", step, iteration, kkt_residual);
        report_progress(options_.progress, "clamp", shown_, detail);
    }

private:
    const BoxQpOptions& options_;
    double first_, shown_ = 0;
};

std::size_t hash_states(const std::vector<Bound>& states) {
    std::string bytes(states.size(), '\0');
    for (std::size_t i = 0; i < states.size(); ++i) bytes[i] = static_cast<char>(states[i]);
    return std::hash<std::string>{}(bytes);
}

/// Runs the active set iterations from x; returns true when the active sets repeated (KKT
/// point), false on a cycle or the iteration limit. x is left at the last iterate (feasible up
/// to rounding when true). With an iterative solver each solve is inexact: it only has to reduce
/// the residual 100× below the KKT residual of the previous iterate (enough to find the active
/// set), and once the active sets repeat the last one is solved again to the tolerance.
bool run_active_set(detail::HeldSolver& solver, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                    const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options, BoxQpReport& report) {
    const double tight = 0.5 * options.tolerance * reference_norm(b);
    const auto loose = [&] {
        return solver.exact() ? tight : std::max(tight, 1e-2 * optimality(solver, b, lower, upper, x, 0).kkt_residual * reference_norm(b));
    };
    Eigen::VectorXd g = product(solver, x) - b;
    std::vector<Bound> states = active_set_estimate(x, g, solver.diagonal(), lower, upper);
    std::set<std::size_t> seen{hash_states(states)};
    double tolerance = loose();
    QpProgress progress(options, optimality(solver, b, lower, upper, x, 0).kkt_residual);
    for (int iteration = 0; iteration < options.active_set_max_iterations; ++iteration) {
        solve_on_active_set(solver, b, states, lower, upper, tolerance, x);
        ++report.active_set_iterations;
        if (options.progress) progress.report("active set", report.active_set_iterations, optimality(solver, b, lower, upper, x, 0).kkt_residual);
        g = product(solver, x) - b;
        for (Eigen::Index i = 0; i < x.size(); ++i)
            if (states[std::size_t(i)] == Bound::None) g[i] = 0;  // the multiplier of a free coordinate is 0
        std::vector<Bound> next = active_set_estimate(x, g, solver.diagonal(), lower, upper);
        if (next == states) {
            if (tolerance <= tight) return true;
            tolerance = tight;  // the active set is found: solve it to the tolerance
            continue;
        }
        if (!seen.insert(hash_states(next)).second) {
            report.active_set_cycled = true;
            return false;
        }
        states.swap(next);
        tolerance = loose();
    }
    return false;
}

// ---------------------------------------------------------------------------------------------
// 3. Projected Newton (Bertsekas 1982) on the ε-active set: the monotone fallback.

/// Coordinates held at a bound this iteration: within ε of it, with the gradient pushing out.
std::vector<bool> epsilon_active(const Eigen::VectorXd& x, const Eigen::VectorXd& g, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, double epsilon) {
    std::vector<bool> active(std::size_t(x.size()));
    for (Eigen::Index i = 0; i < x.size(); ++i)
        active[std::size_t(i)] = lower[i] == upper[i] || (x[i] <= lower[i] + epsilon && g[i] > 0) ||
                                 (x[i] >= upper[i] - epsilon && g[i] < 0);
    return active;
}

/// Newton on the free coordinates (R_FF d_F = −g_F), scaled gradient −g_i / R_ii on the
/// active ones. An iterative solver starts from d = 0 and stops at a tenth of ‖g_F‖: its CG
/// iterate is then still a descent direction (inexact Newton).
Eigen::VectorXd newton_direction(detail::HeldSolver& solver, const Eigen::VectorXd& g, const std::vector<bool>& active) {
    Eigen::VectorXd rhs = -g;
    for (Eigen::Index i = 0; i < g.size(); ++i)
        if (active[std::size_t(i)]) rhs[i] = 0;
    solver.hold(active);
    Eigen::VectorXd d = Eigen::VectorXd::Zero(g.size());
    solver.solve(rhs, d, 0.1 * rhs.norm());
    for (Eigen::Index i = 0; i < g.size(); ++i)
        if (active[std::size_t(i)]) d[i] = -g[i] / solver.diagonal()[i];
    return d;
}

double energy_change(const detail::HeldSolver& solver, const Eigen::VectorXd& gradient, const Eigen::VectorXd& step) {
    return gradient.dot(step) + 0.5 * step.dot(product(solver, step));
}

/// Armijo search along the projection arc x(t) = Π(x + t d): accepts the first t = 1, ½, ¼, …
/// with q(x(t)) − q(x) ≤ σ (t g_Fᵀ d_F + g_Aᵀ (x(t) − x)_A). Returns false if none is found.
bool projected_search(const detail::HeldSolver& solver, const Eigen::VectorXd& g, const Eigen::VectorXd& d,
                      const std::vector<bool>& active, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                      Eigen::VectorXd& x) {
    constexpr double sigma = 1e-4;
    constexpr int max_halvings = 40;
    double free_slope = 0;  // g_Fᵀ d_F ≤ 0
    for (Eigen::Index i = 0; i < g.size(); ++i)
        if (!active[std::size_t(i)]) free_slope += g[i] * d[i];
    double t = 1;
    for (int halving = 0; halving <= max_halvings; ++halving, t *= 0.5) {
        const Eigen::VectorXd trial = project(x + t * d, lower, upper);
        const Eigen::VectorXd step = trial - x;
        double active_slope = 0;  // g_Aᵀ Δ_A ≤ 0
        for (Eigen::Index i = 0; i < g.size(); ++i)
            if (active[std::size_t(i)]) active_slope += g[i] * step[i];
        if (energy_change(solver, g, step) <= sigma * (t * free_slope + active_slope)) {
            x = trial;
            return true;
        }
    }
    return false;
}

void run_projected_newton(detail::HeldSolver& solver, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                          const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options, BoxQpReport& report) {
    double smallest_width = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < x.size(); ++i)
        if (upper[i] > lower[i]) smallest_width = std::min(smallest_width, upper[i] - lower[i]);
    const double epsilon_cap = std::isfinite(smallest_width) ? 0.1 * smallest_width : 0.0;
    x = project(x, lower, upper);
    QpProgress progress(options, optimality(solver, b, lower, upper, x, 0).kkt_residual);
    for (; report.newton_iterations < options.newton_max_iterations; ++report.newton_iterations) {
        const BoxQpReport now = optimality(solver, b, lower, upper, x, options.tolerance);
        progress.report("projected Newton", report.newton_iterations, now.kkt_residual);
        if (now.converged) break;
        const Eigen::VectorXd g = product(solver, x) - b;
        // ε = min(ε̄, ‖x − Π(x − D⁻¹g)‖∞): shrinks to 0 as x approaches the solution.
        const Eigen::VectorXd trial = project(x - g.cwiseQuotient(solver.diagonal()), lower, upper);
        const double epsilon = std::min(epsilon_cap, (x - trial).lpNorm<Eigen::Infinity>());
        const std::vector<bool> active = epsilon_active(x, g, lower, upper, epsilon);
        const Eigen::VectorXd d = newton_direction(solver, g, active);
        if (!projected_search(solver, g, d, active, lower, upper, x)) break;  // no descent left at double precision
    }
}

/// Steps 1–3 from x (already checked): ADMM only with a CHOLMOD factorizer (`admm`, may be null).
BoxQpReport solve_from(detail::HeldSolver& solver, PatternFactorizer* admm, const SparseMatrix* R, const Eigen::VectorXd& b,
                       const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, Eigen::VectorXd& x,
                       const BoxQpOptions& options, double analysis_seconds) {
    const BoxQpReport initial = optimality(solver, b, lower, upper, x, options.tolerance);
    if (initial.converged) return initial;  // e.g. the unconstrained minimizer lies in the box

    BoxQpReport counts;
    auto started = Clock::now();
    if (admm && R && options.admm_max_iterations > 0) {
        counts.admm_rho = automatic_rho(*R, options);
        counts.admm_iterations = run_admm(*admm, b, lower, upper, x, counts.admm_rho, options);
    }
    counts.admm_seconds = analysis_seconds + seconds_since(started);

    started = Clock::now();
    const bool settled = run_active_set(solver, b, lower, upper, x, options, counts);
    x = project(x, lower, upper);
    if (!settled || !optimality(solver, b, lower, upper, x, options.tolerance).converged)
        run_projected_newton(solver, b, lower, upper, x, options, counts);
    counts.active_set_seconds = seconds_since(started);

    BoxQpReport report = optimality(solver, b, lower, upper, x, options.tolerance);
    report.admm_iterations = counts.admm_iterations;
    report.active_set_iterations = counts.active_set_iterations;
    report.active_set_cycled = counts.active_set_cycled;
    report.newton_iterations = counts.newton_iterations;
    report.admm_rho = counts.admm_rho;
    report.admm_seconds = counts.admm_seconds;
    report.active_set_seconds = counts.active_set_seconds;
    return report;
}

}  // namespace

double box_qp_energy_change(const SparseMatrix& R, const Eigen::VectorXd& gradient, const Eigen::VectorXd& step) {
    return gradient.dot(step) + 0.5 * step.dot(R * step);
}

BoxQpReport box_qp_optimality(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& multiply, const Eigen::VectorXd& b,
                              const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const Eigen::VectorXd& x,
                              double tolerance) {
    const Eigen::VectorXd feasible = project(x, lower, upper);
    return optimality_at(feasible, multiply(feasible) - b, (x - feasible).lpNorm<Eigen::Infinity>(), b, lower, upper, tolerance);
}

BoxQpReport box_qp_optimality(const SparseMatrix& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                              const Eigen::VectorXd& upper, const Eigen::VectorXd& x, double tolerance) {
    return box_qp_optimality([&](const Eigen::VectorXd& y) -> Eigen::VectorXd { return R * y; }, b, lower, upper, x, tolerance);
}

BoxQpReport solve_box_qp(const SparseMatrix& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                         const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options) {
    check_problem(R, b, lower, upper);
    if (x.size() != b.size() || !x.allFinite()) throw Error("box QP: the starting point has the wrong size or is not finite");
    const BoxQpReport initial = box_qp_optimality(R, b, lower, upper, x, options.tolerance);
    if (initial.converged) return initial;
    const auto started = Clock::now();
    PatternFactorizer factorizer(R);
    BoxQpReport report = solve_from(factorizer, &factorizer, &R, b, lower, upper, x, options, seconds_since(started));
    report.factorizations = factorizer.factorizations();
    return report;
}

BoxQpReport solve_box_qp_from_unconstrained(const SparseMatrix& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                                            const Eigen::VectorXd& upper, Eigen::VectorXd& unconstrained, Eigen::VectorXd& x,
                                            const BoxQpOptions& options) {
    check_problem(R, b, lower, upper);
    auto started = Clock::now();
    PatternFactorizer factorizer(R);
    factorizer.factorize_held(std::vector<bool>(std::size_t(b.size()), false));
    unconstrained = factorizer.solve(b);
    const double unconstrained_seconds = seconds_since(started);
    x = unconstrained;
    BoxQpReport report = solve_from(factorizer, &factorizer, &R, b, lower, upper, x, options, 0.0);
    report.factorizations = factorizer.factorizations();
    report.unconstrained_seconds = unconstrained_seconds;
    report.unconstrained_residual = (R * unconstrained - b).norm() / reference_norm(b);
    report.factor_nonzeros = factorizer.factor_nonzeros();
    return report;
}

namespace detail {

IterativeHeldSolver::IterativeHeldSolver(const SpdSystem& system, Multigrid& multigrid, int max_iterations)
    : system_(system), multigrid_(multigrid), max_iterations_(max_iterations), diagonal_(system.unknowns()) {
    const std::vector<Eigen::Matrix3d>& blocks = system.diagonal_blocks();
    for (std::size_t i = 0; i < blocks.size(); ++i) diagonal_.segment<3>(3 * Eigen::Index(i)) = blocks[i].diagonal();
}

BoxQpReport solve_box_qp_with(HeldSolver& solver, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                              const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options) {
    if (x.size() != b.size() || !x.allFinite()) throw Error("box QP: the starting point has the wrong size or is not finite");
    BoxQpReport report = solve_from(solver, nullptr, nullptr, b, lower, upper, x, options, 0.0);
    report.cg_iterations = solver.iterations();
    return report;
}

void mask_held(const Eigen::SparseMatrix<double>& R, const std::vector<bool>& held, Eigen::SparseMatrix<double>& work) {
    for (Eigen::Index j = 0; j < R.outerSize(); ++j)
        for (Eigen::SparseMatrix<double>::InnerIterator it(R, j), out(work, j); it; ++it, ++out) {
            const bool masked = held[std::size_t(it.row())] || held[std::size_t(j)];
            out.valueRef() = !masked ? it.value() : (it.row() == j ? it.value() : 0.0);
        }
}

bool IterativeHeldSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double tolerance) {
    Eigen::VectorXd free_part;
    const LinearOperator product = [&](const Eigen::VectorXd& x, Eigen::VectorXd& out) {
        held_product([&](const Eigen::VectorXd& y, Eigen::VectorXd& z) { system_.multiply(y, z); }, held_indices_, diagonal_, x,
                     free_part, out);
    };
    const Preconditioner restricted_vcycle = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
        multigrid_.apply(r, z);  // decouples free and held coordinates
        for (const Eigen::Index i : held_indices_) z[i] = r[i] / diagonal_[i];
    };
    CgStop stop;
    stop.absolute_residual = tolerance;
    stop.max_iterations = max_iterations_;
    const CgResult cg = preconditioned_conjugate_gradient(product, system_.infinity_norm(), rhs, y, restricted_vcycle, stop);
    iterations_ += cg.iterations;
    return cg.converged;
}

}  // namespace detail

}  // namespace dsreg
