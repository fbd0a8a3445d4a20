#include "smoothed_aggregation.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "blas_threads.hpp"
#include "dsreg/error.hpp"
#include "regularization_operator.hpp"

namespace dsreg::detail {

template <class Scalar>
struct SmoothedAggregation<Scalar>::Level {
    /// level 0: R without its weak blocks (filtered_blocks); then Pᵀ A P. Once the next level is
    /// built (every level but the coarsest, which is factored), only its upper triangle is kept:
    /// the V-cycle multiplies by it with multiply_symmetric_upper.
    Matrix op;
    std::int64_t blocks = 0;  ///< of the whole op (both triangles): operator_complexity()
    std::int64_t nodes = 0;
    std::vector<typename Matrix::Block> inverse_diagonal;
    double lambda_max = 0;  ///< upper estimate of the largest eigenvalue of D⁻¹A (Lanczos)
    Matrix prolongator;     ///< P: next coarser level → this level
    mutable Eigen::VectorXd residual, direction, coarse_rhs, coarse_solution, masked;
    mutable std::vector<Eigen::VectorXd> restriction_scratch;  ///< Pᵀ r: one accumulator per thread
    mutable std::vector<Eigen::VectorXd> product_scratch;      ///< A x: multiply_symmetric_upper
};

template <class Scalar>
struct SmoothedAggregation<Scalar>::Coarsest {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> cholesky;
};

/// The coarse levels while coordinates are held (SmoothedAggregation::hold).
template <class Scalar>
struct SmoothedAggregation<Scalar>::HeldCoarse {
    struct Operator {
        Matrix op;  ///< upper triangle (the coarsest level is factored instead)
        std::vector<typename Matrix::Block> inverse_diagonal;
        double lambda_max = 0;
    };
    std::vector<Operator> levels;  ///< levels 1 … coarsest − 1
    Coarsest coarsest;
};

namespace {

std::vector<Eigen::Matrix3d> inverted(const std::vector<Eigen::Matrix3d>& blocks) {
    std::vector<Eigen::Matrix3d> inverse(blocks.size());
#pragma omp parallel for schedule(static) if (std::int64_t(blocks.size()) >= kParallelMinRows)
    for (std::int64_t i = 0; i < std::int64_t(blocks.size()); ++i) inverse[std::size_t(i)] = blocks[std::size_t(i)].inverse();
    for (const Eigen::Matrix3d& b : inverse)
        if (!b.allFinite()) throw Error("algebraic multigrid: a diagonal 3x3 block of the matrix is singular");
    return inverse;
}

template <class Block>
void apply_block_diagonal(const std::vector<Block>& blocks, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    y.resize(x.size());
#pragma omp parallel for schedule(static) if (std::int64_t(blocks.size()) >= kParallelMinRows)
    for (std::int64_t i = 0; i < std::int64_t(blocks.size()); ++i)
        y.segment<3>(3 * i) = blocks[std::size_t(i)].template cast<double>() * x.segment<3>(3 * i);
}

/// Upper estimate of λmax(D⁻¹A) by k steps of Lanczos in the D inner product (D⁻¹A is
/// self-adjoint there): the largest Ritz value θ plus the last off-diagonal β_k, which bounds the
/// distance from θ to the spectrum. Power iteration underestimates λmax, and a Chebyshev
/// smoother whose interval misses the top of the spectrum makes the V-cycle indefinite.
template <class Scalar>
double largest_eigenvalue_bound(const BlockMatrixT<Scalar>& a, const std::vector<Eigen::Matrix3d>& diagonal,
                                const std::vector<Eigen::Matrix3d>& inverse_diagonal, int steps) {
    const auto d_norm = [&](const Eigen::VectorXd& v, Eigen::VectorXd& dv) {
        apply_block_diagonal(diagonal, v, dv);
        return std::sqrt(v.dot(dv));
    };
    Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(3 * a.rows, 0.0, 97.0).array().sin() + 0.5;  // any fixed start
    Eigen::VectorXd previous = Eigen::VectorXd::Zero(v.size()), av, w, dw;
    v /= d_norm(v, dw);
    std::vector<double> alpha, beta;
    for (int k = 0; k < steps; ++k) {
        a.multiply(v, av);
        alpha.push_back(v.dot(av));
        apply_block_diagonal(inverse_diagonal, av, w);
        w -= alpha.back() * v + (beta.empty() ? 0.0 : beta.back()) * previous;
        beta.push_back(d_norm(w, dw));
        if (!(beta.back() > 1e-12 * std::abs(alpha.back()))) break;  // invariant subspace found
        previous.swap(v);
        v = w / beta.back();
    }
    const Eigen::Index m = Eigen::Index(alpha.size());
    Eigen::MatrixXd t = Eigen::MatrixXd::Zero(m, m);
    for (Eigen::Index i = 0; i < m; ++i) {
        t(i, i) = alpha[std::size_t(i)];
        if (i + 1 < m) t(i, i + 1) = t(i + 1, i) = beta[std::size_t(i)];
    }
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(t, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff() + beta.back();
}

/// Strong couplings ‖A_ij‖_F ≥ θ √(‖A_ii‖_F ‖A_jj‖_F) of the node graph, made symmetric (j is a
/// strong neighbour of i iff i is one of j). The test alone is symmetric only up to rounding (the
/// two block norms are summed in different orders, and the Galerkin products are symmetric only to
/// rounding): one pair on the threshold would make the filtered fine operator, and with it the
/// preconditioner, unsymmetric, and CG could break down. Rows in parallel.
template <class Operator>
StrengthGraph strong_couplings(const Operator& a, std::int64_t n, const std::vector<Eigen::Matrix3d>& diagonal, double theta) {
    std::vector<double> diagonal_norm(static_cast<std::size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) diagonal_norm[std::size_t(i)] = diagonal[std::size_t(i)].norm();
    const int threads = n >= kParallelMinRows ? omp_get_max_threads() : 1;
    std::vector<std::vector<std::int32_t>> piece(static_cast<std::size_t>(threads));
    std::vector<std::int64_t> count(static_cast<std::size_t>(n) + 1, 0);
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const std::int64_t first = n * t / nt, last = n * (t + 1) / nt;
        std::vector<double> scratch(static_cast<std::size_t>(n), 0.0);
        BlockRowNorms row;
        auto& out = piece[std::size_t(t)];
        for (std::int64_t i = first; i < last; ++i) {
            block_row_norms(a, i, scratch, row);
            const std::size_t before = out.size();
            for (std::size_t q = 0; q < row.neighbor.size(); ++q) {
                const std::int32_t j = row.neighbor[q];
                if (row.norm[q] >= theta * std::sqrt(diagonal_norm[std::size_t(i)] * diagonal_norm[std::size_t(j)])) out.push_back(j);
            }
            count[std::size_t(i) + 1] = std::int64_t(out.size() - before);
        }
    }
    // One-sided graph G (rows in order), then S = G ∪ Gᵀ row by row.
    StrengthGraph one_sided;
    one_sided.start.assign(std::size_t(n + 1), 0);
    for (std::int64_t i = 0; i < n; ++i) one_sided.start[std::size_t(i + 1)] = one_sided.start[std::size_t(i)] + count[std::size_t(i) + 1];
    one_sided.neighbour.reserve(std::size_t(one_sided.start.back()));
    for (auto& p : piece) {
        one_sided.neighbour.insert(one_sided.neighbour.end(), p.begin(), p.end());
        std::vector<std::int32_t>().swap(p);
    }
    std::vector<std::int64_t> tstart(std::size_t(n + 1), 0);
    for (std::int32_t j : one_sided.neighbour) ++tstart[std::size_t(j) + 1];
    for (std::int64_t i = 0; i < n; ++i) tstart[std::size_t(i + 1)] += tstart[std::size_t(i)];
    std::vector<std::int32_t> tneighbour(one_sided.neighbour.size());
    {
        std::vector<std::int64_t> next(tstart.begin(), tstart.end() - 1);
        for (std::int64_t i = 0; i < n; ++i)
            for (std::int64_t q = one_sided.start[std::size_t(i)]; q < one_sided.start[std::size_t(i + 1)]; ++q)
                tneighbour[std::size_t(next[std::size_t(one_sided.neighbour[std::size_t(q)])]++)] = std::int32_t(i);
    }
    StrengthGraph s;
    s.start.assign(std::size_t(n + 1), 0);
    s.neighbour.reserve(one_sided.neighbour.size() + 16);
    std::vector<std::int32_t> merged;
    for (std::int64_t i = 0; i < n; ++i) {
        merged.assign(one_sided.neighbour.begin() + one_sided.start[std::size_t(i)], one_sided.neighbour.begin() + one_sided.start[std::size_t(i + 1)]);
        merged.insert(merged.end(), tneighbour.begin() + tstart[std::size_t(i)], tneighbour.begin() + tstart[std::size_t(i + 1)]);
        std::sort(merged.begin(), merged.end());
        merged.erase(std::unique(merged.begin(), merged.end()), merged.end());
        s.neighbour.insert(s.neighbour.end(), merged.begin(), merged.end());
        s.start[std::size_t(i + 1)] = std::int64_t(s.neighbour.size());
    }
    return s;
}

/// Directional strength of every off-diagonal block of A: the smallest singular value of
/// D_i^(-1/2) A_ij D_j^(-1/2) (D the diagonal blocks), i.e. how strongly i and j are coupled in
/// their weakest direction, relative to each one's own stiffness in that direction. The Frobenius
/// test of strong_couplings sees the alignment blocks β u uᵀ (strong along u, nothing across) as
/// strong: across a thin wall, a spike or a noisy fold, two vertices can then share an aggregate
/// although they move independently along some direction at the cost of the data term only, and
/// those motions are neither in the coarse space (translations per aggregate) nor reduced by the
/// smoother. Per block, in the order of a.column; +inf on the diagonal. A is exactly symmetric
/// (A_ji = A_ijᵀ), and the pair is always computed as in the row of its smaller index, so the
/// strength of (i, j) and (j, i) are the same number.
template <class Scalar>
std::vector<float> directional_strengths(const BlockMatrixT<Scalar>& a, const std::vector<Eigen::Matrix3d>& diagonal) {
    const std::int64_t n = a.rows;
    std::vector<Eigen::Matrix3d> inverse_root(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static) if (n >= kParallelMinRows)
    for (std::int64_t i = 0; i < n; ++i) {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
        eigen.computeDirect(0.5 * (diagonal[std::size_t(i)] + diagonal[std::size_t(i)].transpose()));
        const Eigen::Vector3d scale = eigen.eigenvalues().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
        inverse_root[std::size_t(i)] = eigen.eigenvectors() * scale.asDiagonal() * eigen.eigenvectors().transpose();
    }
    std::vector<float> strength(a.column.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMinRows)
    for (std::int64_t i = 0; i < n; ++i)
        for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q) {
            const std::int32_t j = a.column[std::size_t(q)];
            if (j == i) {
                strength[std::size_t(q)] = std::numeric_limits<float>::infinity();
                continue;
            }
            const std::int64_t low = std::min<std::int64_t>(i, j), high = std::max<std::int64_t>(i, j);
            const Eigen::Matrix3d block = i < j ? a.block_at(q) : Eigen::Matrix3d(a.block_at(q).transpose());
            const Eigen::Matrix3d m = inverse_root[std::size_t(low)] * block * inverse_root[std::size_t(high)];
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
            eigen.computeDirect(m.transpose() * m, Eigen::EigenvaluesOnly);
            strength[std::size_t(q)] = float(std::sqrt(std::max(0.0, eigen.eigenvalues()[0])));
        }
    return strength;
}

/// The graph of the off-diagonal blocks of directional strength ≥ θ (symmetric: see above).
template <class Scalar>
StrengthGraph directional_graph(const BlockMatrixT<Scalar>& a, const std::vector<float>& strength, double theta) {
    const std::int64_t n = a.rows;
    StrengthGraph g;
    g.start.assign(std::size_t(n + 1), 0);
    const auto strong = [&](std::int64_t i, std::int64_t q) { return a.column[std::size_t(q)] != i && strength[std::size_t(q)] >= theta; };
#pragma omp parallel for schedule(static) if (n >= kParallelMinRows)
    for (std::int64_t i = 0; i < n; ++i) {
        std::int64_t count = 0;
        for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q) count += strong(i, q) ? 1 : 0;
        g.start[std::size_t(i + 1)] = count;
    }
    for (std::int64_t i = 0; i < n; ++i) g.start[std::size_t(i + 1)] += g.start[std::size_t(i)];
    g.neighbour.resize(std::size_t(g.start.back()));
#pragma omp parallel for schedule(static) if (n >= kParallelMinRows)
    for (std::int64_t i = 0; i < n; ++i) {
        std::int64_t out = g.start[std::size_t(i)];
        for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q)
            if (strong(i, q)) g.neighbour[std::size_t(out++)] = a.column[std::size_t(q)];
    }
    return g;
}

