#include "dsreg/regularization.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

using ScalarRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// An optional per-element factor: 1 where the vector is empty.
double element_or_one(const Eigen::VectorXd& values, std::int64_t index) {
    return values.size() ? values[index] : 1.0;
}

/// α_i w0_i: the weight of vertex i in the data term (eq. 3 with W0 and the local α).
double data_weight(const RegularizationWeights& w, std::int64_t i) {
    return element_or_one(w.vertex_alpha, i) * element_or_one(w.vertex_weights, i);
}
/// γ_i w0_i: the weight of vertex i in the fairness term (eq. 11).
double fairness_weight(const RegularizationWeights& w, std::int64_t i) {
    return element_or_one(w.vertex_gamma, i) * element_or_one(w.vertex_weights, i);
}
/// β_f w2_f: the weight of face f in the alignment term (eq. 9).
double alignment_weight(const RegularizationWeights& w, std::int64_t f) {
    return element_or_one(w.face_beta, f) * element_or_one(w.face_weights, f);
}

enum class Sign { Positive, NonNegative };

void check_per_element(const Eigen::VectorXd& values, std::int64_t expected, const std::string& name, Sign sign) {
    if (values.size() == 0) return;
    if (values.size() != expected)
        throw Error(name + ": " + std::to_string(values.size()) + " values given, " + std::to_string(expected) + " expected");
    for (Eigen::Index i = 0; i < values.size(); ++i) {
        const bool ok = std::isfinite(values[i]) && (sign == Sign::Positive ? values[i] > 0 : values[i] >= 0);
        if (!ok)
            throw Error(name + ": value " + std::to_string(values[i]) + " at index " + std::to_string(i) + " is not a " +
                        (sign == Sign::Positive ? "positive" : "non-negative") + " finite number");
    }
}

/// I − B of eq. (13–14): row i has 1 on the diagonal and −1/|link(i)| on each link entry.
ScalarRowMatrix fairness_operator(const VertexLinks& links) {
    const std::int64_t n = static_cast<std::int64_t>(links.offsets.size()) - 1;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(links.neighbors.size() + std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) {
        if (links.size(i) == 0) continue;  // an isolated vertex is its own barycentre
        entries.emplace_back(i, i, 1.0);
        const double share = 1.0 / double(links.size(i));
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            entries.emplace_back(i, links.neighbors[std::size_t(q)], -share);
    }
    ScalarRowMatrix op(n, n);
    op.setFromTriplets(entries.begin(), entries.end());
    return op;
}

/// The part of R that acts on each coordinate separately (α W0_α + γ (I−B)ᵀ W0_γ (I−B), with
/// W0_α = diag(α_i w0_i), W0_γ = diag(γ_i w0_i)), with explicit zeros added on every mesh edge
/// so that the alignment blocks have a place.
ScalarRowMatrix coordinate_wise_part(const VertexLinks& links, const RegularizationWeights& w, std::int64_t n) {
    ScalarRowMatrix part(n, n);
    if (w.gamma > 0) {
        Eigen::VectorXd w0_gamma(n);
        for (std::int64_t i = 0; i < n; ++i) w0_gamma[i] = fairness_weight(w, i);
        const ScalarRowMatrix fair = fairness_operator(links);
        part = w.gamma * (ScalarRowMatrix(fair.transpose()) * w0_gamma.asDiagonal() * fair);
    }
    std::vector<Eigen::Triplet<double>> structure;
    structure.reserve(links.neighbors.size() + std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) {
        structure.emplace_back(i, i, w.alpha * data_weight(w, i));
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            structure.emplace_back(i, links.neighbors[std::size_t(q)], 0.0);
    }
    ScalarRowMatrix data_and_edges(n, n);
    data_and_edges.setFromTriplets(structure.begin(), structure.end());
    ScalarRowMatrix sum = part + data_and_edges;
    sum.makeCompressed();
    return sum;
}

std::int64_t slot_of(const ScalarRowMatrix& m, std::int64_t row, std::int64_t col) {
    const int* first = m.innerIndexPtr() + m.outerIndexPtr()[row];
    const int* last = m.innerIndexPtr() + m.outerIndexPtr()[row + 1];
    const int* it = std::lower_bound(first, last, static_cast<int>(col));
    return it - m.innerIndexPtr();
}

