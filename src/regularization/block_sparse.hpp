// dsreg — internal: sparse matrices made of 3×3 blocks, for the multigrid hierarchy of
// smoothed_aggregation.cpp. Vectors are interleaved (entry 3i + d is component d of node i), as
// everywhere in the regularization stage.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <omp.h>

#include <algorithm>
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

/// Builds a block matrix row by row in parallel (Gustavson): `fill_row(i, block)` adds into
/// `block(j)`, a zero-initialized 3×3 accumulator for column j of row i; `row_bound(i)` is an upper
/// bound on the blocks of row i. Each thread fills a contiguous range of rows into a piece reserved
/// from the bounds (no reallocation: memory is touched once), then copies it into place.
template <class FillRow, class RowBound>
BlockMatrix build_by_rows(std::int64_t rows, std::int64_t cols, FillRow fill_row, RowBound row_bound) {
    const int threads = rows >= kParallelMinRows ? omp_get_max_threads() : 1;
    std::vector<std::int64_t> row_count(static_cast<std::size_t>(rows), 0);
    std::vector<std::int64_t> piece_first(static_cast<std::size_t>(threads) + 1, 0);
    BlockMatrix out;
    out.rows = rows;
    out.cols = cols;
    out.start.assign(std::size_t(rows + 1), 0);
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const std::int64_t first = rows * t / nt, last = rows * (t + 1) / nt;
        std::vector<std::int32_t> slot(static_cast<std::size_t>(cols), -1);
        std::int64_t bound = 0;
        for (std::int64_t i = first; i < last; ++i) bound += std::min<std::int64_t>(row_bound(i), cols);
        std::vector<std::int32_t> columns;
        std::vector<Eigen::Matrix3d> blocks;
        columns.reserve(std::size_t(bound));
        blocks.reserve(std::size_t(bound));
        for (std::int64_t i = first; i < last; ++i) {
            const std::size_t row_begin = columns.size();
            const auto block = [&](std::int32_t j) -> Eigen::Matrix3d& {
                std::int32_t& s = slot[std::size_t(j)];
                if (s < 0) {
                    s = std::int32_t(columns.size() - row_begin);
                    columns.push_back(j);
                    blocks.push_back(Eigen::Matrix3d::Zero());
                }
                return blocks[row_begin + std::size_t(s)];
            };
            fill_row(i, block);
            for (std::size_t q = row_begin; q < columns.size(); ++q) slot[std::size_t(columns[q])] = -1;
            row_count[std::size_t(i)] = std::int64_t(columns.size() - row_begin);
        }
        piece_first[std::size_t(t) + 1] = std::int64_t(columns.size());
#pragma omp barrier
#pragma omp single
        {
            for (int p = 0; p < nt; ++p) piece_first[std::size_t(p) + 1] += piece_first[std::size_t(p)];
            for (std::int64_t i = 0; i < rows; ++i) out.start[std::size_t(i + 1)] = out.start[std::size_t(i)] + row_count[std::size_t(i)];
            out.column.resize(std::size_t(out.start.back()));
            out.block.resize(std::size_t(out.start.back()));
        }  // implicit barrier
        std::copy(columns.begin(), columns.end(), out.column.begin() + piece_first[std::size_t(t)]);
        std::copy(blocks.begin(), blocks.end(), out.block.begin() + piece_first[std::size_t(t)]);
    }
    return out;
}

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