/// (A + Aᵀ)/2 in place for a block matrix with a symmetric pattern: the Galerkin product PᵀAP is
/// symmetric only up to rounding, and the smoother and the V-cycle rely on symmetry.
template <class Scalar>
void symmetrize(BlockMatrixT<Scalar>& a) {
    using Block = typename BlockMatrixT<Scalar>::Block;
#pragma omp parallel for schedule(static) if (a.rows >= kParallelMinRows)
    for (std::int64_t i = 0; i < a.rows; ++i) {
        // sort each row by column so that the mirror block can be found by bisection
        const std::int64_t first = a.start[std::size_t(i)], last = a.start[std::size_t(i + 1)];
        std::vector<std::pair<std::int32_t, Block>> row;
        row.reserve(std::size_t(last - first));
        for (std::int64_t q = first; q < last; ++q) row.emplace_back(a.column[std::size_t(q)], a.block[std::size_t(q)]);
        std::sort(row.begin(), row.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        for (std::int64_t q = first; q < last; ++q) {
            a.column[std::size_t(q)] = row[std::size_t(q - first)].first;
            a.block[std::size_t(q)] = row[std::size_t(q - first)].second;
        }
    }
    const auto find = [&](std::int64_t i, std::int32_t j) -> std::int64_t {
        const auto first = a.column.begin() + a.start[std::size_t(i)], last = a.column.begin() + a.start[std::size_t(i + 1)];
        const auto it = std::lower_bound(first, last, j);
        return it != last && *it == j ? std::int64_t(it - a.column.begin()) : -1;
    };
    bool missing = false;
#pragma omp parallel for schedule(static) reduction(|| : missing) if (a.rows >= kParallelMinRows)
    for (std::int64_t i = 0; i < a.rows; ++i)
        for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q) {
            const std::int32_t j = a.column[std::size_t(q)];
            if (j < i) continue;  // each pair once, by its upper block
            if (j == i) {
                const Eigen::Matrix3d b = a.block_at(q);
                a.block[std::size_t(q)] = (0.5 * (b + b.transpose())).template cast<Scalar>();
                continue;
            }
            const std::int64_t mirror = find(j, std::int32_t(i));
            if (mirror < 0) {
                missing = true;
                continue;
            }
            const Block average = (0.5 * (a.block_at(q) + a.block_at(mirror).transpose())).template cast<Scalar>();
            a.block[std::size_t(q)] = average;  // rounded once: the mirror is its exact transpose
            a.block[std::size_t(mirror)] = average.transpose();
        }
    if (missing) throw Error("algebraic multigrid: a coarse operator has an unsymmetric pattern");
}

