// dsreg — internal: preconditioned conjugate gradients for the SPD regularization system, with a
// stopping test that stays meaningful when α is tiny.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "block_sparse.hpp"

namespace dsreg::detail {

/// z = M⁻¹ r for an SPD preconditioner M.
using Preconditioner = std::function<void(const Eigen::VectorXd& r, Eigen::VectorXd& z)>;
/// y = R x for the SPD matrix R.
using LinearOperator = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& y)>;

struct CgStop {
    double relative_residual = 1e-10;  ///< stop once ‖b − R x‖ ≤ this · ‖b‖ ...
    double absolute_residual = 0;      ///< ... or, if > 0 (replacing the line above), ‖b − R x‖ ≤ this ...
    /// ... or once the residual is at rounding level, ‖b − R x‖ ≤ this · (‖R‖∞ ‖x‖ + ‖b‖): no
    /// smaller residual can be computed in double precision (a normwise backward error; CHOLMOD's
    /// answers have about 1e-16). This is what ends the iteration when α is tiny.
    double backward_error = 1e-15;
    int max_iterations = 20000;
    /// Called after every iteration with the iteration count, ‖b − R x‖ (recursive) and the
    /// residual the stop needs (from the calling thread; may throw to abandon the solve).
    std::function<void(int iteration, double residual, double target)> monitor;
};

struct CgResult {
    int iterations = 0;
    bool converged = false;
};

/// PCG on R x = b from the initial guess in x. The test is made on the recursively updated
/// residual and confirmed on the true one b − R x; if they disagree (rounding drift), CG restarts
/// from the true residual.
/// `infinity_norm` is ‖R‖∞ (largest absolute row sum), for the rounding floor.
CgResult preconditioned_conjugate_gradient(const LinearOperator& R, double infinity_norm, const Eigen::VectorXd& b,
                                           Eigen::VectorXd& x, const Preconditioner& preconditioner, const CgStop& stop);
/// The same with an assembled matrix.
CgResult preconditioned_conjugate_gradient(const ScalarRows& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                           const Preconditioner& preconditioner, const CgStop& stop);

/// ‖R‖∞ of an assembled matrix.
double infinity_norm(const ScalarRows& R);

}  // namespace dsreg::detail
