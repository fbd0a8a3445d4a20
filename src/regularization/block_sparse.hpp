// dsreg — internal: sparse matrices made of 3×3 blocks, for the multigrid hierarchy of
// smoothed_aggregation.cpp. Vectors are interleaved (entry 3i + d is component d of node i), as
// everywhere in the regularization stage.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <omp.h>

#include <algorithm>
#include <cassert>
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
/// The blocks are stored in `Scalar` (double, or float for the multigrid hierarchy: half the
/// memory and memory traffic); every computation on them is made in double.
template <class Scalar>
struct BlockMatrixT {
    using Block = Eigen::Matrix<Scalar, 3, 3>;
    std::int64_t rows = 0;  ///< block rows (nodes)
    std::int64_t cols = 0;  ///< block columns
    std::vector<std::int64_t> start{0};
    std::vector<std::int32_t> column;
    std::vector<Block> block;

    std::int64_t block_count() const { return std::int64_t(column.size()); }
    Eigen::Matrix3d block_at(std::int64_t q) const { return block[std::size_t(q)].template cast<double>(); }
    /// y = A x (parallel over block rows).
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
    /// y = Aᵀ x (parallel over block rows; `scratch` holds one accumulator per thread).
    void multiply_transposed(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::vector<Eigen::VectorXd>& scratch) const;
    /// The same matrix as scalar column-major CSC (for CHOLMOD on the coarsest level).
    Eigen::SparseMatrix<double> to_scalar() const;
};
using BlockMatrix = BlockMatrixT<double>;

/// The accumulators of one block row while it is built (Gustavson): block(j) is a zero-initialized
/// 3×3 double accumulator for column j, created at its first use; columns keep that order.
class BlockRowAccumulator {
public:
    explicit BlockRowAccumulator(std::int64_t cols) : slot_(static_cast<std::size_t>(cols), -1) {}
    Eigen::Matrix3d& block(std::int32_t j) {
        std::int32_t& s = slot_[std::size_t(j)];
        if (s < 0) {
            s = std::int32_t(blocks_.size());
            columns_.push_back(j);
            blocks_.push_back(Eigen::Matrix3d::Zero());
        }
        return blocks_[std::size_t(s)];
    }
    /// Counts column j once (a pattern pass: a row uses either mark or block); count() gives the
    /// distinct columns since clear().
    void mark(std::int32_t j) {
        std::int32_t& s = slot_[std::size_t(j)];
        if (s < 0) {
            s = 0;
            columns_.push_back(j);
        }
    }
    std::size_t count() const { return columns_.size(); }
    std::int32_t* columns() { return columns_.data(); }
    Eigen::Matrix3d* blocks() { return blocks_.data(); }
    void clear() {
        for (std::int32_t j : columns_) slot_[std::size_t(j)] = -1;
        columns_.clear();
        blocks_.clear();
    }

private:
    std::vector<std::int32_t> slot_;  ///< per column: its accumulator in this row, or −1
    std::vector<std::int32_t> columns_;
    std::vector<Eigen::Matrix3d> blocks_;
};