/// Greedy aggregation (Vaněk et al. 1996): (1) a node whose strong neighbours are all free
/// starts an aggregate with them; (2) a free node joins the aggregate of a strong neighbour;
/// (3) the remaining free nodes group with their free strong neighbours.
std::vector<std::int32_t> aggregate_nodes(const StrengthGraph& strong, std::int64_t n, std::int64_t& count) {
    const auto neighbours = [&](std::int64_t i) {
        return std::make_pair(strong.neighbour.begin() + strong.start[std::size_t(i)], strong.neighbour.begin() + strong.start[std::size_t(i + 1)]);
    };
    std::vector<std::int32_t> aggregate(static_cast<std::size_t>(n), -1);
    count = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        auto [first, last] = neighbours(i);
        bool all_free = aggregate[std::size_t(i)] < 0;
        for (auto it = first; all_free && it != last; ++it) all_free = aggregate[std::size_t(*it)] < 0;
        if (!all_free) continue;
        aggregate[std::size_t(i)] = std::int32_t(count);
        for (auto it = first; it != last; ++it) aggregate[std::size_t(*it)] = std::int32_t(count);
        ++count;
    }
    std::vector<std::int32_t> joined = aggregate;
    for (std::int64_t i = 0; i < n; ++i) {
        if (aggregate[std::size_t(i)] >= 0) continue;
        auto [first, last] = neighbours(i);
        for (auto it = first; it != last; ++it)
            if (aggregate[std::size_t(*it)] >= 0) {
                joined[std::size_t(i)] = aggregate[std::size_t(*it)];
                break;
            }
    }
    aggregate.swap(joined);
    for (std::int64_t i = 0; i < n; ++i) {
        if (aggregate[std::size_t(i)] >= 0) continue;
        aggregate[std::size_t(i)] = std::int32_t(count);
        auto [first, last] = neighbours(i);
        for (auto it = first; it != last; ++it)
            if (aggregate[std::size_t(*it)] < 0) aggregate[std::size_t(*it)] = std::int32_t(count);
        ++count;
    }
    return aggregate;
}

}  // namespace

