#include "conjugate_gradient.hpp"

#include <algorithm>
#include <cmath>

#include "dsreg/error.hpp"

namespace dsreg::detail {

double infinity_norm(const ScalarRows& R) {
    double largest = 0;
#pragma omp parallel for schedule(static) reduction(max : largest)
    for (Eigen::Index i = 0; i < R.rows(); ++i) {
        double sum = 0;
        for (int q = R.outerIndexPtr()[i]; q < R.outerIndexPtr()[i + 1]; ++q) sum += std::abs(R.valuePtr()[q]);
        largest = std::max(largest, sum);
    }
    return largest;
}

CgResult preconditioned_conjugate_gradient(const ScalarRows& R, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                           const Preconditioner& preconditioner, const CgStop& stop) {
    const LinearOperator product = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { multiply_operator(R, in, out); };
    return preconditioned_conjugate_gradient(product, infinity_norm(R), b, x, preconditioner, stop);
}

CgResult preconditioned_conjugate_gradient(const LinearOperator& multiply, double norm_R, const Eigen::VectorXd& b,
                                           Eigen::VectorXd& x, const Preconditioner& preconditioner, const CgStop& stop) {
    const double norm_b = b.norm();
    const auto target = [&](const Eigen::VectorXd& at) {
        const double wanted = stop.absolute_residual > 0 ? stop.absolute_residual : stop.relative_residual * norm_b;
        return std::max(wanted, stop.backward_error * (norm_R * at.norm() + norm_b));
    };
    const int max_restarts = 8;
    Eigen::VectorXd r(b.size()), z(b.size()), p, q(b.size());
    CgResult result;
    for (int restart = 0; restart <= max_restarts; ++restart) {
        multiply(x, q);
        r = b - q;
        if (r.norm() <= target(x)) {
            result.converged = true;
            return result;
        }
        preconditioner(r, z);
        p = z;
        double rz = r.dot(z);
        while (result.iterations < stop.max_iterations) {
            multiply(p, q);
            const double curvature = p.dot(q);
            if (!(curvature > 0) || !(rz > 0))
                throw Error("conjugate gradient: the matrix or the preconditioner is not positive definite (iteration " +
                            std::to_string(result.iterations) + ", pᵀRp = " + std::to_string(curvature) + ", rᵀz = " + std::to_string(rz) + ")");
            const double step = rz / curvature;
            x += step * p;
            r -= step * q;
            ++result.iterations;
            const double residual = r.norm(), wanted = target(x);
            if (stop.monitor) stop.monitor(result.iterations, residual, wanted);
            if (residual <= wanted) break;  // confirm on the true residual above
            preconditioner(r, z);
            const double rz_next = r.dot(z);
            p = z + (rz_next / rz) * p;
            rz = rz_next;
        }
        if (result.iterations >= stop.max_iterations) break;
    }
    multiply(x, q);
    result.converged = (b - q).norm() <= target(x);
    return result;
}

}  // namespace dsreg::detail
