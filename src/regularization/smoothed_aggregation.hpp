// dsreg — internal: smoothed aggregation algebraic multigrid (Vaněk, Mandel, Brezina 1996) for
// the 3×3-block SPD regularization matrix, used as the preconditioner of conjugate gradients.
//
// Near-null space: the three rigid translations. The alignment and fairness terms of eq. (23)
// annihilate them (they only see differences of positions), so on each aggregate of vertices
// R acts on a translation like α W0: these are the smooth modes the smoother cannot reduce.
// The finest level is R without its weak blocks (filtered_blocks: the fairness term's 2-ring,
// lumped into the diagonal), which CG corrects for. Per level: strength graph on 3×3 block
// norms, greedy aggregation, tentative prolongator T = translations per aggregate, smoothed
// prolongator P = (I − ω D⁻¹A_F) T (A_F: weak blocks lumped), Galerkin coarse operator Pᵀ A P,
// Chebyshev smoother on D⁻¹A (D = 3×3 block diagonal), λmax(D⁻¹A) bounded by Lanczos.
// Coarsest level (≤ 400 vertices): CHOLMOD.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "block_sparse.hpp"

namespace dsreg::detail {

struct AmgSettings {
    double strength_threshold = 0.08;  ///< block (i,j) is strong if ‖A_ij‖ ≥ θ √(‖A_ii‖ ‖A_jj‖)
    /// Aggregation joins i and j only if they are coupled in every direction: the smallest
    /// singular value of D_i^(-1/2) A_ij D_j^(-1/2) is at least this (see aggregation_graph).
    /// 0: aggregate on the graph of strength_threshold.
    double directional_threshold = 0.04;
    /// If the directional graph leaves more than nodes / this aggregates, its threshold is halved
    /// (at most 4 times), then the graph of strength_threshold is used.
    double minimum_coarsening = 4;
    /// make_multigrid stores the hierarchy in float (half the memory and memory traffic; every
    /// computation in double) when min_i (R t)_i / mean diag(R) is at least this, the smallest
    /// data weight `auto` gives to amg. The rounding of the entries (about 2^-24·‖R‖) perturbs
    /// the preconditioner only: on lobster.vol, float and double hierarchies took the same
    /// iterations (29, 70, 107, 152) at data weights 3.7e-4, 3.7e-5, 7.5e-6 and 1.9e-6 of the
    /// diagonal. Below it (e.g. the paper's Fig. 7 α with --solver amg), double.
    double float_storage_min_data_weight = 1e-6;
    int smoothing_degree = 2;          ///< Chebyshev degree of pre- and post-smoothing
    double smoothing_range = 30;       ///< Chebyshev targets [λmax/range, λmax] of D⁻¹A
    /// The Chebyshev interval ends at this × the Lanczos estimate of λmax(D⁻¹A). The estimate
    /// (12 steps, largest Ritz value + last β) is not a guaranteed bound: it was measured 0.2–1.5 %
    /// low on bunny-64, and a degree-2 Chebyshev smoother amplifies the modes more than 3.3 % above
    /// its interval, which makes the V-cycle indefinite and CG break down. 1.1 leaves a margin of 13 %.
    double smoothing_safety = 1.1;
    double prolongator_damping = 4.0 / 3.0;  ///< ω = damping / λmax(D⁻¹A)
    std::int64_t coarsest_nodes = 400;       ///< factor the level directly at or below this size
    int max_levels = 16;
};

class RegularizationOperator;

/// The first level of the hierarchy straight from the operator's block rows (no scalar matrix):
/// R without its weak blocks (‖R_jk‖_F < θ √(‖R_jj‖_F ‖R_kk‖_F)), each lumped into its row's
/// diagonal block as diag(Σ_c |R_jk(r, c)|): the same matrix as filtered_blocks of the assembled R.
template <class Scalar>
BlockMatrixT<Scalar> filtered_fine_level(const RegularizationOperator& R, const std::vector<Eigen::Matrix3d>& diagonal, double theta);

/// One V-cycle as a preconditioner, whatever the precision of the hierarchy.
class Multigrid {
public:
    virtual ~Multigrid() = default;
    /// z = M⁻¹ r: one symmetric V-cycle from a zero initial guess.
    virtual void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const = 0;
    virtual int level_count() const = 0;
    /// Σ over levels of the operator's stored scalar entries / entries of R.
    virtual double operator_complexity() const = 0;
    /// Makes apply() a preconditioner of A_held (A with the rows and columns of the held
    /// coordinates replaced by their diagonal entries; all false: A again): the finest level's
    /// operator and block diagonal are masked, the coarse correction acts on the free
    /// coordinates only, and the coarse levels' operators are rebuilt as Galerkin products of
    /// the free coordinates on the same aggregates (about one set-up's Galerkin products per
    /// call). The V-cycle stays symmetric positive definite (any SPD coarse operators give an
    /// SPD V-cycle) and never couples free and held coordinates.
    virtual void hold(const std::vector<bool>& held) = 0;
};

/// The hierarchy with its matrices stored in Scalar (float or double).
template <class Scalar>
class SmoothedAggregation : public Multigrid {
public:
    using Matrix = BlockMatrixT<Scalar>;
    /// Builds the hierarchy for R (symmetric, both triangles stored).
    SmoothedAggregation(const Eigen::SparseMatrix<double>& R, const AmgSettings& settings);
    /// Builds the hierarchy from the fine level R without its weak blocks (filtered_fine_level);
    /// `fine_nonzeros` (R's scalar entries) is the reference of operator_complexity().
    SmoothedAggregation(Matrix filtered_fine, double fine_nonzeros, const AmgSettings& settings);
    ~SmoothedAggregation() override;
    SmoothedAggregation(const SmoothedAggregation&) = delete;
    SmoothedAggregation& operator=(const SmoothedAggregation&) = delete;

    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
    int level_count() const override;
    double operator_complexity() const override;
    void hold(const std::vector<bool>& held) override;

private:
    struct Level;
    struct Coarsest;
    struct HeldCoarse;
    void build(Matrix fine);
    std::vector<std::int32_t> aggregate_level(const Matrix& a, const std::vector<Eigen::Matrix3d>& diagonal,
                                              const StrengthGraph& strong, std::int64_t& count) const;
    void factor_coarsest(const Eigen::SparseMatrix<double>& matrix);
    void vcycle(std::size_t level, const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
    void smooth(std::size_t level, const Eigen::VectorXd& b, Eigen::VectorXd& x, bool zero_guess) const;
    /// y = A_level x, or y −= A_level x if `subtract` (A_held on the finest level while coordinates are held).
    void multiply_level(std::size_t level, const Eigen::VectorXd& x, Eigen::VectorXd& y, bool subtract = false) const;
    void mask_held(Eigen::VectorXd& v) const;
    void hold_coarse_levels();

    AmgSettings settings_;
    double fine_nonzeros_ = 0;
    std::vector<std::unique_ptr<Level>> levels_;
    std::unique_ptr<Coarsest> coarsest_;
    std::vector<char> held_;  ///< per coordinate of the finest level; empty: nothing held
    std::vector<std::int64_t> held_indices_;  ///< the held coordinates, in increasing order
    Eigen::VectorXd held_diagonal_;
    mutable Eigen::VectorXd held_product_;  ///< A_held x on the finest level, while coordinates are held
    std::vector<typename Matrix::Block> held_inverse_diagonal_;
    /// The coarse levels while coordinates are held: the Galerkin products of the free
    /// coordinates, which replace the operators of A's coarse levels (hold_coarse_levels).
    std::unique_ptr<HeldCoarse> held_coarse_;
    TransposedPattern fine_lower_;           ///< the finest level's mirrored blocks (first hold)
    TransposedPattern prolongator_columns_;  ///< Pᵀ's pattern of the finest level (first hold)
};

/// The hierarchy in float when `data_weight_ratio` (SpdSystem::data_weight_ratio) allows it
/// (AmgSettings::float_storage_min_data_weight), else in double: for an assembled R, or from the
/// operator's block rows and diagonal blocks (fine_nonzeros: R's scalar entries).
std::unique_ptr<Multigrid> make_multigrid(const Eigen::SparseMatrix<double>& R, double data_weight_ratio, const AmgSettings& settings);
std::unique_ptr<Multigrid> make_multigrid(const RegularizationOperator& R, const std::vector<Eigen::Matrix3d>& diagonal,
                                          double fine_nonzeros, double data_weight_ratio, const AmgSettings& settings);

}  // namespace dsreg::detail