template <class Scalar>
BlockMatrixT<Scalar> filtered_fine_level(const RegularizationOperator& R, const std::vector<Eigen::Matrix3d>& diagonal, double theta) {
    const std::int64_t n = R.vertex_count();
    std::vector<double> diagonal_norm(static_cast<std::size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) diagonal_norm[std::size_t(i)] = diagonal[std::size_t(i)].norm();
    const int threads = n >= kParallelMinRows ? omp_get_max_threads() : 1;
    std::vector<RegularizationOperator::Row> rows;
    for (int t = 0; t < threads; ++t) rows.emplace_back(n);
    return build_by_rows<Scalar>(
        n, n,
        [&](std::int64_t j, auto&& block) {
            RegularizationOperator::Row& row = rows[std::size_t(omp_get_thread_num())];
            R.row(j, row, true);
            Eigen::Vector3d lumped = Eigen::Vector3d::Zero();
            for (std::size_t q = 0; q < row.columns.size(); ++q) {
                const std::int32_t k = row.columns[q];
                const Eigen::Matrix3d& b = row.blocks[q];
                // ‖A_jk‖ computed on the block of the lower row, so that the test is symmetric
                const Eigen::Matrix3d upper = k >= j ? b : Eigen::Matrix3d(b.transpose());
                const bool strong = k == j || upper.norm() >= theta * std::sqrt(diagonal_norm[std::size_t(j)] * diagonal_norm[std::size_t(k)]);
                if (strong) block(k) += b;
                else lumped += b.cwiseAbs().rowwise().sum();
            }
            block(std::int32_t(j)).diagonal() += lumped;
        },
        [&](std::int64_t) { return std::int64_t(16); });
}