/// 3×3 alignment blocks β β_f w2_f u_f u_fᵀ (eq. 20) accumulated on the pattern of `pattern`:
/// for each edge (a,b) of face f, +M on blocks (a,a), (b,b) and −M on (a,b), (b,a).
std::vector<Eigen::Matrix3d> alignment_blocks(const ScalarRowMatrix& pattern, const FaceMatrix& quads,
                                              const PointMatrix& normals, const RegularizationWeights& w) {
    std::vector<Eigen::Matrix3d> blocks(std::size_t(pattern.nonZeros()), Eigen::Matrix3d::Zero());
    if (w.beta == 0) return blocks;
    const Eigen::Index k = quads.cols();
    for (Eigen::Index f = 0; f < quads.rows(); ++f) {
        const Eigen::Vector3d u = normals.row(f).transpose();
        const double weight = w.beta * alignment_weight(w, f);
        if (weight == 0) continue;
        const Eigen::Matrix3d m = weight * (u * u.transpose());
        for (Eigen::Index e = 0; e < k; ++e) {
            const std::int64_t a = quads(f, e), b = quads(f, (e + 1) % k);
            blocks[std::size_t(slot_of(pattern, a, a))] += m;
            blocks[std::size_t(slot_of(pattern, b, b))] += m;
            blocks[std::size_t(slot_of(pattern, a, b))] -= m;
            blocks[std::size_t(slot_of(pattern, b, a))] -= m;
        }
    }
    return blocks;
}

/// Expands scalar part ⊗ I3 + alignment blocks into the 3n×3n interleaved matrix. A block whose
/// alignment part is zero contributes only its diagonal (the scalar part is ⊗ I3).
Eigen::SparseMatrix<double> expand_blocks(const ScalarRowMatrix& scalar, const std::vector<Eigen::Matrix3d>& blocks) {
    const std::int64_t n = scalar.rows();
    std::vector<char> full(blocks.size());
    for (std::size_t q = 0; q < blocks.size(); ++q) full[q] = !blocks[q].isZero(0.0);
    // Entries per scalar row 3a+r: 3 per full block, 1 per diagonal-only block (same for r = 0,1,2).
    std::vector<std::int64_t> row_start(std::size_t(3 * n + 1), 0);
    for (std::int64_t a = 0; a < n; ++a) {
        std::int64_t count = 0;
        for (std::int64_t q = scalar.outerIndexPtr()[a]; q < scalar.outerIndexPtr()[a + 1]; ++q) count += full[std::size_t(q)] ? 3 : 1;
        for (int r = 0; r < 3; ++r) row_start[std::size_t(3 * a + r + 1)] = count;
    }
    for (std::size_t i = 1; i < row_start.size(); ++i) row_start[i] += row_start[i - 1];
    if (row_start.back() > std::int64_t(INT32_MAX))
        throw Error("regularization system too large: " + std::to_string(row_start.back()) + " non-zeros (limit 2^31)");

    Eigen::SparseMatrix<double> R(3 * n, 3 * n);  // symmetric: row-major layout = column-major layout
    R.resizeNonZeros(Eigen::Index(row_start.back()));
    for (std::int64_t i = 0; i <= 3 * n; ++i) R.outerIndexPtr()[i] = int(row_start[std::size_t(i)]);
#pragma omp parallel for schedule(static)
    for (std::int64_t a = 0; a < n; ++a) {
        for (int r = 0; r < 3; ++r) {
            std::int64_t out = row_start[std::size_t(3 * a + r)];
            for (std::int64_t q = scalar.outerIndexPtr()[a]; q < scalar.outerIndexPtr()[a + 1]; ++q) {
                const std::int64_t b = scalar.innerIndexPtr()[q];
                const double s = scalar.valuePtr()[q];
                const Eigen::Matrix3d& block = blocks[std::size_t(q)];
                for (int c = 0; c < 3; ++c) {
                    if (!full[std::size_t(q)] && c != r) continue;
                    R.innerIndexPtr()[out] = int(3 * b + c);
                    R.valuePtr()[out] = block(r, c) + (c == r ? s : 0.0);
                    ++out;
                }
            }
        }
    }
    return R;
}

}  // namespace

