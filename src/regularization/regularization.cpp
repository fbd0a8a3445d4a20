#include "dsreg/regularization.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "../common/ordered_sum.hpp"
#include "block_sparse.hpp"
#include "dsreg/error.hpp"
#include "regularization_operator.hpp"

namespace dsreg {

using detail::alignment_weight;
using detail::data_weight;
using detail::fairness_weight;
using detail::ordered_sums;

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
    if (w.fairness_targets.rows() != 0 && w.fairness_targets.rows() != vertex_count)
        throw Error("fairness targets: " + std::to_string(w.fairness_targets.rows()) + " rows given, " +
                    std::to_string(vertex_count) + " expected");
    if (!w.fairness_targets.allFinite()) throw Error("fairness targets: not all finite");
}

RegularizationSystem assemble_regularization_system(const PointMatrix& positions, const FaceMatrix& quads,
                                                     const VertexLinks& links, const PointMatrix& normals,
                                                     const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    validate_weights(weights, n, quads.rows());
    if (normals.rows() != quads.rows()) throw Error("normal field has " + std::to_string(normals.rows()) +
                                                    " vectors for " + std::to_string(quads.rows()) + " faces");
    RegularizationSystem system = regularization_right_hand_side(positions, links, weights);
    detail::assemble_matrix(detail::RegularizationOperator(quads, links, normals, weights, n), system.matrix);
    return system;
}

RegularizationSystem regularization_right_hand_side(const PointMatrix& positions, const VertexLinks& links,
                                                    const RegularizationWeights& weights) {
    const std::int64_t n = positions.rows();
    RegularizationSystem system;
    system.rhs.resize(3 * n);
    system.constant = ordered_sums<1>(n, [&](std::int64_t i, std::array<double, 1>& constant) {
        const double aw = weights.alpha * data_weight(weights, i);
        for (int d = 0; d < 3; ++d) system.rhs[3 * i + d] = aw * positions(i, d);
        constant[0] += aw * positions.row(i).squaredNorm();
    })[0];
    const detail::FairnessTargetTerms targets = detail::fairness_target_terms(links, weights, n);
    if (targets.rhs.size() > 0) system.rhs += targets.rhs;
    system.constant += targets.constant;
    return system;
}

namespace detail {

FairnessTargetTerms fairness_target_terms(const VertexLinks& links, const RegularizationWeights& weights, std::int64_t n) {
    FairnessTargetTerms terms;
    if (weights.fairness_targets.rows() == 0) return terms;
    if (static_cast<std::int64_t>(links.offsets.size()) != n + 1)
        throw Error("fairness targets need the links of all " + std::to_string(n) + " vertices");
    // γ c_i |L_i x − t_i|² = γ c_i (xᵀ L_iᵀ L_i x − 2 (L_iᵀ t_i)ᵀ x + |t_i|²): b gains γ c_i L_iᵀ t_i,
    // t_i at vertex i and −t_i / k_i at each of its k_i links. Few vertices hold a target (the
    // turns of junction curves), so one thread scatters them, in vertex order.
    terms.rhs = Eigen::VectorXd::Zero(3 * n);
    for (std::int64_t i = 0; i < n; ++i) {
        const Eigen::Vector3d t = weights.fairness_targets.row(i).transpose();
        if (links.size(i) == 0 || t.isZero(0.0)) continue;
        const double c = weights.gamma * fairness_weight(weights, i);
        terms.rhs.segment<3>(3 * i) += c * t;
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            terms.rhs.segment<3>(3 * links.neighbors[std::size_t(q)]) -= (c / double(links.size(i))) * t;
        terms.constant += c * t.squaredNorm();
    }
    return terms;
}

}  // namespace detail

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
    // Summed in an order fixed by the mesh alone (ordered_sum.hpp): the same bits at any thread count.
    const std::array<double, 2> vertex_terms = ordered_sums<2>(n, [&](std::int64_t i, std::array<double, 2>& sums) {
        sums[0] += data_weight(weights, i) * (candidate.row(i) - positions.row(i)).squaredNorm();
        Eigen::RowVector3d barycenter = Eigen::RowVector3d::Zero();
        for (std::int64_t q = links.offsets[std::size_t(i)]; q < links.offsets[std::size_t(i + 1)]; ++q)
            barycenter += candidate.row(links.neighbors[std::size_t(q)]);
        if (links.size(i) > 0) barycenter /= double(links.size(i));
        else barycenter = candidate.row(i);
        if (links.size(i) > 0 && weights.fairness_targets.rows() > 0) barycenter += weights.fairness_targets.row(i);
        sums[1] += fairness_weight(weights, i) * (candidate.row(i) - barycenter).squaredNorm();
    });
    const Eigen::Index k = quads.cols();
    const std::array<double, 1> face_terms = ordered_sums<1>(quads.rows(), [&](std::int64_t f, std::array<double, 1>& sums) {
        double sum = 0;
        for (Eigen::Index e = 0; e < k; ++e) {
            const double d = (candidate.row(quads(f, e)) - candidate.row(quads(f, (e + 1) % k))).dot(normals.row(f));
            sum += d * d;
        }
        sums[0] += alignment_weight(weights, f) * sum;
    });
    EnergyTerms terms;
    terms.data = vertex_terms[0];
    terms.fairness = vertex_terms[1];
    terms.alignment = face_terms[0];
    return terms;
}

Eigen::VectorXd flatten_points(const PointMatrix& points) {
    return Eigen::Map<const Eigen::VectorXd>(points.data(), points.size());
}

PointMatrix unflatten_points(const Eigen::VectorXd& x) {
    return Eigen::Map<const PointMatrix>(x.data(), x.size() / 3, 3);
}

}  // namespace dsreg
