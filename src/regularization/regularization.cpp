#include "dsreg/regularization.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

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

/// Vertex → (face, corner) incidences, in increasing face order for each vertex.
struct Incidence {
    std::vector<std::int64_t> start;
    std::vector<std::int64_t> face;  ///< f·k + corner
};

Incidence vertex_incidence(const FaceMatrix& quads, std::int64_t n) {
    const std::int64_t m = quads.rows(), k = quads.cols();
    Incidence inc;
    inc.start.assign(std::size_t(n + 1), 0);
    for (std::int64_t f = 0; f < m; ++f)
        for (std::int64_t e = 0; e < k; ++e) ++inc.start[std::size_t(quads(f, e)) + 1];
    for (std::int64_t i = 0; i < n; ++i) inc.start[std::size_t(i + 1)] += inc.start[std::size_t(i)];
    inc.face.resize(std::size_t(inc.start.back()));
    std::vector<std::int64_t> next(inc.start.begin(), inc.start.end() - 1);
    for (std::int64_t f = 0; f < m; ++f)
        for (std::int64_t e = 0; e < k; ++e) inc.face[std::size_t(next[std::size_t(quads(f, e))]++)] = f * k + e;
    return inc;
}

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

/// Direct assembly of R (eq. 22–23) in its 3×3 block structure, one block row per vertex j:
///   R_jk = (α α_j w0_j [j = k] + γ Σ_i γ_i w0_i F_ij F_ik) I3 + β Σ_f β_f w2_f (±u_f u_fᵀ per edge),
/// with F = I − B (eq. 13–14; F_ii = 1, F_ik = −1/|link(i)| for k ∈ link(i), row i empty if the
/// link is). Row j gathers its terms from i ∈ {j} ∪ in(j) (the rows of F with an entry in column j)
/// and from the faces around j, so rows are independent and built in parallel, in time linear in
/// the non-zeros. Block (j,k) and block (k,j) receive the same terms in the same order (increasing
/// i, increasing f, products written symmetrically), so R is exactly symmetric. A block with an
/// alignment part is stored full (9 entries), the others (the fairness 2-ring) as their diagonal.
class BlockAssembler {
public:
    BlockAssembler(const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
                   const RegularizationWeights& w, std::int64_t n)
        : quads_(quads), links_(links), normals_(normals), w_(w), n_(n), k_(quads.cols()),
          in_(incoming_links(links, n)), incidence_(vertex_incidence(quads, n)) {
        face_weight_.resize(std::size_t(quads.rows()));
        for (Eigen::Index f = 0; f < quads.rows(); ++f) face_weight_[std::size_t(f)] = w.beta * alignment_weight(w, f);
        fair_weight_.assign(std::size_t(n), 0.0);
        fairness_ = false;
        if (w.gamma > 0)
            for (std::int64_t i = 0; i < n; ++i) {
                fair_weight_[std::size_t(i)] = links.size(i) > 0 ? w.gamma * fairness_weight(w, i) : 0.0;
                fairness_ = fairness_ || fair_weight_[std::size_t(i)] != 0;
            }
    }

    struct Scratch {
        std::vector<std::int32_t> slot;
        std::vector<std::int32_t> columns;
        std::vector<char> full;
        std::vector<double> scalar;
        std::vector<Eigen::Matrix3d> block;
        explicit Scratch(std::int64_t n) : slot(std::size_t(n), -1) {}
    };

