// dsreg — internal: sparse matrices made of 3×3 blocks, for the multigrid hierarchy of
// smoothed_aggregation.cpp. Vectors are interleaved (entry 3i + d is component d of node i), as
// everywhere in the regularization stage.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace dsreg::detail {

/// Loops over fewer block rows than this run on one thread: a parallel region costs more than
/// the work, and far more when other processes share the cores.
constexpr std::int64_t kParallelMinRows = 4096;

/// The fine matrix R (symmetric, both triangles, column-major) read as row-major CSR: for a
/// symmetric matrix the two layouts share their arrays, so this is a view, not a copy.
using ScalarRows = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>>;
ScalarRows row_view(const Eigen::SparseMatrix<double>& symmetric);

/// Block compressed sparse rows: block (i, column[q]) = block[q] for q in [start[i], start[i+1]).
/// Columns are not sorted within a block row (they come in the order the products find them).
struct BlockMatrix {
    std::int64_t rows = 0;  ///< block rows (nodes)
    std::int64_t cols = 0;  ///< block columns
    std::vector<std::int64_t> start{0};
    std::vector<std::int32_t> column;
    std::vector<Eigen::Matrix3d> block;

    std::int64_t block_count() const { return std::int64_t(column.size()); }
    /// y = A x (parallel over block rows).
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
    /// The same matrix as scalar column-major CSC (for CHOLMOD on the coarsest level).
    Eigen::SparseMatrix<double> to_scalar() const;
};

BlockMatrix transpose(const BlockMatrix& a);

/// A·B for block matrices.
BlockMatrix multiply(const BlockMatrix& a, const BlockMatrix& b);

/// Node graph of the strong couplings: the strong neighbours of i are
/// neighbour[start[i]] … neighbour[start[i+1] − 1].
struct StrengthGraph {
    std::vector<std::int64_t> start{0};
    std::vector<std::int32_t> neighbour;
};

/// The smoothed prolongator of smoothed aggregation, P = (I − ω D⁻¹ A_F) T, where the tentative
/// prolongator T maps coarse node a to the fine nodes of aggregate a: T(i, a) = weight[i]·I3 if
/// aggregate[i] = a (the rigid translations restricted to each aggregate), D = diagonal blocks
/// of A, and A_F = A without its weak blocks, each added to the diagonal block of its row (so
/// A_F and A agree on translations; Vaněk, Mandel, Brezina 1996, §4). Dropping the weak blocks
/// keeps P, and so the coarse operators, sparse.
BlockMatrix smoothed_prolongator(const BlockMatrix& a, const std::vector<Eigen::Matrix3d>& inverse_diagonal,
                                 const StrengthGraph& strong, const std::vector<std::int32_t>& aggregate,
                                 const std::vector<double>& weight, std::int64_t aggregate_count, double omega);

/// A_F: the diagonal blocks and the strong blocks of the scalar matrix A, as a block matrix. Each
/// weak block W_ij is dropped and diag(Σ_c |W_ij(r, c)|) added to the diagonal block instead,
/// which keeps A_F ⪰ A (so positive definite) and, for the weak blocks w·I3 with w > 0 of the
/// fairness term's 2-ring, gives A_F t = A t on translations t.
BlockMatrix filtered_blocks(const ScalarRows& a, const StrengthGraph& strong);

/// Diagonal 3×3 blocks of A (one per node).
std::vector<Eigen::Matrix3d> diagonal_blocks(const ScalarRows& a);
std::vector<Eigen::Matrix3d> diagonal_blocks(const BlockMatrix& a);

/// y = A x for either kind of level (parallel over rows).
void multiply_operator(const ScalarRows& a, const Eigen::VectorXd& x, Eigen::VectorXd& y);
inline void multiply_operator(const BlockMatrix& a, const Eigen::VectorXd& x, Eigen::VectorXd& y) { a.multiply(x, y); }

/// Frobenius norms of the off-diagonal blocks of node row i, visited as (j, ‖A_ij‖_F); the
/// diagonal block norm goes to `diagonal`. `scratch` is n zeros on entry and on exit.
struct BlockRowNorms {
    std::vector<std::int32_t> neighbor;
    std::vector<double> norm;
    double diagonal = 0;
};
void block_row_norms(const ScalarRows& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out);
void block_row_norms(const BlockMatrix& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out);

}  // namespace dsreg::detail
