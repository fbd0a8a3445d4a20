#include "regularization_operator.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../common/ordered_sum.hpp"
#include "block_sparse.hpp"
#include "dsreg/error.hpp"

namespace dsreg::detail {

namespace {

double element_or_one(const Eigen::VectorXd& values, std::int64_t index) { return values.size() ? values[index] : 1.0; }

/// The transpose of the link relation: in(j) = {i : j ∈ link(i)} with multiplicity, increasing i.
VertexLinks incoming_links(const VertexLinks& links, std::int64_t n) {
    VertexLinks in;
    in.offsets.assign(std::size_t(n + 1), 0);
    for (std::int32_t j : links.neighbors) ++in.offsets[std::size_t(j) + 1];
    for (std::int64_t i = 0; i < n; ++i) in.offsets[std::size_t(i + 1)] += in.offsets[std::size_t(i)];
    in.neighbors.resize(links.neighbors.size());
    std::vector<std::int64_t> next(in.offsets.begin(), in.offsets.end() - 1);
    for (std::int64_t i = 0; i < n; ++i)
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            in.neighbors[std::size_t(next[std::size_t(links.neighbors[std::size_t(q)])]++)] = std::int32_t(i);
    return in;
}

}  // namespace

double data_weight(const RegularizationWeights& w, std::int64_t i) {
    return element_or_one(w.vertex_alpha, i) * element_or_one(w.vertex_weights, i);
}
double fairness_weight(const RegularizationWeights& w, std::int64_t i) {
    return element_or_one(w.vertex_gamma, i) * element_or_one(w.vertex_weights, i);
}
double alignment_weight(const RegularizationWeights& w, std::int64_t f) {
    return element_or_one(w.face_beta, f) * element_or_one(w.face_weights, f);
}

RegularizationOperator::RegularizationOperator(const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
                                               const RegularizationWeights& w, std::int64_t n)
    : quads_(quads), links_(links), normals_(normals), w_(w), n_(n), k_(quads.cols()), in_(incoming_links(links, n)), corners_(vertex_corners(quads, n)) {
    const std::int64_t m = quads.rows();
    face_weight_.resize(std::size_t(m));
    for (std::int64_t f = 0; f < m; ++f) face_weight_[std::size_t(f)] = w.beta * alignment_weight(w, f);
    fair_weight_.assign(std::size_t(n), 0.0);
    data_weight_.resize(std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) {
        data_weight_[std::size_t(i)] = w.alpha * data_weight(w, i);
        if (w.gamma > 0 && links.size(i) > 0) fair_weight_[std::size_t(i)] = w.gamma * fairness_weight(w, i);
        fairness_ = fairness_ || fair_weight_[std::size_t(i)] != 0;
    }
}

/// Block row j of R (eq. 22–23):
///   R_jk = (α α_j w0_j [j = k] + γ Σ_i γ_i w0_i F_ij F_ik) I3 + β Σ_f β_f w2_f (±u_f u_fᵀ per edge),
/// with F = I − B (eq. 13–14; F_ii = 1, F_ik = −1/|link(i)| for k ∈ link(i), row i empty if the
/// link is). Row j gathers its terms from i ∈ {j} ∪ in(j) (the rows of F with an entry in column j)
/// and from the faces around j, so rows are independent and can be built in parallel, in time
/// linear in the non-zeros. Block (j,k) and block (k,j) receive the same terms in the same order
/// (increasing i, increasing f, products written symmetrically), so R is exactly symmetric.
void RegularizationOperator::row(std::int64_t j, Row& s, bool values) const {
    s.columns.clear();
    const auto touch = [&](std::int32_t c) {
        if (s.slot[std::size_t(c)] < 0) {
            s.slot[std::size_t(c)] = 0;
            s.columns.push_back(c);
        }
    };
    for_each_coupled(j, touch);
    std::sort(s.columns.begin(), s.columns.end());
    for (std::size_t q = 0; q < s.columns.size(); ++q) s.slot[std::size_t(s.columns[q])] = std::int32_t(q);
    const auto slot = [&](std::int64_t c) { return std::size_t(s.slot[std::size_t(c)]); };

    s.full.assign(s.columns.size(), 0);
    if (values) {
        s.scalar.assign(s.columns.size(), 0.0);
        s.blocks.assign(s.columns.size(), Eigen::Matrix3d::Zero());
    }
    for (std::int64_t q = corners_.offsets[std::size_t(j)]; q < corners_.offsets[std::size_t(j + 1)]; ++q) {
        const std::int64_t f = corners_.codes[std::size_t(q)] / k_, e = corners_.codes[std::size_t(q)] % k_;
        const double weight = face_weight_[std::size_t(f)];
        if (weight == 0) continue;
        const std::size_t next = slot(quads_(f, (e + 1) % k_)), previous = slot(quads_(f, (e + k_ - 1) % k_)), self = slot(j);
        s.full[self] = s.full[next] = s.full[previous] = 1;
        if (!values) continue;
        Eigen::Matrix3d m;  // weight·u uᵀ, written so that m is exactly symmetric
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) m(r, c) = weight * (normals_(f, r) * normals_(f, c));
        s.blocks[self] += m;  // edge (previous, j)
        s.blocks[self] += m;  // edge (j, next)
        s.blocks[next] -= m;
        s.blocks[previous] -= m;
    }
    if (values) {
        if (fairness_)
            for_each_fairness_row(j, [&](std::int64_t i, double f_ij) {
                const double wi = fair_weight_[std::size_t(i)];
                const double share = -1.0 / double(links_.size(i));
                s.scalar[slot(i)] += wi * (f_ij * 1.0);
                for (std::int64_t q = links_.offsets[std::size_t(i)]; q < links_.offsets[std::size_t(i + 1)]; ++q)
                    s.scalar[slot(links_.neighbors[std::size_t(q)])] += wi * (f_ij * share);
            });
        s.scalar[slot(j)] += data_weight_[std::size_t(j)];
        for (std::size_t q = 0; q < s.columns.size(); ++q) s.blocks[q].diagonal().array() += s.scalar[q];
    }
    for (std::int32_t c : s.columns) s.slot[std::size_t(c)] = -1;
}