template <class Scalar>
SmoothedAggregation<Scalar>::SmoothedAggregation(const Eigen::SparseMatrix<double>& R, const AmgSettings& settings) : settings_(settings) {
    if (R.rows() % 3 != 0) throw Error("algebraic multigrid: the matrix is not made of 3x3 blocks");
    const ScalarRows rows = row_view(R);
    fine_nonzeros_ = double(R.nonZeros());
    if (R.rows() / 3 <= settings_.coarsest_nodes) {  // a small system: factor R itself
        factor_coarsest(R);
        auto level = std::make_unique<Level>();
        level->nodes = R.rows() / 3;
        levels_.push_back(std::move(level));
        return;
    }
    // The hierarchy starts from R without its weak blocks (the fairness term's 2-ring): 64 % of
    // R's entries at h = 0.25, and half the setup and V-cycle cost, for 28 instead of 25 iterations.
    build(filtered_blocks<Scalar>(rows, strong_couplings(rows, R.rows() / 3, diagonal_blocks(rows), settings_.strength_threshold)));
}

template <class Scalar>
SmoothedAggregation<Scalar>::SmoothedAggregation(Matrix filtered_fine, double fine_nonzeros, const AmgSettings& settings)
    : settings_(settings), fine_nonzeros_(fine_nonzeros) {
    build(std::move(filtered_fine));
}

template <class Scalar>
void SmoothedAggregation<Scalar>::factor_coarsest(const Eigen::SparseMatrix<double>& matrix) {
    coarsest_ = std::make_unique<Coarsest>();
    factorize_with_cholmod(coarsest_->cholesky, matrix);
    if (coarsest_->cholesky.info() != Eigen::Success)
        throw Error("algebraic multigrid: the coarsest level is not positive definite (alpha must be > 0)");
}

/// Aggregates of a level on the directional graph, its threshold halved while the aggregates are
/// too many (a level whose couplings are weak in some direction almost everywhere, e.g. with the
/// trivial normals of a staircase), and on the graph of strong blocks as the last resort.
template <class Scalar>
std::vector<std::int32_t> SmoothedAggregation<Scalar>::aggregate_level(const Matrix& a, const std::vector<Eigen::Matrix3d>& diagonal,
                                                                       const StrengthGraph& strong, std::int64_t& count) const {
    if (settings_.directional_threshold > 0) {
        const std::vector<float> strength = directional_strengths(a, diagonal);
        double theta = settings_.directional_threshold;
        for (int attempt = 0; attempt < 5; ++attempt, theta /= 2) {
            std::vector<std::int32_t> aggregate = aggregate_nodes(directional_graph(a, strength, theta), a.rows, count);
            if (double(count) * settings_.minimum_coarsening <= double(a.rows)) return aggregate;
        }
    }
    return aggregate_nodes(strong, a.rows, count);
}

