#include "block_sparse.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace dsreg::detail {

namespace {

template <class Visit>
void for_each_scalar_entry(const ScalarRows& a, std::int64_t row, Visit visit) {
    const int* inner = a.innerIndexPtr();
    const double* value = a.valuePtr();
    for (int q = a.outerIndexPtr()[row]; q < a.outerIndexPtr()[row + 1]; ++q) visit(inner[q], value[q]);
}

void finish_norms(std::vector<double>& scratch, std::int64_t i, BlockRowNorms& out) {
    out.diagonal = 0;
    std::size_t kept = 0;
    for (std::size_t q = 0; q < out.neighbor.size(); ++q) {
        const std::int32_t j = out.neighbor[q];
        const double norm = std::sqrt(scratch[std::size_t(j)]);
        scratch[std::size_t(j)] = 0;
        if (j == i) {
            out.diagonal = norm;
        } else {
            out.neighbor[kept] = j;
            out.norm[kept] = norm;
            ++kept;
        }
    }
    out.neighbor.resize(kept);
    out.norm.resize(kept);
}

}  // namespace

ScalarRows row_view(const Eigen::SparseMatrix<double>& s) {
    return ScalarRows(s.rows(), s.cols(), s.nonZeros(), s.outerIndexPtr(), s.innerIndexPtr(), s.valuePtr());
}

template <class Scalar>
void BlockMatrixT<Scalar>::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    y.resize(3 * rows);
#pragma omp parallel for schedule(static) if (rows >= kParallelMinRows)
    for (std::int64_t i = 0; i < rows; ++i) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (std::int64_t q = start[std::size_t(i)]; q < start[std::size_t(i + 1)]; ++q)
            sum.noalias() += block[std::size_t(q)].template cast<double>() * x.segment<3>(3 * std::int64_t(column[std::size_t(q)]));
        y.segment<3>(3 * i) = sum;
    }
}

template <class Scalar>
Eigen::SparseMatrix<double> BlockMatrixT<Scalar>::to_scalar() const {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(9 * column.size());
    for (std::int64_t i = 0; i < rows; ++i)
        for (std::int64_t q = start[std::size_t(i)]; q < start[std::size_t(i + 1)]; ++q)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    entries.emplace_back(3 * i + r, 3 * std::int64_t(column[std::size_t(q)]) + c, double(block[std::size_t(q)](r, c)));
    Eigen::SparseMatrix<double> s(3 * rows, 3 * cols);
    s.setFromTriplets(entries.begin(), entries.end());
    return s;
}

template <class Scalar>
TransposedPattern transposed_pattern(const BlockMatrixT<Scalar>& p) {
    TransposedPattern t;
    t.start.assign(std::size_t(p.cols + 1), 0);
    for (std::int32_t j : p.column) ++t.start[std::size_t(j) + 1];
    for (std::int64_t j = 0; j < p.cols; ++j) t.start[std::size_t(j + 1)] += t.start[std::size_t(j)];
    t.row.resize(p.column.size());
    t.source.resize(p.column.size());
    std::vector<std::int64_t> next(t.start.begin(), t.start.end() - 1);
    for (std::int64_t i = 0; i < p.rows; ++i)
        for (std::int64_t q = p.start[std::size_t(i)]; q < p.start[std::size_t(i + 1)]; ++q) {
            const std::int64_t slot = next[std::size_t(p.column[std::size_t(q)])]++;
            t.row[std::size_t(slot)] = std::int32_t(i);
            t.source[std::size_t(slot)] = q;
        }
    return t;
}

template <class Scalar>
void BlockMatrixT<Scalar>::multiply_transposed(const Eigen::VectorXd& x, Eigen::VectorXd& y, std::vector<Eigen::VectorXd>& scratch) const {
    // Scattered along the rows of A (read once, in order) into one accumulator per thread; the
    // accumulators (as long as the short side of A: the coarse level) are then summed.
    const int threads = rows >= kParallelMinRows ? omp_get_max_threads() : 1;
    y.setZero(3 * cols);
    if (threads > 1) scratch.resize(std::size_t(threads));
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        Eigen::VectorXd& sum = nt > 1 ? scratch[std::size_t(t)] : y;
        if (nt > 1) sum.setZero(3 * cols);
        const std::int64_t first = rows * t / nt, last = rows * (t + 1) / nt;
        for (std::int64_t i = first; i < last; ++i) {
            const Eigen::Vector3d xi = x.segment<3>(3 * i);
            for (std::int64_t q = start[std::size_t(i)]; q < start[std::size_t(i + 1)]; ++q)
                sum.segment<3>(3 * std::int64_t(column[std::size_t(q)])).noalias() += block[std::size_t(q)].template cast<double>().transpose() * xi;
        }
        if (nt > 1) {
#pragma omp barrier
            const std::int64_t n = 3 * cols, begin = n * t / nt, end = n * (t + 1) / nt;
            for (int u = 0; u < nt; ++u) y.segment(begin, end - begin) += scratch[std::size_t(u)].segment(begin, end - begin);
        }
    }
}

