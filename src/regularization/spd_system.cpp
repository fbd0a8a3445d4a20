#include "spd_system.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "../common/ordered_sum.hpp"
#include "conjugate_gradient.hpp"

namespace dsreg::detail {

AssembledSystem::AssembledSystem(const Eigen::SparseMatrix<double>& R)
    : R_(R), diagonal_(detail::diagonal_blocks(row_view(R))), infinity_norm_(detail::infinity_norm(row_view(R))) {}

void AssembledSystem::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const { multiply_operator(row_view(R_), x, y); }

/// min_i (R·t_d)_i / mean_i R_ii, with t_d the translations: for eq. (23) the numerator is
/// α·min w0 (K annihilates translations), so this is the weight of the data term relative to the
/// whole diagonal: the smaller it is, the more ill-conditioned R (and the slower any CG).
double AssembledSystem::data_weight_ratio() const {
    const ScalarRows rows = row_view(R_);
    // The minimum is exact in any order; the trace is summed in an order fixed by R (ordered_sum.hpp).
    const std::int64_t blocks = sum_blocks(rows.rows());
    std::vector<double> block_diagonal(static_cast<std::size_t>(blocks), 0.0);
    double smallest = std::numeric_limits<double>::infinity();
#pragma omp parallel for schedule(static) reduction(min : smallest)
    for (std::int64_t b = 0; b < blocks; ++b)
        for (Eigen::Index i = block_first(b); i < block_last(b, rows.rows()); ++i) {
            double same_coordinate = 0;
            for (int q = rows.outerIndexPtr()[i]; q < rows.outerIndexPtr()[i + 1]; ++q) {
                const Eigen::Index j = rows.innerIndexPtr()[q];
                if (j % 3 == i % 3) same_coordinate += rows.valuePtr()[q];
                if (j == i) block_diagonal[std::size_t(b)] += rows.valuePtr()[q];
            }
            smallest = std::min(smallest, same_coordinate);
        }
    double diagonal = 0;
    for (const double d : block_diagonal) diagonal += d;
    return rows.rows() > 0 && diagonal > 0 ? smallest / (diagonal / double(rows.rows())) : 0.0;
}

std::unique_ptr<Multigrid> AssembledSystem::multigrid(const AmgSettings& settings) const {
    return make_multigrid(R_, data_weight_ratio(), settings);
}

OperatorSystem::OperatorSystem(const RegularizationOperator& R, double smallest_data_weight)
    : R_(R), summary_(R.summary()), smallest_data_weight_(smallest_data_weight) {}

double OperatorSystem::data_weight_ratio() const {
    return summary_.mean_diagonal > 0 ? smallest_data_weight_ / summary_.mean_diagonal : 0.0;
}

const std::vector<Eigen::Matrix3d>& OperatorSystem::diagonal_blocks() const {
    if (summary_.diagonal.empty()) summary_.diagonal = R_.summary().diagonal;
    return summary_.diagonal;
}

std::unique_ptr<Multigrid> OperatorSystem::multigrid(const AmgSettings& settings) const {
    std::unique_ptr<Multigrid> amg = make_multigrid(R_, diagonal_blocks(), summary_.scalar_nonzeros, data_weight_ratio(), settings);
    // 72 bytes per vertex that the solve does not read (lobster.vol: 18 MB of the run's peak).
    std::vector<Eigen::Matrix3d>().swap(summary_.diagonal);
    return amg;
}

const Eigen::SparseMatrix<double>& OperatorSystem::matrix() const {
    if (!assembled_) {
        assembled_.emplace();
        assemble_matrix(R_, *assembled_);
    }
    return *assembled_;
}

SolverOptions completed_options(const SolverOptions& options, const RegularizationWeights& weights, std::int64_t vertex_count,
                                double smallest_spacing) {
    SolverOptions o = options;
    if (!(o.smallest_eigenvalue > 0)) o.smallest_eigenvalue = smallest_eigenvalue_bound(weights, vertex_count);
    if (o.max_error == 0 && o.max_error_voxels > 0) o.max_error = o.max_error_voxels * smallest_spacing;
    return o;
}

MeshSystem::MeshSystem(const PointMatrix& positions, const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
                       const RegularizationWeights& weights)
    : operator_(quads, links, normals, weights, positions.rows()),
      rhs_(regularization_right_hand_side(positions, links, weights).rhs),
      system_(operator_, smallest_eigenvalue_bound(weights, positions.rows())) {}

}  // namespace dsreg::detail