template <class Scalar>
void SmoothedAggregation<Scalar>::build(Matrix fine) {
    auto level = std::make_unique<Level>();
    level->nodes = fine.rows;
    level->op = std::move(fine);
    std::vector<double> weight(static_cast<std::size_t>(level->nodes), 1.0);  // translations restricted to the level
    while (true) {
        Level& L = *level;
        std::vector<Eigen::Matrix3d> diagonal = diagonal_blocks(L.op);
        std::vector<Eigen::Matrix3d> inverse_diagonal = inverted(diagonal);
        L.inverse_diagonal.resize(inverse_diagonal.size());
        for (std::size_t i = 0; i < inverse_diagonal.size(); ++i) L.inverse_diagonal[i] = inverse_diagonal[i].template cast<Scalar>();
        if (L.nodes <= settings_.coarsest_nodes || int(levels_.size()) + 1 >= settings_.max_levels) break;

        // sets ω and the Chebyshev interval
        L.lambda_max = largest_eigenvalue_bound(L.op, diagonal, inverse_diagonal, 12);

        StrengthGraph strong = strong_couplings(L.op, L.nodes, diagonal, settings_.strength_threshold);
        std::int64_t aggregates = 0;
        const std::vector<std::int32_t> aggregate = aggregate_level(L.op, diagonal, strong, aggregates);
        if (aggregates > L.nodes * 4 / 5) break;  // no real coarsening left: factor this level

        // T(i, a) = weight_i / ‖weight on a‖ · I3 (orthonormal columns); the coarse weights are the norms.
        std::vector<double> coarse_weight(static_cast<std::size_t>(aggregates), 0.0), tentative(static_cast<std::size_t>(L.nodes));
        for (std::int64_t i = 0; i < L.nodes; ++i) coarse_weight[std::size_t(aggregate[std::size_t(i)])] += weight[std::size_t(i)] * weight[std::size_t(i)];
        for (double& c : coarse_weight) c = std::sqrt(c);
        for (std::int64_t i = 0; i < L.nodes; ++i) tentative[std::size_t(i)] = weight[std::size_t(i)] / coarse_weight[std::size_t(aggregate[std::size_t(i)])];

        const double omega = settings_.prolongator_damping / L.lambda_max;
        L.prolongator = smoothed_prolongator(L.op, inverse_diagonal, strong, aggregate, tentative, aggregates, omega);
        // The Galerkin product below is the set-up's largest transient: what only the prolongator
        // needed goes first (lobster.vol: 45 MB of double blocks and the graph at the finest level).
        std::vector<Eigen::Matrix3d>().swap(diagonal);
        std::vector<Eigen::Matrix3d>().swap(inverse_diagonal);
        strong = StrengthGraph{};
        auto next = std::make_unique<Level>();
        next->op = galerkin_product(L.op, L.prolongator, transposed_pattern(L.prolongator));  // Pᵀ A P
        symmetrize(next->op);
        // L's rows are not read any more, only its products: half its blocks suffice (lobster.vol:
        // 1.5M of the hierarchy's 3.1M blocks).
        L.blocks = L.op.block_count();
        keep_upper_triangle(L.op);
        next->nodes = aggregates;
        weight.swap(coarse_weight);
        levels_.push_back(std::move(level));
        level = std::move(next);
    }
    level->blocks = level->op.block_count();
    factor_coarsest(level->op.to_scalar());
    levels_.push_back(std::move(level));
}

template <class Scalar>
SmoothedAggregation<Scalar>::~SmoothedAggregation() = default;

template <class Scalar>
int SmoothedAggregation<Scalar>::level_count() const { return int(levels_.size()); }

template <class Scalar>
double SmoothedAggregation<Scalar>::operator_complexity() const {
    double entries = 0;
    for (const auto& L : levels_) entries += 9.0 * double(L->blocks);
    return entries / fine_nonzeros_;
}

template <class Scalar>
void SmoothedAggregation<Scalar>::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const { vcycle(0, r, z); }

template <class Scalar>
void SmoothedAggregation<Scalar>::hold(const std::vector<bool>& held) {
    held_.clear();
    held_indices_.clear();
    held_inverse_diagonal_.clear();
    if (std::find(held.begin(), held.end(), true) == held.end()) {
        held_coarse_.reset();
        return;
    }
    const Level& L = *levels_.front();
    held_.assign(held.begin(), held.end());
    for (std::size_t q = 0; q < held.size(); ++q)
        if (held[q]) held_indices_.push_back(std::int64_t(q));
    // The diagonal blocks of A_held: the held rows and columns of each block replaced by their
    // diagonal entries.
    std::vector<Eigen::Matrix3d> blocks = diagonal_blocks(L.op);
    held_diagonal_.resize(3 * L.nodes);
    for (std::int64_t i = 0; i < L.nodes; ++i)
        for (int d = 0; d < 3; ++d) {
            held_diagonal_[3 * i + d] = blocks[std::size_t(i)](d, d);
            if (!held_[std::size_t(3 * i + d)]) continue;
            const double diagonal = blocks[std::size_t(i)](d, d);
            blocks[std::size_t(i)].row(d).setZero();
            blocks[std::size_t(i)].col(d).setZero();
            blocks[std::size_t(i)](d, d) = diagonal;
        }
    const std::vector<Eigen::Matrix3d> inverse = inverted(blocks);
    held_inverse_diagonal_.resize(inverse.size());
    for (std::size_t i = 0; i < inverse.size(); ++i) held_inverse_diagonal_[i] = inverse[i].template cast<Scalar>();
    if (levels_.size() >= 2) hold_coarse_levels();
}