RegularizationOperator::Summary RegularizationOperator::summary() const {
    Summary summary;
    summary.diagonal.resize(std::size_t(n_));
    // The maximum is exact in any order, the counts are whole numbers; the trace is summed in an
    // order fixed by the mesh (ordered_sum.hpp): the same bits at any thread count.
    const std::int64_t blocks = sum_blocks(n_);
    std::vector<double> block_trace(static_cast<std::size_t>(blocks), 0.0);
    double largest = 0, nonzeros = 0;
#pragma omp parallel if (n_ >= kParallelMinRows)
    {
        Row s(n_);
#pragma omp for schedule(static) reduction(max : largest) reduction(+ : nonzeros)
        for (std::int64_t b = 0; b < blocks; ++b)
            for (std::int64_t j = block_first(b); j < block_last(b, n_); ++j) {
                row(j, s, true);
                Eigen::Vector3d sums = Eigen::Vector3d::Zero();
                for (std::size_t q = 0; q < s.columns.size(); ++q) {
                    nonzeros += s.full[q] ? 9 : 3;
                    if (s.full[q]) sums += s.blocks[q].cwiseAbs().rowwise().sum();
                    else sums += s.blocks[q].diagonal().cwiseAbs();
                    if (s.columns[q] == j) summary.diagonal[std::size_t(j)] = s.blocks[q];
                }
                largest = std::max(largest, sums.maxCoeff());
                block_trace[std::size_t(b)] += summary.diagonal[std::size_t(j)].trace();
            }
    }
    double trace = 0;
    for (const double t : block_trace) trace += t;
    summary.infinity_norm = largest;
    summary.scalar_nonzeros = nonzeros;
    summary.mean_diagonal = n_ > 0 ? trace / double(3 * n_) : 0.0;
    return summary;
}

void RegularizationOperator::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    y.resize(3 * n_);
    const bool parallel = n_ >= kParallelMinRows;
    // Fairness, γ FᵀG F x: first v_i = g_i (F x)_i / |link(i)| ...
    if (fairness_) {
        scaled_residual_.resize(3 * n_);
#pragma omp parallel for schedule(static) if (parallel)
        for (std::int64_t i = 0; i < n_; ++i) {
            const double g = fair_weight_[std::size_t(i)];
            if (g == 0) {
                scaled_residual_.segment<3>(3 * i).setZero();
                continue;
            }
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            for (std::int64_t q = links_.offsets[std::size_t(i)]; q < links_.offsets[std::size_t(i + 1)]; ++q)
                sum += x.segment<3>(3 * std::int64_t(links_.neighbors[std::size_t(q)]));
            const double size = double(links_.size(i));
            scaled_residual_.segment<3>(3 * i) = (g / size) * (x.segment<3>(3 * i) - sum / size);
        }
    }
    // ... then (FᵀG F x)_j = |link(j)| v_j − Σ_{i ∈ in(j)} v_i; alignment from the faces around j:
    // each face f at corner e adds c_f u_f (2 s_e − s_{e+1} − s_{e−1}), s_c = x_{corner c}·u_f.
