// dsreg internal — the linear solver of the Ambrosio–Tortorelli rounds (see
// ambrosio_tortorelli.hpp): a CHOLMOD factor of a fixed sparsity pattern, analysed once and
// refactorized numerically, and a solver that refines with an older factor before refactorizing.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cholmod.h>
#include <string>

#include "dsreg/ambrosio_tortorelli.hpp"

namespace dsreg::at_detail {

/// Cholesky factor of a symmetric positive definite matrix given by its lower triangle
/// (compressed columns, int indices), through CHOLMOD. The pattern is analysed by the first
/// factorize() (METIS nested-dissection ordering, AMD if CHOLMOD has no METIS; CHOLMOD chooses
/// a simplicial or supernodal factor); later calls must keep that pattern and only redo the
/// numbers. Solves use a simplicial copy of a supernodal factor: its triangular solves are about
/// twice as fast on these surface graphs, which matters for the refinement iterations.
class CholeskyFactor {
public:
    explicit CholeskyFactor(std::string name);
    ~CholeskyFactor();
    CholeskyFactor(const CholeskyFactor&) = delete;
    CholeskyFactor& operator=(const CholeskyFactor&) = delete;

    /// The symbolic analysis of the pattern, once (the first factorize() does it). Not to be run
    /// concurrently with another analysis: METIS keeps its random state in globals.
    void analyse(const Eigen::SparseMatrix<double>& lower);
    /// Throws dsreg::Error if the matrix is not positive definite.
    void factorize(const Eigen::SparseMatrix<double>& lower);
    /// K⁻¹ B for the last factorized K, every column at once.
    Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;

    bool factorized() const { return factorized_; }
    bool supernodal() const { return factor_ != nullptr && factor_->is_super; }

    static constexpr double kSupernodalSwitch = 200;  ///< CHOLMOD's flops/entries threshold
    double nonzeros() const { return nonzeros_; }

private:
    std::string name_;
    mutable cholmod_common common_;
    cholmod_factor* factor_ = nullptr;  ///< as factorized (supernodal or simplicial)
    cholmod_factor* solver_ = nullptr;  ///< simplicial copy of a supernodal factor_, else null
    mutable cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;  ///< cholmod_solve2 workspace
    bool factorized_ = false;
    double nonzeros_ = 0;
    double flops_ = 0;  ///< of the factorization, from the analysis
};

/// Solves K X = B for a sequence of matrices K of one pattern (one per AT round). A new K is
/// first solved by conjugate gradients preconditioned with the factor of an earlier K, started
/// from the previous solution X: in the later rounds of an ε, K changes little and a few
/// iterations (each two triangular solves) reach the tolerance. When the residual decrease
/// predicts more than kMaxIterations, or `reuse` is false, K is refactorized and solved directly.
class RefactoringSolver {
public:
    static constexpr double kTolerance = 1e-10;  ///< relative residual of a refined solve
    static constexpr int kMaxIterations = 8;     ///< about the cost of one factorization

    explicit RefactoringSolver(const std::string& name) : factor_(name), name_(name) {}

    /// X: the previous solution on entry (ignored if its size differs), the solution on exit.
    /// Returns the largest relative residual ‖K x_j − b_j‖/‖b_j‖ over the columns.
    double solve(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& B, Eigen::MatrixXd& X, bool reuse,
                 AtSolveStats& stats);

    double factor_nonzeros() const { return factor_.nonzeros(); }

private:
    bool refine(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& B, Eigen::MatrixXd& X,
                int& iterations) const;

    CholeskyFactor factor_;
    std::string name_;
};

}  // namespace dsreg::at_detail
