// dsreg — internal: the regularization matrix R of eq. (22–23) without storing it.
//
// R = αW0_α ⊗ I3 + γ (FᵀG F) ⊗ I3 + β Σ_f c_f Σ_{edges (a,b) of f} (e_a − e_b)(e_a − e_b)ᵀ ⊗ u_f u_fᵀ,
// with F = I − B the umbrella operator (eq. 13–14), G = diag(γ_i w0_i) and c_f = β_f w2_f. The
// operator gives
//  - y = R x from the mesh, the field and the weights (matrix-free: two passes over the vertices,
//    reading the faces around each vertex and its link): about a third of the memory traffic of
//    the assembled matrix, and no matrix in memory;
//  - the 3×3 block rows of R, one vertex at a time (from which assemble_regularization_system
//    writes the scalar CSR matrix and the multigrid solver its fine level).
// Unknowns are interleaved (3i + d), as everywhere in the regularization stage. The quads, links,
// normals and weights are referenced, not copied: they must outlive the operator.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/regularization.hpp"

namespace dsreg::detail {

/// α_i w0_i, γ_i w0_i, β_f w2_f: the local factors of the three terms (1 where a vector is empty).
double data_weight(const RegularizationWeights& w, std::int64_t vertex);
double fairness_weight(const RegularizationWeights& w, std::int64_t vertex);
double alignment_weight(const RegularizationWeights& w, std::int64_t face);

/// The part of b that the fairness targets give, γ Lᵀ Γ t (3n, interleaved), and their part of
/// E's constant, γ tᵀ Γ t; an empty vector and 0 without targets (regularization.hpp).
struct FairnessTargetTerms {
    Eigen::VectorXd rhs;
    double constant = 0;
};
FairnessTargetTerms fairness_target_terms(const VertexLinks& links, const RegularizationWeights& weights, std::int64_t vertex_count);

class RegularizationOperator {
public:
    RegularizationOperator(const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
                           const RegularizationWeights& weights, std::int64_t vertex_count);

    std::int64_t vertex_count() const { return n_; }
    std::int64_t unknowns() const { return 3 * n_; }
    /// The faces' corners at each vertex (vertex_corners of the quads).
    const VertexCorners& corners() const { return corners_; }

    /// y = R x (parallel over vertices; y is resized). Equal to the assembled matrix's product up
    /// to rounding (the terms are summed in another order).
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

    /// One block row of R: column (vertex) indices, sorted, and for each the 3×3 block.
    struct Row {
        std::vector<std::int32_t> columns;
        std::vector<Eigen::Matrix3d> blocks;
        std::vector<char> full;  ///< 1 if the block has an alignment part (9 entries), else it is c·I3
        // scratch
        std::vector<std::int32_t> slot;
        std::vector<double> scalar;
        explicit Row(std::int64_t n) : slot(std::size_t(n), -1) {}
    };
    /// Fills `row` with block row j (pattern only if `values` is false: columns and full).
    void row(std::int64_t j, Row& row, bool values) const;
    /// Calls visit(c) for each column c of block row j (the columns of row(), j included), some
    /// more than once, in no particular order: the coupling alone, without sorting the row.
    template <class Visit>
    void for_each_coupled(std::int64_t j, Visit visit) const;

    /// Diagonal blocks and ‖R‖∞ (largest absolute row sum), from one pass over the block rows.
    struct Summary {
        std::vector<Eigen::Matrix3d> diagonal;
        double infinity_norm = 0;
        double mean_diagonal = 0;   ///< mean of the scalar diagonal entries
        double scalar_nonzeros = 0;  ///< entries of the assembled scalar matrix
    };
    Summary summary() const;

private:
    template <class Visit>
    void for_each_fairness_row(std::int64_t j, Visit visit) const;

    const FaceMatrix& quads_;
    const VertexLinks& links_;
    const PointMatrix& normals_;
    const RegularizationWeights& w_;
    std::int64_t n_, k_;
    VertexLinks in_;                              ///< in(j) = {i : j ∈ link(i)}, with multiplicity
    VertexCorners corners_;                       ///< vertex → its (face, corner) pairs, increasing face
    std::vector<double> face_weight_;             ///< β β_f w2_f
    std::vector<double> fair_weight_;             ///< γ γ_i w0_i (0 where the link is empty)
    std::vector<double> data_weight_;             ///< α α_i w0_i
    bool fairness_ = false;
    mutable Eigen::VectorXd scaled_residual_;     ///< multiply(): G F x / |link|, per vertex
};

/// Calls visit(i, F_ij) for every row i of F with an entry in column j, in increasing i (an i
/// with j several times in its link is visited once per occurrence).
template <class Visit>
void RegularizationOperator::for_each_fairness_row(std::int64_t j, Visit visit) const {
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

template <class Visit>
void RegularizationOperator::for_each_coupled(std::int64_t j, Visit visit) const {
    visit(std::int32_t(j));
    for (std::int64_t q = links_.offsets[std::size_t(j)]; q < links_.offsets[std::size_t(j + 1)]; ++q) visit(links_.neighbors[std::size_t(q)]);
    for (std::int64_t q = in_.offsets[std::size_t(j)]; q < in_.offsets[std::size_t(j + 1)]; ++q) visit(in_.neighbors[std::size_t(q)]);
    // The face neighbours of j are in its links on a manifold, not always on a label complex
    // (a junction vertex is linked along its junction curve only, a junction point not at all).
    for (std::int64_t q = corners_.offsets[std::size_t(j)]; q < corners_.offsets[std::size_t(j + 1)]; ++q) {
        const std::int64_t f = corners_.codes[std::size_t(q)] / k_, e = corners_.codes[std::size_t(q)] % k_;
        visit(quads_(f, (e + 1) % k_));
        visit(quads_(f, (e + k_ - 1) % k_));
    }
    if (fairness_)
        for_each_fairness_row(j, [&](std::int64_t i, double) {
            for (std::int64_t q = links_.offsets[std::size_t(i)]; q < links_.offsets[std::size_t(i + 1)]; ++q) visit(links_.neighbors[std::size_t(q)]);
        });
}

/// Writes R, assembled, into `R` (Eigen 3.4's SparseMatrix has no move assignment: returning it
/// would copy), block row by block row: a block with an alignment part is stored full (9
/// entries), the others (the fairness term's 2-ring) as their diagonal. Exactly symmetric.
void assemble_matrix(const RegularizationOperator& rows, Eigen::SparseMatrix<double>& R);

}  // namespace dsreg::detail