template <class Scalar>
void keep_upper_triangle(BlockMatrixT<Scalar>& a) {
    std::int64_t kept = 0;
    for (std::int64_t i = 0; i < a.rows; ++i) {
        const std::int64_t first = a.start[std::size_t(i)], last = a.start[std::size_t(i + 1)];
        a.start[std::size_t(i)] = kept;
        for (std::int64_t q = first; q < last; ++q)
            if (a.column[std::size_t(q)] >= i) {
                a.column[std::size_t(kept)] = a.column[std::size_t(q)];
                a.block[std::size_t(kept)] = a.block[std::size_t(q)];
                ++kept;
            }
    }
    a.start[std::size_t(a.rows)] = kept;
    a.column.resize(std::size_t(kept));
    a.column.shrink_to_fit();
    a.block.resize(std::size_t(kept));
    a.block.shrink_to_fit();
}

template <class Scalar>
void multiply_symmetric_upper(const BlockMatrixT<Scalar>& a, const Eigen::VectorXd& x, Eigen::VectorXd& y,
                              std::vector<Eigen::VectorXd>& scratch, bool subtract) {
    const int threads = a.rows >= kParallelMinRows ? omp_get_max_threads() : 1;
    const double sign = subtract ? -1.0 : 1.0;
    if (!subtract) y.setZero(3 * a.rows);
    if (threads > 1) scratch.resize(std::size_t(threads - 1));
    std::vector<std::int64_t> reach(std::size_t(threads), 0);  // each accumulator's rows end here
#pragma omp parallel num_threads(threads)
    {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const std::int64_t first = a.rows * t / nt, last = a.rows * (t + 1) / nt;
        // Rows j ≥ i below `last` are this thread's: straight into y. Rows beyond go to its
        // accumulator, zeroed as far as they reach (with the mesh's vertex order, a band).
        Eigen::VectorXd* beyond = t + 1 < nt ? &scratch[std::size_t(t)] : nullptr;
        if (beyond && beyond->size() != 3 * a.rows) beyond->resize(3 * a.rows);
        std::int64_t end = last;  // the accumulator's rows [last, end) are in use
        for (std::int64_t i = first; i < last; ++i) {
            const Eigen::Vector3d xi = sign * x.segment<3>(3 * i);
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q) {
                const std::int64_t j = a.column[std::size_t(q)];
                const Eigen::Matrix3d b = a.block[std::size_t(q)].template cast<double>();
                sum.noalias() += b * x.segment<3>(3 * j);
                if (j == i) continue;
                if (j < last) {
                    y.segment<3>(3 * j).noalias() += b.transpose() * xi;
                    continue;
                }
                if (j >= end) {
                    beyond->segment(3 * end, 3 * (j + 1 - end)).setZero();
                    end = j + 1;
                }
                beyond->segment<3>(3 * j).noalias() += b.transpose() * xi;
            }
            y.segment<3>(3 * i) += sign * sum;
        }
        reach[std::size_t(t)] = end;
        if (nt > 1) {
#pragma omp barrier
            for (int u = 0; u < t; ++u) {  // the threads before this one reach into its rows
                const std::int64_t stop = std::min(last, reach[std::size_t(u)]);
                if (stop > first) y.segment(3 * first, 3 * (stop - first)) += scratch[std::size_t(u)].segment(3 * first, 3 * (stop - first));
            }
        }
    }
}