void validate_weights(const RegularizationWeights& w, std::int64_t vertex_count, std::int64_t face_count) {
    if (!(w.alpha > 0) || !std::isfinite(w.alpha))
        throw Error("alpha must be a positive finite number (got " + std::to_string(w.alpha) +
                    "): the data term keeps the system positive definite");
    if (!(w.beta >= 0) || !std::isfinite(w.beta)) throw Error("beta must be a non-negative finite number (got " + std::to_string(w.beta) + ")");
    if (!(w.gamma >= 0) || !std::isfinite(w.gamma)) throw Error("gamma must be a non-negative finite number (got " + std::to_string(w.gamma) + ")");
    check_per_element(w.vertex_weights, vertex_count, "vertex weights (W0)", Sign::Positive);
    check_per_element(w.face_weights, face_count, "face weights (W2)", Sign::Positive);
    check_per_element(w.vertex_alpha, vertex_count, "per-vertex alpha multipliers", Sign::Positive);
    check_per_element(w.face_beta, face_count, "per-face beta multipliers", Sign::NonNegative);
    check_per_element(w.vertex_gamma, vertex_count, "per-vertex gamma multipliers", Sign::NonNegative);
}

RegularizationSystem assemble_regularization_system(const PointMatrix& positions, const FaceMatrix& quads,
                                                     const VertexLinks& links, const PointMatrix& normals,
                                                     const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    validate_weights(weights, n, quads.rows());
    if (normals.rows() != quads.rows()) throw Error("normal field has " + std::to_string(normals.rows()) +
                                                    " vectors for " + std::to_string(quads.rows()) + " faces");
    const ScalarRowMatrix scalar = coordinate_wise_part(links, weights, n);
    const std::vector<Eigen::Matrix3d> blocks = alignment_blocks(scalar, quads, normals, weights);

    RegularizationSystem system;
    system.matrix = expand_blocks(scalar, blocks);
    system.rhs.resize(3 * n);
    system.constant = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        const double aw = weights.alpha * data_weight(weights, i);
        for (int d = 0; d < 3; ++d) system.rhs[3 * i + d] = aw * positions(i, d);
        system.constant += aw * positions.row(i).squaredNorm();
    }
    return system;
}

EnergyTerms regularization_energy(const PointMatrix& candidate, const PointMatrix& positions, const FaceMatrix& quads,
                                  const VertexLinks& links, const PointMatrix& normals, const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    validate_weights(weights, n, quads.rows());
    EnergyTerms terms;
    for (std::int64_t i = 0; i < n; ++i) {
        terms.data += data_weight(weights, i) * (candidate.row(i) - positions.row(i)).squaredNorm();
        Eigen::RowVector3d barycenter = Eigen::RowVector3d::Zero();
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            barycenter += candidate.row(links.neighbors[std::size_t(q)]);
        if (links.size(i) > 0) barycenter /= double(links.size(i));
        else barycenter = candidate.row(i);
        terms.fairness += fairness_weight(weights, i) * (candidate.row(i) - barycenter).squaredNorm();
    }
    const Eigen::Index k = quads.cols();
    for (Eigen::Index f = 0; f < quads.rows(); ++f) {
        double sum = 0;
        for (Eigen::Index e = 0; e < k; ++e) {
            const double d = (candidate.row(quads(f, e)) - candidate.row(quads(f, (e + 1) % k))).dot(normals.row(f));
            sum += d * d;
        }
        terms.alignment += alignment_weight(weights, f) * sum;
    }
    return terms;
}

Eigen::VectorXd flatten_points(const PointMatrix& points) {
    return Eigen::Map<const Eigen::VectorXd>(points.data(), points.size());
}

PointMatrix unflatten_points(const Eigen::VectorXd& x) {
    return Eigen::Map<const PointMatrix>(x.data(), x.size() / 3, 3);
}

}  // namespace dsreg