#pragma omp parallel for schedule(static) if (parallel)
    for (std::int64_t j = 0; j < n_; ++j) {
        const Eigen::Vector3d xj = x.segment<3>(3 * j);
        Eigen::Vector3d sum = data_weight_[std::size_t(j)] * xj;
        if (fairness_) {
            sum += double(links_.size(j)) * scaled_residual_.segment<3>(3 * j);
            for (std::int64_t q = in_.offsets[std::size_t(j)]; q < in_.offsets[std::size_t(j + 1)]; ++q)
                sum -= scaled_residual_.segment<3>(3 * std::int64_t(in_.neighbors[std::size_t(q)]));
        }
        for (std::int64_t q = corners_.offsets[std::size_t(j)]; q < corners_.offsets[std::size_t(j + 1)]; ++q) {
            const std::int64_t f = corners_.codes[std::size_t(q)] / k_, e = corners_.codes[std::size_t(q)] % k_;
            const double c = face_weight_[std::size_t(f)];
            if (c == 0) continue;
            const Eigen::Vector3d u = normals_.row(f).transpose();
            const double next = x.segment<3>(3 * std::int64_t(quads_(f, (e + 1) % k_))).dot(u);
            const double previous = x.segment<3>(3 * std::int64_t(quads_(f, (e + k_ - 1) % k_))).dot(u);
            sum += (c * (2 * xj.dot(u) - next - previous)) * u;
        }
        y.segment<3>(3 * j) = sum;
    }
}

void assemble_matrix(const RegularizationOperator& rows, Eigen::SparseMatrix<double>& R) {
    const std::int64_t n = rows.vertex_count();
    const bool parallel = n >= kParallelMinRows;
    // Pass 1: entries per scalar row (the three rows of a vertex have the same count).
    std::vector<std::int64_t> row_start(std::size_t(3 * n + 1), 0);
#pragma omp parallel if (parallel)
    {
        RegularizationOperator::Row s(n);
#pragma omp for schedule(static)
        for (std::int64_t j = 0; j < n; ++j) {
            rows.row(j, s, false);
            std::int64_t count = 0;
            for (char full : s.full) count += full ? 3 : 1;
            for (int r = 0; r < 3; ++r) row_start[std::size_t(3 * j + r + 1)] = count;
        }
    }
    for (std::size_t i = 1; i < row_start.size(); ++i) row_start[i] += row_start[i - 1];
    if (row_start.back() > std::int64_t(INT32_MAX))
        throw Error("regularization system too large: " + std::to_string(row_start.back()) + " non-zeros (limit 2^31)");

    // Pass 2: values, written in place (symmetric: the row-major layout is the column-major one).
    R.resize(3 * n, 3 * n);
    R.resizeNonZeros(Eigen::Index(row_start.back()));
    int* outer = R.outerIndexPtr();
    int* inner = R.innerIndexPtr();
    double* value = R.valuePtr();
    for (std::int64_t i = 0; i <= 3 * n; ++i) outer[i] = int(row_start[std::size_t(i)]);
#pragma omp parallel if (parallel)
    {
        RegularizationOperator::Row s(n);
#pragma omp for schedule(static)
        for (std::int64_t j = 0; j < n; ++j) {
            rows.row(j, s, true);
            for (int r = 0; r < 3; ++r) {
                std::int64_t out = row_start[std::size_t(3 * j + r)];
                for (std::size_t q = 0; q < s.columns.size(); ++q) {
                    const std::int64_t c0 = 3 * std::int64_t(s.columns[q]);
                    if (s.full[q]) {
                        for (int c = 0; c < 3; ++c, ++out) {
                            inner[out] = int(c0 + c);
                            value[out] = s.blocks[q](r, c);
                        }
                    } else {
                        inner[out] = int(c0 + r);
                        value[out] = s.blocks[q](r, r);
                        ++out;
                    }
                }
            }
        }
    }
}

}  // namespace dsreg::detail
