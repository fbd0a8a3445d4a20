// dsreg — internal: preconditioned conjugate gradients for the SPD regularization system, with a
// stopping test that stays meaningful when α is tiny.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "block_sparse.hpp"

namespace dsreg::detail {

/// z = M⁻¹ r for an SPD preconditioner M.
using Preconditioner = std::function<void(const Eigen::VectorXd& r, Eigen::VectorXd& z)>;

struct CgStop {
    double relative_residual = 1e-10;  ///< stop once ‖b − R x‖ ≤ this · ‖b‖ ...
    double absolute_residual = 0;      ///< ... or, if > 0 (replacing the line above), ‖b − R x‖ ≤ this ...
    /// ... or once the residual is at rounding level, ‖b − R x‖ ≤ this · (‖R‖∞ ‖x‖ + ‖b‖): no
    /// smaller residual can be computed in double precision (a normwise backward error; CHOLMOD's
    /// answers have about 1e-16). This is what ends the iteration when α is tiny.
    double backward_error = 1e-15;
    int max_iterations = 20000;
};

struct CgResult {
    int iterations = 0;
    bool converged = false;
};

/// PCG on R x = b from the initial guess in x. The test is made on the recursively updated
/// residual and confirmed on the true one b − R x; if they disagree (rounding drift), CG restarts
/// from the true residual.
CgResult preconditioned_conjugate_gradient(const ScalarRows& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                           const Preconditioner& preconditioner, const CgStop& stop);

}  // namespace dsreg::detail