namespace {

/// Pᵀ A P row by row of Pᵀ, for any storage of A: `visit_row(i, add)` calls add(k, A(i, k)) for
/// every block of row i. With `held` (one flag per coordinate), Pᵀ (M A M + ε H D H) P instead:
/// M zeroes the held coordinates, H the free ones, D = diag(A), ε = `held_weight`.
template <class Scalar, class VisitRow>
BlockMatrixT<Scalar> galerkin_by_rows(const BlockMatrixT<Scalar>& p, const TransposedPattern& t, VisitRow visit_row,
                                      const std::vector<char>* held, double held_weight = 0) {
    const auto mask_columns = [&](std::int64_t i, Eigen::Matrix3d& m) {
        for (int d = 0; d < 3; ++d)
            if ((*held)[std::size_t(3 * i + d)]) m.col(d).setZero();
    };
    return build_by_pattern<Scalar>(
        p.cols, p.cols,
        [&](std::int64_t c, auto&& mark) {
            for (std::int64_t q = t.start[std::size_t(c)]; q < t.start[std::size_t(c + 1)]; ++q)
                visit_row(t.row[std::size_t(q)], [&](std::int64_t k, const auto&) {
                    for (std::int64_t s = p.start[std::size_t(k)]; s < p.start[std::size_t(k + 1)]; ++s) mark(p.column[std::size_t(s)]);
                });
        },
        [&](std::int64_t c, auto&& block) {
            for (std::int64_t q = t.start[std::size_t(c)]; q < t.start[std::size_t(c + 1)]; ++q) {
                const std::int64_t i = t.row[std::size_t(q)];
                const Eigen::Matrix3d p_ic = p.block_at(t.source[std::size_t(q)]);
                Eigen::Matrix3d left = p_ic.transpose();  // P(i, c)ᵀ M(i)
                if (held) mask_columns(i, left);
                visit_row(i, [&](std::int64_t k, const Eigen::Matrix3d& a_ik) {
                    Eigen::Matrix3d middle = left * a_ik;  // P(i, c)ᵀ M(i) A(i, k) M(k) + ε P(i, c)ᵀ H(i) D(i) H(i)
                    if (held) {
                        mask_columns(k, middle);
                        if (k == i)
                            for (int d = 0; d < 3; ++d)
                                if ((*held)[std::size_t(3 * i + d)]) middle.col(d) += held_weight * a_ik(d, d) * p_ic.row(d).transpose();
                    }
                    for (std::int64_t s = p.start[std::size_t(k)]; s < p.start[std::size_t(k + 1)]; ++s)
                        block(p.column[std::size_t(s)]).noalias() += middle * p.block_at(s);
                });
            }
        },
        [](std::int64_t, const std::int32_t*, Eigen::Matrix3d*, std::size_t) {});
}

}  // namespace

template <class Scalar>
BlockMatrixT<Scalar> galerkin_product(const BlockMatrixT<Scalar>& a, const BlockMatrixT<Scalar>& p, const TransposedPattern& t) {
    return galerkin_by_rows(
        p, t,
        [&](std::int64_t i, auto&& add) {
            for (std::int64_t r = a.start[std::size_t(i)]; r < a.start[std::size_t(i + 1)]; ++r) add(a.column[std::size_t(r)], a.block_at(r));
        },
        nullptr);
}

template <class Scalar>
BlockMatrixT<Scalar> held_galerkin_product(const BlockMatrixT<Scalar>& upper, const TransposedPattern& lower,
                                           const BlockMatrixT<Scalar>& p, const TransposedPattern& t, const std::vector<char>& held,
                                           double held_weight) {
    return galerkin_by_rows(
        p, t,
        [&](std::int64_t i, auto&& add) {
            for (std::int64_t r = upper.start[std::size_t(i)]; r < upper.start[std::size_t(i + 1)]; ++r)
                add(upper.column[std::size_t(r)], upper.block_at(r));
            for (std::int64_t r = lower.start[std::size_t(i)]; r < lower.start[std::size_t(i + 1)]; ++r)
                if (lower.row[std::size_t(r)] != i) add(lower.row[std::size_t(r)], Eigen::Matrix3d(upper.block_at(lower.source[std::size_t(r)]).transpose()));
        },
        &held, held_weight);
}