/// Builds a block matrix row by row in parallel (Gustavson): `fill_row(i, block)` adds into
/// `block(j)`, a zero-initialized 3×3 double accumulator for column j of row i; `row_bound(i)` is
/// an upper bound on the blocks of row i. Each thread fills a contiguous range of rows into a
/// piece reserved from the bounds (no reallocation: memory is touched once), then copies it into
/// place. When a row is complete, `finish_row(i, columns, blocks, count)` may still change its
/// accumulators; then they are rounded to Scalar. (build_by_pattern needs no pieces, where a
/// row's columns are cheap to list.)
template <class Scalar, class FillRow, class RowBound, class FinishRow>
BlockMatrixT<Scalar> build_by_rows(std::int64_t rows, std::int64_t cols, FillRow fill_row, RowBound row_bound, FinishRow finish_row) {
    using Block = typename BlockMatrixT<Scalar>::Block;
    const int threads = rows >= kParallelMinRows ? omp_get_max_threads() : 1;
    std::vector<std::int64_t> row_count(static_cast<std::size_t>(rows), 0);
    std::vector<std::int64_t> piece_first(static_cast<std::size_t>(threads) + 1, 0);
    BlockMatrixT<Scalar> out;
    out.rows = rows;
    out.cols = cols;
    out.start.assign(std::size_t(rows + 1), 0);
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const std::int64_t first = rows * t / nt, last = rows * (t + 1) / nt;
        BlockRowAccumulator row(cols);
        std::int64_t bound = 0;
        for (std::int64_t i = first; i < last; ++i) bound += std::min<std::int64_t>(row_bound(i), cols);
        std::vector<std::int32_t> columns;
        std::vector<Block> blocks;
        columns.reserve(std::size_t(bound));
        blocks.reserve(std::size_t(bound));
        for (std::int64_t i = first; i < last; ++i) {
            row.clear();
            fill_row(i, [&](std::int32_t j) -> Eigen::Matrix3d& { return row.block(j); });
            finish_row(i, row.columns(), row.blocks(), row.count());
            columns.insert(columns.end(), row.columns(), row.columns() + row.count());
            for (std::size_t q = 0; q < row.count(); ++q) blocks.push_back(row.blocks()[q].cast<Scalar>());
            row_count[std::size_t(i)] = std::int64_t(row.count());
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

template <class Scalar, class FillRow, class RowBound>
BlockMatrixT<Scalar> build_by_rows(std::int64_t rows, std::int64_t cols, FillRow fill_row, RowBound row_bound) {
    return build_by_rows<Scalar>(rows, cols, fill_row, row_bound, [](std::int64_t, const std::int32_t*, Eigen::Matrix3d*, std::size_t) {});
}

/// Builds a block matrix row by row in parallel in two passes: `row_pattern(i, mark)` calls
/// mark(j) for every column j of row i (repeats allowed), which sizes the matrix exactly; then
/// `fill_row(i, block)` and `finish_row` as in build_by_rows (fill_row must create the same
/// columns) write each row straight into place. No piece is copied, so the matrix is the only
/// memory the build touches (the pieces of build_by_rows double it for a moment: the multigrid
/// set-up's peak on lobster.vol).
template <class Scalar, class RowPattern, class FillRow, class FinishRow>
BlockMatrixT<Scalar> build_by_pattern(std::int64_t rows, std::int64_t cols, RowPattern row_pattern, FillRow fill_row, FinishRow finish_row) {
    const int threads = rows >= kParallelMinRows ? omp_get_max_threads() : 1;
    BlockMatrixT<Scalar> out;
    out.rows = rows;
    out.cols = cols;
    out.start.assign(std::size_t(rows + 1), 0);
#pragma omp parallel num_threads(threads)
    {
        BlockRowAccumulator row(cols);
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < rows; ++i) {
            row.clear();
            row_pattern(i, [&](std::int32_t j) { row.mark(j); });
            out.start[std::size_t(i + 1)] = std::int64_t(row.count());
        }
#pragma omp single
        {
            for (std::int64_t i = 0; i < rows; ++i) out.start[std::size_t(i + 1)] += out.start[std::size_t(i)];
            out.column.resize(std::size_t(out.start.back()));
            out.block.resize(std::size_t(out.start.back()));
        }  // implicit barrier
#pragma omp for schedule(static)
        for (std::int64_t i = 0; i < rows; ++i) {
            row.clear();
            fill_row(i, [&](std::int32_t j) -> Eigen::Matrix3d& { return row.block(j); });
            finish_row(i, row.columns(), row.blocks(), row.count());
            const std::size_t first = std::size_t(out.start[std::size_t(i)]);
            const std::size_t count = std::size_t(out.start[std::size_t(i + 1)]) - first;
            assert(row.count() == count);  // else row_pattern and fill_row disagree
            for (std::size_t q = 0; q < std::min(row.count(), count); ++q) {
                out.column[first + q] = row.columns()[q];
                out.block[first + q] = row.blocks()[q].template cast<Scalar>();
            }
        }
    }
    return out;
}

/// Keeps the upper triangle (the blocks with column ≥ row) of a symmetric block matrix, in place,
/// and gives the memory of the rest back.
template <class Scalar>
void keep_upper_triangle(BlockMatrixT<Scalar>& a);

/// y = A x, or y −= A x if `subtract`, for the symmetric A whose upper triangle is `upper`
/// (keep_upper_triangle): each stored block A_ij gives A_ij x_j to row i and A_ijᵀ x_i to row j,
/// so a level needs half its blocks and reads each once. Rows in parallel, in one contiguous range
/// per thread; what a thread adds to rows beyond its range goes to its accumulator in `scratch`
/// (one per thread but the last, whose range ends the matrix; only the band of rows it reaches is
/// zeroed and summed).
template <class Scalar>
void multiply_symmetric_upper(const BlockMatrixT<Scalar>& upper, const Eigen::VectorXd& x, Eigen::VectorXd& y,
                              std::vector<Eigen::VectorXd>& scratch, bool subtract);

/// The pattern of Pᵀ for a block matrix P, pointing into P's blocks instead of copying them (12
/// bytes per block instead of 40–76): row a of Pᵀ holds the blocks P(row[q], a) = P.block[source[q]]
/// for q in [start[a], start[a+1]), in increasing fine row.
struct TransposedPattern {
    std::vector<std::int64_t> start{0};
    std::vector<std::int32_t> row;
    std::vector<std::int64_t> source;
};
template <class Scalar>
TransposedPattern transposed_pattern(const BlockMatrixT<Scalar>& p);

/// The Galerkin product Pᵀ A P, row by row of Pᵀ: row a is Σ_{i} P(i,a)ᵀ Σ_k A(i,k) P(k,·), summed
/// in double without storing A·P (which would hold about 8 blocks per fine row).
template <class Scalar>
BlockMatrixT<Scalar> galerkin_product(const BlockMatrixT<Scalar>& a, const BlockMatrixT<Scalar>& p, const TransposedPattern& t);

/// The Galerkin product of the free coordinates, Pᵀ (M A M + ε H D H) P, for A stored as its
/// upper triangle (keep_upper_triangle; `lower` = transposed_pattern(A) gives the mirrored
/// blocks): M is the diagonal 0/1 mask of the free coordinates (`held`: one flag per scalar
/// coordinate of A), H = I − M, D = diag(A), ε = `held_weight`. (M P)ᵀ A (M P) alone is the coarse
/// operator of A with the held coordinates decoupled, but only semidefinite where the free
/// coordinates do not tell two coarse basis functions apart (or reach none); the small term of
/// the held coordinates makes it definite and changes nothing along the coarse corrections'
/// directions that the free coordinates see fully.
template <class Scalar>
BlockMatrixT<Scalar> held_galerkin_product(const BlockMatrixT<Scalar>& upper, const TransposedPattern& lower,
                                           const BlockMatrixT<Scalar>& p, const TransposedPattern& t, const std::vector<char>& held,
                                           double held_weight);

/// A copy with the blocks rounded to another precision.
template <class To, class From>
BlockMatrixT<To> convert(const BlockMatrixT<From>& a) {
    BlockMatrixT<To> out;
    out.rows = a.rows;
    out.cols = a.cols;
    out.start = a.start;
    out.column = a.column;
    out.block.resize(a.block.size());
    for (std::size_t q = 0; q < a.block.size(); ++q) out.block[q] = a.block[q].template cast<To>();
    return out;
}

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
template <class Scalar>
BlockMatrixT<Scalar> smoothed_prolongator(const BlockMatrixT<Scalar>& a, const std::vector<Eigen::Matrix3d>& inverse_diagonal,
                                          const StrengthGraph& strong, const std::vector<std::int32_t>& aggregate,
                                          const std::vector<double>& weight, std::int64_t aggregate_count, double omega);

/// A_F: the diagonal blocks and the strong blocks of the scalar matrix A, as a block matrix. Each
/// weak block W_ij is dropped and diag(Σ_c |W_ij(r, c)|) added to the diagonal block instead,
/// which keeps A_F ⪰ A (so positive definite) and, for the weak blocks w·I3 with w > 0 of the
/// fairness term's 2-ring, gives A_F t = A t on translations t.
template <class Scalar = double>
BlockMatrixT<Scalar> filtered_blocks(const ScalarRows& a, const StrengthGraph& strong);

/// Diagonal 3×3 blocks of A (one per node).
std::vector<Eigen::Matrix3d> diagonal_blocks(const ScalarRows& a);
template <class Scalar>
std::vector<Eigen::Matrix3d> diagonal_blocks(const BlockMatrixT<Scalar>& a);

/// y = A x for either kind of level (parallel over rows).
void multiply_operator(const ScalarRows& a, const Eigen::VectorXd& x, Eigen::VectorXd& y);
template <class Scalar>
void multiply_operator(const BlockMatrixT<Scalar>& a, const Eigen::VectorXd& x, Eigen::VectorXd& y) { a.multiply(x, y); }

/// Frobenius norms of the off-diagonal blocks of node row i, visited as (j, ‖A_ij‖_F); the
/// diagonal block norm goes to `diagonal`. `scratch` is n zeros on entry and on exit.
struct BlockRowNorms {
    std::vector<std::int32_t> neighbor;
    std::vector<double> norm;
    double diagonal = 0;
};
void block_row_norms(const ScalarRows& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out);
template <class Scalar>
void block_row_norms(const BlockMatrixT<Scalar>& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out);

}  // namespace dsreg::detail