/// The coarse correction of A_held restricts and prolongs on the free coordinates only (M P):
/// its Galerkin operator is (M P)ᵀ A (M P), not Pᵀ A P. Near the held coordinates the two differ
/// (the holes a held coordinate leaves in a smooth coarse vector cost energy that Pᵀ A P does not
/// see); with the operators of A on the coarse levels, PCG on A_held needed up to 10 times the
/// iterations of PCG on A (every tenth coordinate held), 2–3 times on lobster.vol --clamp. So
/// every coarse level is rebuilt from the held product with the prolongators of A's hierarchy:
/// the first product costs about what the set-up's finest Galerkin product costs, the others far
/// less, and the aggregates and prolongators are kept. The held coordinates enter the product
/// with a hundredth of their diagonal (held_galerkin_product): without it the product is singular
/// where two basis functions differ only on held coordinates (tiny components of random volumes),
/// and a nearly held basis function leaves a block that rounding to float made indefinite.
template <class Scalar>
void SmoothedAggregation<Scalar>::hold_coarse_levels() {
    constexpr double kHeldWeight = 1e-2;
    held_coarse_.reset();  // the previous hold's levels go before the new ones are built
    const Level& fine = *levels_.front();
    if (prolongator_columns_.row.empty()) {
        fine_lower_ = transposed_pattern(fine.op);
        prolongator_columns_ = transposed_pattern(fine.prolongator);
    }
    auto coarse = std::make_unique<HeldCoarse>();
    Matrix op = held_galerkin_product(fine.op, fine_lower_, fine.prolongator, prolongator_columns_, held_, kHeldWeight);
    for (std::size_t index = 1;; ++index) {
        symmetrize(op);
        if (index + 1 == levels_.size()) {
            factorize_with_cholmod(coarse->coarsest.cholesky, op.to_scalar());
            if (coarse->coarsest.cholesky.info() != Eigen::Success)
                throw Error("algebraic multigrid: the coarse operator of the free coordinates is not positive definite");
            break;
        }
        const Level& L = *levels_[index];
        const std::vector<Eigen::Matrix3d> diagonal = diagonal_blocks(op);
        const std::vector<Eigen::Matrix3d> inverse = inverted(diagonal);
        typename HeldCoarse::Operator level;
        level.inverse_diagonal.resize(inverse.size());
        for (std::size_t i = 0; i < inverse.size(); ++i) level.inverse_diagonal[i] = inverse[i].template cast<Scalar>();
        level.lambda_max = largest_eigenvalue_bound(op, diagonal, inverse, 12);
        Matrix next = galerkin_product(op, L.prolongator, transposed_pattern(L.prolongator));
        keep_upper_triangle(op);
        level.op = std::move(op);
        coarse->levels.push_back(std::move(level));
        op = std::move(next);
    }
    held_coarse_ = std::move(coarse);
}

template <class Scalar>
void SmoothedAggregation<Scalar>::mask_held(Eigen::VectorXd& v) const {
    for (const std::int64_t q : held_indices_) v[q] = 0;
}

template <class Scalar>
void SmoothedAggregation<Scalar>::multiply_level(std::size_t index, const Eigen::VectorXd& x, Eigen::VectorXd& y, bool subtract) const {
    const Level& L = *levels_[index];
    if (index > 0 || held_.empty()) {
        const Matrix& op = index > 0 && held_coarse_ ? held_coarse_->levels[index - 1].op : L.op;
        multiply_symmetric_upper(op, x, y, L.product_scratch, subtract);
        return;
    }
    if (subtract) {
        multiply_level(index, x, held_product_, false);
        y -= held_product_;
        return;
    }
    // A_held x: A on the free coordinates, the diagonal on the held ones.
    Eigen::VectorXd& free = L.masked;
    free = x;
    mask_held(free);
    multiply_symmetric_upper(L.op, free, y, L.product_scratch, false);
    for (const std::int64_t q : held_indices_) y[q] = held_diagonal_[q] * x[q];
}

template <class Scalar>
void SmoothedAggregation<Scalar>::vcycle(std::size_t index, const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
    const Level& L = *levels_[index];
    if (index + 1 == levels_.size()) {
        x = (held_coarse_ ? held_coarse_->coarsest : *coarsest_).cholesky.solve(b);
        return;
    }
    const bool holding = index == 0 && !held_.empty();
    smooth(index, b, x, true);
    multiply_level(index, x, L.residual);
    L.residual = b - L.residual;
    if (holding) mask_held(L.residual);  // the coarse correction acts on the free coordinates only
    L.prolongator.multiply_transposed(L.residual, L.coarse_rhs, L.restriction_scratch);
    vcycle(index + 1, L.coarse_rhs, L.coarse_solution);
    L.prolongator.multiply(L.coarse_solution, L.residual);
    if (holding) mask_held(L.residual);
    x += L.residual;
    smooth(index, b, x, false);
}

