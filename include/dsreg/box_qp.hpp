// dsreg — strictly convex quadratic programs with box (bound) constraints:
//
//   minimize  q(x) = ½ xᵀ R x − bᵀ x   subject to  lower ≤ x ≤ upper  (componentwise),
//
// with R sparse symmetric positive definite (both triangles stored); a bound may be infinite
// (lower = −∞ or upper = +∞: the coordinate is free on that side). The regularization energy
// of eq. (1) is E(x) = xᵀRx − 2bᵀx + constant = 2 q(x) + constant, so both have the same
// minimizer; this is the problem of the clamped ("reversible") mode.
//
// Optimality (KKT) with the gradient g = R x − b, which is also minus the multiplier of the
// active bound:
//   free coordinate      (lower_i < x_i < upper_i):  g_i = 0            (stationarity)
//   at its lower bound   (x_i = lower_i):            g_i ≥ 0            (sign of the multiplier)
//   at its upper bound   (x_i = upper_i):            g_i ≤ 0
// The projected gradient pg collects what violates these conditions (g_i on free coordinates,
// min(g_i, 0) at a lower bound, max(g_i, 0) at an upper bound); x is optimal iff pg = 0.
// Residuals are relative to ‖b‖₂, like the relative residual ‖Rx − b‖/‖b‖ of an unconstrained
// solve (to which the KKT residual reduces when no bound is active).
//
// Method (see solve_box_qp), all on one symbolic analysis (fill-reducing ordering) of R:
//  1. ADMM with a single numeric Cholesky factorization of R + ρI, to find the active set
//     approximately (stops when the set of coordinates at their bounds stays the same);
//  2. primal–dual active set iterations (Hintermüller–Ito–Kunisch, a semismooth Newton method
//     on the KKT conditions): from (x, g), the estimate x_i − g_i / R_ii below lower_i or above
//     upper_i puts i at that bound, the other coordinates are free and solve R_FF x_F = b_F −
//     R_FA x_A exactly (a numeric factorization of R with the active rows and columns replaced
//     by their diagonal entries). Stops when the active sets repeat: then x satisfies the KKT conditions
//     up to the accuracy of the solve;
//  3. only if step 2 cycles or stalls (possible since R is not an M-matrix): the projected
//     Newton method of Bertsekas (1982) — Newton step on the free coordinates, projected Armijo
//     search, ε-active sets — which decreases q monotonically and converges from any feasible
//     point.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <functional>

#include "dsreg/progress.hpp"

namespace dsreg {

struct BoxQpOptions {
    /// Target relative KKT residual ‖pg‖₂ / ‖b‖₂ of the returned point.
    double tolerance = 1e-10;
    /// ADMM penalty ρ (in the units of R); ≤ 0 chooses sqrt(λ_low · λ_high) with λ_low =
    /// `smallest_eigenvalue_bound` (or min diag(R)/1000 when that is ≤ 0) and λ_high the
    /// Gershgorin bound of R.
    double admm_rho = 0;
    /// A lower bound of the smallest eigenvalue of R if known (e.g. α·min w0 for eq. 23), else 0.
    double smallest_eigenvalue_bound = 0;
    /// ADMM stops after this many iterations, or earlier once the set of coordinates at their
    /// bounds has not changed for `admm_stable_iterations` iterations. 0 skips ADMM. One ADMM
    /// iteration (two triangular solves) costs about 1/25 of a factorization; 50 iterations
    /// halve the active set iterations that follow (docs/clamped.md).
    int admm_max_iterations = 50;
    int admm_stable_iterations = 10;
    /// Primal–dual active set iterations (one numeric factorization each).
    int active_set_max_iterations = 30;
    /// Projected Newton iterations of the fallback (one numeric factorization each).
    int newton_max_iterations = 100;
    /// Called after each active set and Newton iteration (stage "clamp", fraction of the way from
    /// the first KKT residual to the tolerance in log scale, detail "active set iteration 3, KKT
    /// residual 2.1e-07"); from the calling thread, may throw to abandon the solve.
    ProgressCallback progress;
};

struct BoxQpReport {
    bool converged = false;           ///< KKT residual ≤ tolerance
    double kkt_residual = 0;          ///< ‖pg‖₂ / ‖b‖₂ (both conditions below together)
    double stationarity = 0;          ///< ‖g_free‖₂ / ‖b‖₂
    double multiplier_sign = 0;       ///< ‖wrong-sign multipliers of active bounds‖₂ / ‖b‖₂
    double constraint_violation = 0;  ///< max_i max(lower_i − x_i, x_i − upper_i, 0), units of x
    std::int64_t at_lower = 0;        ///< coordinates exactly at their lower bound
    std::int64_t at_upper = 0;        ///< coordinates exactly at their upper bound
    int admm_iterations = 0;
    int active_set_iterations = 0;
    bool active_set_cycled = false;  ///< step 2 revisited an earlier active set (fallback used)
    int newton_iterations = 0;       ///< projected Newton fallback (0 when not needed)
    int factorizations = 0;          ///< numeric Cholesky factorizations (one symbolic analysis)
    int cg_iterations = 0;           ///< conjugate gradient iterations of steps 2–3 (iterative solver, regularize_clamped)
    double admm_rho = 0;             ///< the ρ used
    double admm_seconds = 0;         ///< analysis (solve_box_qp) + ADMM
    double active_set_seconds = 0;   ///< steps 2 and 3
    // solve_box_qp_from_unconstrained only:
    double unconstrained_seconds = 0;   ///< analysis + factorization of R + solve
    double unconstrained_residual = 0;  ///< ‖R x_u − b‖ / ‖b‖ of the unconstrained minimizer x_u
    double factor_nonzeros = 0;         ///< entries of the Cholesky factor (same for every factorization)
};

/// KKT measures of x (feasible or not: x is projected onto the box first for the
/// complementarity part, and the distance to the box is reported as constraint_violation).
/// Fills every field of the report except iteration counts and times.
BoxQpReport box_qp_optimality(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                              const Eigen::VectorXd& upper, const Eigen::VectorXd& x, double tolerance);
/// The same for an R that is applied, not stored: `multiply(y)` returns R y.
BoxQpReport box_qp_optimality(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& multiply, const Eigen::VectorXd& b,
                              const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const Eigen::VectorXd& x,
                              double tolerance);

/// q(x + Δ) − q(x) = gᵀΔ + ½ ΔᵀRΔ with g = Rx − b: the exact energy change without the
/// cancellation of subtracting two large values.
double box_qp_energy_change(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& gradient, const Eigen::VectorXd& step);

/// Minimizes q over the box, starting from the unconstrained minimizer x_u = R⁻¹b (returned in
/// `unconstrained`), which is computed on the same symbolic analysis as the later
/// factorizations. `x` receives the solution. Same errors as solve_box_qp.
BoxQpReport solve_box_qp_from_unconstrained(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b,
                                            const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                            Eigen::VectorXd& unconstrained, Eigen::VectorXd& x,
                                            const BoxQpOptions& options = {});

/// Minimizes q over the box. `x` is the starting point on entry (any point; it is projected) —
/// typically the unconstrained minimizer — and the solution on exit (always inside the box).
/// Throws dsreg::Error for inconsistent sizes, lower > upper, a NaN bound, a lower bound of +∞ or
/// an upper bound of −∞, a non-finite b or x, or a failed factorization. Does not throw when the tolerance is not reached: see report.converged.
BoxQpReport solve_box_qp(const Eigen::SparseMatrix<double>& R, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                         const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options = {});

}  // namespace dsreg
