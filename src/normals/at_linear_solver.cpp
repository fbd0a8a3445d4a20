// The linear solver of the Ambrosio–Tortorelli rounds (see at_linear_solver.hpp).
#include "at_linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <limits>

#include "../regularization/blas_threads.hpp"
#include "dsreg/error.hpp"

namespace dsreg::at_detail {

namespace {

/// CHOLMOD's view of the lower triangle of a symmetric matrix (no copy).
cholmod_sparse lower_view(const Eigen::SparseMatrix<double>& lower) {
    cholmod_sparse A = Eigen::viewAsCholmod(lower);
    A.stype = -1;  // symmetric, lower triangle stored
    return A;
}

/// ‖K x − b‖ / ‖b‖ per column, for a symmetric K stored as its lower triangle.
double worst_relative_residual(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& X,
                               const Eigen::MatrixXd& B) {
    const Eigen::MatrixXd R = lower.selfadjointView<Eigen::Lower>() * X - B;
    double worst = 0;
    for (Eigen::Index j = 0; j < B.cols(); ++j) {
        const double norm_b = B.col(j).norm();
        worst = std::max(worst, norm_b > 0 ? R.col(j).norm() / norm_b : R.col(j).norm());
    }
    return worst;
}

/// Iterations the slowest column needs at the mean rate of decrease seen in `done` of them.
double predicted_iterations(const Eigen::ArrayXd& initial, const Eigen::ArrayXd& now, const Eigen::ArrayXd& target,
                            int done) {
    double worst = done;
    for (Eigen::Index j = 0; j < now.size(); ++j) {
        if (now[j] <= target[j]) continue;
        const double rate = std::log(now[j] / initial[j]) / done;  // < 0 when decreasing
        if (!(rate < 0)) return std::numeric_limits<double>::infinity();
        worst = std::max(worst, done + std::log(target[j] / now[j]) / rate);
    }
    return worst;
}

}  // namespace

// ---- CholeskyFactor ----------------------------------------------------------------------------

CholeskyFactor::CholeskyFactor(std::string name) : name_(std::move(name)) { cholmod_start(&common_); }

CholeskyFactor::~CholeskyFactor() {
    cholmod_free_dense(&x_, &common_);
    cholmod_free_dense(&y_, &common_);
    cholmod_free_dense(&e_, &common_);
    cholmod_free_factor(&solver_, &common_);
    cholmod_free_factor(&factor_, &common_);
    cholmod_finish(&common_);
}

void CholeskyFactor::analyse(const Eigen::SparseMatrix<double>& lower) {
    if (factor_ != nullptr) return;
    cholmod_sparse A = lower_view(lower);
    // Nested dissection: on these surface graphs it halves the flops of every factorization
    // compared with AMD, and it runs once.
    common_.nmethods = 1;
    common_.method[0].ordering = CHOLMOD_METIS;
    // Supernodal (BLAS) factors only pay off for large fronts: below about 200 flops per factor
    // entry (up to some 10⁵ faces here) the simplicial factorization is as fast and its solves faster.
    common_.supernodal_switch = kSupernodalSwitch;
    factor_ = cholmod_analyze(&A, &common_);
    if (factor_ == nullptr) {
        common_.status = CHOLMOD_OK;
        common_.method[0].ordering = CHOLMOD_AMD;
        factor_ = cholmod_analyze(&A, &common_);
    }
    if (factor_ == nullptr) throw Error("Ambrosio-Tortorelli: CHOLMOD could not analyse the " + name_ + "-matrix");
    nonzeros_ = common_.lnz;
    flops_ = common_.fl;
}

void CholeskyFactor::factorize(const Eigen::SparseMatrix<double>& lower) {
    analyse(lower);
    cholmod_sparse A = lower_view(lower);
    factorized_ = false;
    detail::use_blas_threads_for(flops_);
    cholmod_factorize(&A, factor_, &common_);
    if (common_.status != CHOLMOD_OK || factor_->minor != factor_->n)
        throw Error("Ambrosio-Tortorelli: CHOLMOD could not factor the " + name_ + "-matrix (not positive definite)");
    cholmod_free_factor(&solver_, &common_);
    if (factor_->is_super) {
        solver_ = cholmod_copy_factor(factor_, &common_);
        if (solver_ == nullptr || !cholmod_change_factor(CHOLMOD_REAL, true, false, true, true, solver_, &common_))
            throw Error("Ambrosio-Tortorelli: CHOLMOD could not convert the " + name_ + "-factor");
    }
    factorized_ = true;
}

Eigen::MatrixXd CholeskyFactor::solve(const Eigen::MatrixXd& B) const {
    Eigen::MatrixXd input = B;  // CHOLMOD's dense view needs a mutable pointer
    cholmod_dense b = Eigen::viewAsCholmod(input);
    cholmod_factor* L = solver_ != nullptr ? solver_ : factor_;
    if (!cholmod_solve2(CHOLMOD_A, L, &b, nullptr, &x_, nullptr, &y_, &e_, &common_))
        throw Error("Ambrosio-Tortorelli: the " + name_ + "-solve failed");
    Eigen::MatrixXd X = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_->x), B.rows(), B.cols());
    if (!X.allFinite()) throw Error("Ambrosio-Tortorelli: the " + name_ + "-solve gave non-finite values");
    return X;
}

