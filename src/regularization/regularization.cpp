#include "dsreg/regularization.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "block_sparse.hpp"
#include "dsreg/error.hpp"
#include "regularization_operator.hpp"

namespace dsreg {

using detail::alignment_weight;
using detail::data_weight;
using detail::fairness_weight;

namespace {

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
    RegularizationSystem system = regularization_right_hand_side(positions, weights);
    detail::assemble_matrix(detail::RegularizationOperator(quads, links, normals, weights, n), system.matrix);
    return system;
}

RegularizationSystem regularization_right_hand_side(const PointMatrix& positions, const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    RegularizationSystem system;
    system.rhs.resize(3 * n);
    double constant = 0;
#pragma omp parallel for schedule(static) reduction(+ : constant) if (n >= 4096)
    for (std::int64_t i = 0; i < n; ++i) {
        const double aw = weights.alpha * data_weight(weights, i);
        for (int d = 0; d < 3; ++d) system.rhs[3 * i + d] = aw * positions(i, d);
        constant += aw * positions.row(i).squaredNorm();
    }
    system.constant = constant;
    return system;
}

double smallest_eigenvalue_bound(const RegularizationWeights& w, std::int64_t vertex_count) {
    double smallest = std::numeric_limits<double>::infinity();
    for (std::int64_t i = 0; i < vertex_count; ++i) smallest = std::min(smallest, data_weight(w, i));
    return std::isfinite(smallest) ? w.alpha * smallest : w.alpha;
}

double smallest_eigenvalue_bound(const RegularizationWeights& w, const std::vector<char>& selected) {
    double smallest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < selected.size(); ++i)
        if (selected[i]) smallest = std::min(smallest, data_weight(w, std::int64_t(i)));
    return w.alpha * smallest;
}

EnergyTerms regularization_energy(const PointMatrix& candidate, const PointMatrix& positions, const FaceMatrix& quads,
                                  const VertexLinks& links, const PointMatrix& normals, const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    validate_weights(weights, n, quads.rows());
    double data = 0, fairness = 0, alignment = 0;
#pragma omp parallel for schedule(static) reduction(+ : data, fairness) if (n >= 4096)
    for (std::int64_t i = 0; i < n; ++i) {
        data += data_weight(weights, i) * (candidate.row(i) - positions.row(i)).squaredNorm();
        Eigen::RowVector3d barycenter = Eigen::RowVector3d::Zero();
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            barycenter += candidate.row(links.neighbors[std::size_t(q)]);
        if (links.size(i) > 0) barycenter /= double(links.size(i));
        else barycenter = candidate.row(i);
        fairness += fairness_weight(weights, i) * (candidate.row(i) - barycenter).squaredNorm();
    }
    const Eigen::Index k = quads.cols(), m = quads.rows();
#pragma omp parallel for schedule(static) reduction(+ : alignment) if (m >= 4096)
    for (Eigen::Index f = 0; f < m; ++f) {
        double sum = 0;
        for (Eigen::Index e = 0; e < k; ++e) {
            const double d = (candidate.row(quads(f, e)) - candidate.row(quads(f, (e + 1) % k))).dot(normals.row(f));
            sum += d * d;
        }
        alignment += alignment_weight(weights, f) * sum;
    }
    EnergyTerms terms;
    terms.data = data;
    terms.fairness = fairness;
    terms.alignment = alignment;
    return terms;
}

Eigen::VectorXd flatten_points(const PointMatrix& points) {
    return Eigen::Map<const Eigen::VectorXd>(points.data(), points.size());
}

PointMatrix unflatten_points(const Eigen::VectorXd& x) {
    return Eigen::Map<const PointMatrix>(x.data(), x.size() / 3, 3);
}

}  // namespace dsreg