/// Chebyshev iteration on D⁻¹A over [λmax/range, λmax] (Saad, Iterative Methods, alg. 12.1): a
/// fixed polynomial, so the V-cycle stays symmetric with the same pre- and post-smoother. With
/// held coordinates, on A_held (λmax(D⁻¹A) bounds its spectrum too: its free block is a principal
/// block of the pencil (A, D), its held block the identity).
template <class Scalar>
void SmoothedAggregation<Scalar>::smooth(std::size_t index, const Eigen::VectorXd& b, Eigen::VectorXd& x, bool zero_guess) const {
    const Level& L = *levels_[index];
    const typename HeldCoarse::Operator* held = index > 0 && held_coarse_ ? &held_coarse_->levels[index - 1] : nullptr;
    const auto& inverse_diagonal = index == 0 && !held_.empty() ? held_inverse_diagonal_
                                   : held                       ? held->inverse_diagonal
                                                                : L.inverse_diagonal;
    const double lambda_max = held ? held->lambda_max : L.lambda_max;
    const double upper = settings_.smoothing_safety * lambda_max, lower = upper / settings_.smoothing_range;
    const double theta = 0.5 * (upper + lower), delta = 0.5 * (upper - lower), sigma = theta / delta;
    double rho = 1 / sigma;
    if (zero_guess) {
        x.setZero(b.size());
        L.residual = b;
    } else {
        multiply_level(index, x, L.residual);
        L.residual = b - L.residual;
    }
    // d = D⁻¹r / θ, then per step x += d, r −= A d, d = ρ'ρ d + (2ρ'/δ) D⁻¹r: each product of
    // A or D⁻¹ goes straight into the vector it updates (one vector less to store and stream).
    L.direction.resize(L.residual.size());
    const auto update_direction = [&](bool first, double keep, double add) {
#pragma omp parallel for schedule(static) if (std::int64_t(inverse_diagonal.size()) >= kParallelMinRows)
        for (std::int64_t i = 0; i < std::int64_t(inverse_diagonal.size()); ++i) {
            const Eigen::Vector3d step = inverse_diagonal[std::size_t(i)].template cast<double>() * L.residual.template segment<3>(3 * i);
            if (first) L.direction.template segment<3>(3 * i) = step / theta;
            else L.direction.template segment<3>(3 * i) = keep * L.direction.template segment<3>(3 * i) + add * step;
        }
    };
    update_direction(true, 0, 0);
    for (int k = 1;; ++k) {
        x += L.direction;
        if (k == settings_.smoothing_degree) break;
        multiply_level(index, L.direction, L.residual, true);  // r −= A d
        const double rho_next = 1 / (2 * sigma - rho);
        update_direction(false, rho_next * rho, 2 * rho_next / delta);
        rho = rho_next;
    }
}

std::unique_ptr<Multigrid> make_multigrid(const Eigen::SparseMatrix<double>& R, double data_weight_ratio, const AmgSettings& settings) {
    if (data_weight_ratio >= settings.float_storage_min_data_weight) return std::make_unique<SmoothedAggregation<float>>(R, settings);
    return std::make_unique<SmoothedAggregation<double>>(R, settings);
}

std::unique_ptr<Multigrid> make_multigrid(const RegularizationOperator& R, const std::vector<Eigen::Matrix3d>& diagonal,
                                          double fine_nonzeros, double data_weight_ratio, const AmgSettings& settings) {
    if (data_weight_ratio >= settings.float_storage_min_data_weight)
        return std::make_unique<SmoothedAggregation<float>>(filtered_fine_level<float>(R, diagonal, settings.strength_threshold),
                                                            fine_nonzeros, settings);
    return std::make_unique<SmoothedAggregation<double>>(filtered_fine_level<double>(R, diagonal, settings.strength_threshold),
                                                         fine_nonzeros, settings);
}

template class SmoothedAggregation<double>;
template class SmoothedAggregation<float>;
template BlockMatrixT<double> filtered_fine_level(const RegularizationOperator&, const std::vector<Eigen::Matrix3d>&, double);
template BlockMatrixT<float> filtered_fine_level(const RegularizationOperator&, const std::vector<Eigen::Matrix3d>&, double);

}  // namespace dsreg::detail
