// dsreg — internal: the linear algebra of the box-constrained QP (box_qp.hpp) — products with R,
// its diagonal, and solves with R whose "held" coordinates (those fixed at a bound) are
// decoupled:
//
//   R_held = R with the rows and columns of the held coordinates replaced by diag(R_ii),
//
// so that R_held y = r gives y_F = R_FF⁻¹ r_F on the free coordinates and y_i = r_i / R_ii on
// the held ones. Two implementations: CHOLMOD factorizations on one symbolic analysis (exact,
// box_qp.cpp), and conjugate gradients preconditioned by the V-cycle of R restricted to the free
// coordinates (IterativeHeldSolver: no factor in memory, for the large components of the
// clamped mode).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dsreg/box_qp.hpp"
#include "smoothed_aggregation.hpp"
#include "spd_system.hpp"

namespace dsreg::detail {

class HeldSolver {
public:
    virtual ~HeldSolver() = default;
    /// y = R x
    virtual void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const = 0;
    /// diag(R), all entries > 0
    virtual const Eigen::VectorXd& diagonal() const = 0;
    /// The coordinates decoupled by the next solves.
    virtual void hold(const std::vector<bool>& held) = 0;
    /// Solves R_held y = rhs. `y` holds an initial guess on entry (used by iterative solvers) and
    /// the answer on exit; iterative solvers stop once ‖rhs − R_held y‖₂ ≤ tolerance (exact
    /// solvers ignore it). Returns false if the tolerance was not reached.
    virtual bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double tolerance) = 0;
    /// Whether solve() ignores its tolerance (a direct solver).
    virtual bool exact() const = 0;
    /// Numeric factorizations (exact solvers) or CG iterations (iterative) so far.
    virtual int factorizations() const { return 0; }
    virtual int iterations() const { return 0; }
};

/// CG on R_held, preconditioned on the free coordinates by the V-cycle of R's hierarchy set to
/// hold the same coordinates (Multigrid::hold), and by z_i = r_i / R_ii on the held ones. The
/// system and the hierarchy must outlive the solver.
class IterativeHeldSolver : public HeldSolver {
public:
    IterativeHeldSolver(const SpdSystem& system, Multigrid& multigrid, int max_iterations);
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override { system_.multiply(x, y); }
    const Eigen::VectorXd& diagonal() const override { return diagonal_; }
    void hold(const std::vector<bool>& held) override {
        held_indices_.clear();
        for (std::size_t q = 0; q < held.size(); ++q)
            if (held[q]) held_indices_.push_back(Eigen::Index(q));
        multigrid_.hold(held);
    }
    bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double tolerance) override;
    bool exact() const override { return false; }
    int iterations() const override { return iterations_; }

private:
    const SpdSystem& system_;
    Multigrid& multigrid_;
    int max_iterations_;
    Eigen::VectorXd diagonal_;
    std::vector<Eigen::Index> held_indices_;  ///< in increasing order
    int iterations_ = 0;
};

/// `work` (R's pattern, compressed) = R with the rows and columns of the held coordinates
/// reduced to their diagonal entries: R_held, for a factorization.
void mask_held(const Eigen::SparseMatrix<double>& R, const std::vector<bool>& held, Eigen::SparseMatrix<double>& work);

/// out = R_held x from a product with R: the held coordinates of x left out, their rows R_ii x_i.
template <class Multiply>
void held_product(const Multiply& multiply, const std::vector<Eigen::Index>& held_indices, const Eigen::VectorXd& diagonal,
                  const Eigen::VectorXd& x, Eigen::VectorXd& free_part, Eigen::VectorXd& out) {
    free_part = x;
    for (const Eigen::Index i : held_indices) free_part[i] = 0;
    multiply(free_part, out);
    for (const Eigen::Index i : held_indices) out[i] = diagonal[i] * x[i];
}

/// Minimizes ½xᵀRx − bᵀx over the box from x (typically the unconstrained minimizer) with the
/// active set iterations and the projected Newton fallback of box_qp.hpp (no ADMM) on `solver`.
BoxQpReport solve_box_qp_with(HeldSolver& solver, const Eigen::VectorXd& b, const Eigen::VectorXd& lower,
                              const Eigen::VectorXd& upper, Eigen::VectorXd& x, const BoxQpOptions& options);

}  // namespace dsreg::detail