namespace {

/// Rows of P: block (i, a) = −ω D_i⁻¹ (A_F T)(i, a), plus weight_i·I3 on the aggregate of i.
/// `visit_row(i, add)` calls add(j, A_ij) for every block of row i, as a 3×3 matrix expression.
template <class Scalar, class VisitRow>
BlockMatrixT<Scalar> build_prolongator(std::int64_t n, const std::vector<Eigen::Matrix3d>& inverse_diagonal, const StrengthGraph& strong,
                                       const std::vector<std::int32_t>& aggregate, const std::vector<double>& weight,
                                       std::int64_t aggregate_count, double omega, VisitRow visit_row) {
    // P's rows: (A_F T)(i, ·) accumulated in double, then −ω D_i⁻¹ times it plus weight_i·I3 on
    // the aggregate of i, before the blocks are rounded to Scalar.
    const auto is_strong = [&](std::int64_t i, std::int64_t j) {
        const auto first = strong.neighbour.begin() + strong.start[std::size_t(i)];
        const auto last = strong.neighbour.begin() + strong.start[std::size_t(i + 1)];
        return j == i || std::find(first, last, std::int32_t(j)) != last;
    };
    return build_by_pattern<Scalar>(
        n, aggregate_count,
        [&](std::int64_t i, auto&& mark) {
            mark(aggregate[std::size_t(i)]);
            visit_row(i, [&](std::int64_t j, const auto&) {
                if (is_strong(i, j)) mark(aggregate[std::size_t(j)]);
            });
        },
        [&](std::int64_t i, auto&& block) {
            const std::int32_t own = aggregate[std::size_t(i)];
            block(own);  // the aggregate of i is always present
            visit_row(i, [&](std::int64_t j, const Eigen::Matrix3d& a_ij) {
                if (is_strong(i, j))
                    block(aggregate[std::size_t(j)]) += weight[std::size_t(j)] * a_ij;
                else  // weak: lumped into the diagonal block of A_F
                    block(own) += weight[std::size_t(i)] * a_ij;
            });
        },
        [&](std::int64_t i, const std::int32_t* columns, Eigen::Matrix3d* blocks, std::size_t count) {
            for (std::size_t q = 0; q < count; ++q) {
                blocks[q] = (-omega * inverse_diagonal[std::size_t(i)] * blocks[q]).eval();
                if (columns[q] == aggregate[std::size_t(i)]) blocks[q].diagonal().array() += weight[std::size_t(i)];
            }
        });
}

}  // namespace

template <class Scalar>
BlockMatrixT<Scalar> smoothed_prolongator(const BlockMatrixT<Scalar>& a, const std::vector<Eigen::Matrix3d>& inverse_diagonal,
                                          const StrengthGraph& strong, const std::vector<std::int32_t>& aggregate,
                                          const std::vector<double>& weight, std::int64_t aggregate_count, double omega) {
    return build_prolongator<Scalar>(a.rows, inverse_diagonal, strong, aggregate, weight, aggregate_count, omega,
                                     [&](std::int64_t i, auto&& add) {
                                         for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q)
                                             add(a.column[std::size_t(q)], a.block_at(q));
                                     });
}

template <class Scalar>
BlockMatrixT<Scalar> filtered_blocks(const ScalarRows& a, const StrengthGraph& strong) {
    return build_by_rows<Scalar>(
        a.rows() / 3, a.rows() / 3,
        [&](std::int64_t i, auto&& block) {
            const auto first = strong.neighbour.begin() + strong.start[std::size_t(i)];
            const auto last = strong.neighbour.begin() + strong.start[std::size_t(i + 1)];
            Eigen::Vector3d lumped = Eigen::Vector3d::Zero();
            for (int r = 0; r < 3; ++r)
                for_each_scalar_entry(a, 3 * i + r, [&](int col, double v) {
                    const std::int32_t j = col / 3;
                    if (j == i || std::find(first, last, j) != last) block(j)(r, col % 3) += v;
                    else lumped[r] += std::abs(v);
                });
            block(std::int32_t(i)).diagonal() += lumped;
        },
        [&](std::int64_t i) { return 1 + strong.start[std::size_t(i + 1)] - strong.start[std::size_t(i)]; });
}