// ---- RefactoringSolver -------------------------------------------------------------------------

double RefactoringSolver::solve(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& B, Eigen::MatrixXd& X,
                                bool reuse, AtSolveStats& stats) {
    if (factor_.factorized() && reuse && X.rows() == B.rows() && X.cols() == B.cols()) {
        int iterations = 0;
        const bool converged = refine(lower, B, X, iterations);
        stats.refinement_iterations += iterations;
        if (converged) {
            ++stats.refined_solves;
            return worst_relative_residual(lower, X, B);
        }
    }
    factor_.factorize(lower);
    ++stats.factorizations;
    X = factor_.solve(B);  // one factorization, every column
    return worst_relative_residual(lower, X, B);
}

/// Conjugate gradients on each column (its own step lengths), preconditioned by the factor of an
/// earlier matrix; true when every column reaches kTolerance. Gives up as soon as the residual
/// decrease observed so far predicts more than kMaxIterations.
bool RefactoringSolver::refine(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& B, Eigen::MatrixXd& X,
                               int& iterations) const {
    const auto K = lower.selfadjointView<Eigen::Lower>();
    const Eigen::ArrayXd target = kTolerance * B.colwise().norm().transpose().array();
    Eigen::MatrixXd R = B - K * X;
    const Eigen::ArrayXd initial = R.colwise().norm().transpose().array();
    if ((initial <= target).all()) return true;
    Eigen::MatrixXd Z = factor_.solve(R);
    Eigen::MatrixXd P = Z;
    Eigen::ArrayXd rz = (R.array() * Z.array()).colwise().sum().transpose();
    for (iterations = 1; iterations <= kMaxIterations; ++iterations) {
        const Eigen::MatrixXd Q = K * P;
        const Eigen::ArrayXd step = rz / (P.array() * Q.array()).colwise().sum().transpose();
        X += P * step.matrix().asDiagonal();
        R -= Q * step.matrix().asDiagonal();
        const Eigen::ArrayXd norm = R.colwise().norm().transpose().array();
        if ((norm <= target).all()) return true;
        if (predicted_iterations(initial, norm, target, iterations) > kMaxIterations) return false;
        Z = factor_.solve(R);
        const Eigen::ArrayXd rz_next = (R.array() * Z.array()).colwise().sum().transpose();
        P = Z + P * (rz_next / rz).matrix().asDiagonal();
        rz = rz_next;
    }
    iterations = kMaxIterations;
    return false;
}

}  // namespace dsreg::at_detail