    /// Pattern of block row j: sorted columns and which blocks are full; values too if asked.
    void row(std::int64_t j, Scratch& s, bool values) const {
        s.columns.clear();
        const auto touch = [&](std::int32_t c) {
            if (s.slot[std::size_t(c)] < 0) {
                s.slot[std::size_t(c)] = 0;
                s.columns.push_back(c);
            }
        };
        touch(std::int32_t(j));
        for (std::int64_t q = links_.offsets[std::size_t(j)]; q < links_.offsets[std::size_t(j + 1)]; ++q) touch(links_.neighbors[std::size_t(q)]);
        for (std::int64_t q = in_.offsets[std::size_t(j)]; q < in_.offsets[std::size_t(j + 1)]; ++q) touch(in_.neighbors[std::size_t(q)]);
        // The face neighbours of j are in its links on a manifold, not always on a label complex
        // (a junction vertex is linked along its junction curve only).
        for (std::int64_t q = incidence_.start[std::size_t(j)]; q < incidence_.start[std::size_t(j + 1)]; ++q) {
            const std::int64_t f = incidence_.face[std::size_t(q)] / k_, e = incidence_.face[std::size_t(q)] % k_;
            touch(quads_(f, (e + 1) % k_));
            touch(quads_(f, (e + k_ - 1) % k_));
        }
        if (fairness_)
            for_each_fairness_row(j, [&](std::int64_t i, double) {
                for (std::int64_t q = links_.offsets[std::size_t(i)]; q < links_.offsets[std::size_t(i + 1)]; ++q) touch(links_.neighbors[std::size_t(q)]);
            });
        std::sort(s.columns.begin(), s.columns.end());
        for (std::size_t q = 0; q < s.columns.size(); ++q) s.slot[std::size_t(s.columns[q])] = std::int32_t(q);
        const auto slot = [&](std::int64_t c) { return std::size_t(s.slot[std::size_t(c)]); };

        s.full.assign(s.columns.size(), 0);
        if (values) {
            s.scalar.assign(s.columns.size(), 0.0);
            s.block.assign(s.columns.size(), Eigen::Matrix3d::Zero());
        }
        for (std::int64_t q = incidence_.start[std::size_t(j)]; q < incidence_.start[std::size_t(j + 1)]; ++q) {
            const std::int64_t f = incidence_.face[std::size_t(q)] / k_, e = incidence_.face[std::size_t(q)] % k_;
            const double weight = face_weight_[std::size_t(f)];
            if (weight == 0) continue;
            const std::size_t next = slot(quads_(f, (e + 1) % k_)), previous = slot(quads_(f, (e + k_ - 1) % k_)), self = slot(j);
            s.full[self] = s.full[next] = s.full[previous] = 1;
            if (!values) continue;
            Eigen::Matrix3d m;  // weight·u uᵀ, written so that m is exactly symmetric
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) m(r, c) = weight * (normals_(f, r) * normals_(f, c));
            s.block[self] += m;  // edge (previous, j)
            s.block[self] += m;  // edge (j, next)
            s.block[next] -= m;
            s.block[previous] -= m;
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
            s.scalar[slot(j)] += w_.alpha * data_weight(w_, j);
        }
        for (std::int32_t c : s.columns) s.slot[std::size_t(c)] = -1;
    }

    /// Scalar entries of each of the three scalar rows of block row j.
    static std::int64_t scalar_count(const Scratch& s) {
        std::int64_t count = 0;
        for (char f : s.full) count += f ? 3 : 1;
        return count;
    }

private:
    /// Calls visit(i, F_ij) for every row i of F with an entry in column j, in increasing i (an
    /// i with j several times in its link is visited once per occurrence).
    template <class Visit>
    void for_each_fairness_row(std::int64_t j, Visit visit) const {
        const std::int32_t* in = in_.neighbors.data();
        std::int64_t q = in_.offsets[std::size_t(j)];
        const std::int64_t last = in_.offsets[std::size_t(j + 1)];
        bool self_done = false;
        const auto self = [&] {
            self_done = true;
            if (fair_weight_[std::size_t(j)] != 0) visit(j, 1.0);
        };
        for (; q < last; ++q) {
            const std::int64_t i = in[q];
            if (!self_done && j <= i) self();
            if (fair_weight_[std::size_t(i)] != 0) visit(i, -1.0 / double(links_.size(i)));
        }
        if (!self_done) self();
    }

    const FaceMatrix& quads_;
    const VertexLinks& links_;
    const PointMatrix& normals_;
    const RegularizationWeights& w_;
    std::int64_t n_, k_;
    VertexLinks in_;
    Incidence incidence_;
    std::vector<double> face_weight_, fair_weight_;
    bool fairness_ = false;
};

/// Writes R into `R` (Eigen 3.4's SparseMatrix has no move assignment: returning it would copy).
void assemble_matrix(const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
                     const RegularizationWeights& w, std::int64_t n, Eigen::SparseMatrix<double>& R) {
    const BlockAssembler assembler(quads, links, normals, w, n);
    const bool parallel = n >= 4096;
    // Pass 1: entries per scalar row (the three rows of a vertex have the same count).
    std::vector<std::int64_t> row_start(std::size_t(3 * n + 1), 0);
#pragma omp parallel if (parallel)
    {
        BlockAssembler::Scratch s(n);
#pragma omp for schedule(static)
        for (std::int64_t j = 0; j < n; ++j) {
            assembler.row(j, s, false);
            const std::int64_t count = BlockAssembler::scalar_count(s);
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
        BlockAssembler::Scratch s(n);
#pragma omp for schedule(static)
        for (std::int64_t j = 0; j < n; ++j) {
            assembler.row(j, s, true);
            for (int r = 0; r < 3; ++r) {
                std::int64_t out = row_start[std::size_t(3 * j + r)];
                for (std::size_t q = 0; q < s.columns.size(); ++q) {
                    const std::int64_t c0 = 3 * std::int64_t(s.columns[q]);
                    if (s.full[q]) {
                        for (int c = 0; c < 3; ++c, ++out) {
                            inner[out] = int(c0 + c);
                            value[out] = s.block[q](r, c) + (c == r ? s.scalar[q] : 0.0);
                        }
                    } else {
                        inner[out] = int(c0 + r);
                        value[out] = s.scalar[q];
                        ++out;
                    }
                }
            }
        }
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
    RegularizationSystem system;
    assemble_matrix(quads, links, normals, weights, n, system.matrix);
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