std::vector<Eigen::Matrix3d> diagonal_blocks(const ScalarRows& a) {
    const std::int64_t n = a.rows() / 3;
    std::vector<Eigen::Matrix3d> d(static_cast<std::size_t>(n), Eigen::Matrix3d::Zero());
#pragma omp parallel for schedule(static) if (n >= kParallelMinRows)
    for (std::int64_t i = 0; i < n; ++i)
        for (int r = 0; r < 3; ++r)
            for_each_scalar_entry(a, 3 * i + r, [&](int col, double v) {
                if (col / 3 == i) d[std::size_t(i)](r, col % 3) = v;
            });
    return d;
}

template <class Scalar>
std::vector<Eigen::Matrix3d> diagonal_blocks(const BlockMatrixT<Scalar>& a) {
    std::vector<Eigen::Matrix3d> d(static_cast<std::size_t>(a.rows), Eigen::Matrix3d::Zero());
#pragma omp parallel for schedule(static) if (a.rows >= kParallelMinRows)
    for (std::int64_t i = 0; i < a.rows; ++i)
        for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q)
            if (a.column[std::size_t(q)] == i) d[std::size_t(i)] += a.block_at(q);
    return d;
}

void multiply_operator(const ScalarRows& a, const Eigen::VectorXd& x, Eigen::VectorXd& y) { y.noalias() = a * x; }

void block_row_norms(const ScalarRows& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out) {
    out.neighbor.clear();
    for (int r = 0; r < 3; ++r)
        for_each_scalar_entry(a, 3 * i + r, [&](int col, double v) {
            const std::int32_t j = col / 3;
            if (scratch[std::size_t(j)] == 0) out.neighbor.push_back(j);
            scratch[std::size_t(j)] += v * v + 1e-300;  // stays non-zero once visited
        });
    out.norm.resize(out.neighbor.size());
    finish_norms(scratch, i, out);
}

template <class Scalar>
void block_row_norms(const BlockMatrixT<Scalar>& a, std::int64_t i, std::vector<double>& scratch, BlockRowNorms& out) {
    out.neighbor.clear();
    for (std::int64_t q = a.start[std::size_t(i)]; q < a.start[std::size_t(i + 1)]; ++q) {
        const std::int32_t j = a.column[std::size_t(q)];
        if (scratch[std::size_t(j)] == 0) out.neighbor.push_back(j);
        scratch[std::size_t(j)] += a.block_at(q).squaredNorm() + 1e-300;
    }
    out.norm.resize(out.neighbor.size());
    finish_norms(scratch, i, out);
}

// The two precisions of the multigrid hierarchy.
#define DSREG_BLOCK_SPARSE_INSTANTIATE(Scalar)                                                                           \
    template struct BlockMatrixT<Scalar>;                                                                                \
    template BlockMatrixT<Scalar> smoothed_prolongator(const BlockMatrixT<Scalar>&, const std::vector<Eigen::Matrix3d>&, \
                                                       const StrengthGraph&, const std::vector<std::int32_t>&,          \
                                                       const std::vector<double>&, std::int64_t, double);               \
    template BlockMatrixT<Scalar> filtered_blocks(const ScalarRows&, const StrengthGraph&);                              \
    template std::vector<Eigen::Matrix3d> diagonal_blocks(const BlockMatrixT<Scalar>&);                                 \
    template void block_row_norms(const BlockMatrixT<Scalar>&, std::int64_t, std::vector<double>&, BlockRowNorms&);   \
    template TransposedPattern transposed_pattern(const BlockMatrixT<Scalar>&);                                          \
    template void keep_upper_triangle(BlockMatrixT<Scalar>&);                                                          \
    template void multiply_symmetric_upper(const BlockMatrixT<Scalar>&, const Eigen::VectorXd&, Eigen::VectorXd&,       \
                                           std::vector<Eigen::VectorXd>&, bool);                                        \
    template BlockMatrixT<Scalar> galerkin_product(const BlockMatrixT<Scalar>&, const BlockMatrixT<Scalar>&,            \
                                                   const TransposedPattern&);                                           \
    template BlockMatrixT<Scalar> held_galerkin_product(const BlockMatrixT<Scalar>&, const TransposedPattern&,          \
                                                        const BlockMatrixT<Scalar>&, const TransposedPattern&,          \
                                                        const std::vector<char>&, double);
DSREG_BLOCK_SPARSE_INSTANTIATE(double)
DSREG_BLOCK_SPARSE_INSTANTIATE(float)
#undef DSREG_BLOCK_SPARSE_INSTANTIATE

}  // namespace dsreg::detail
