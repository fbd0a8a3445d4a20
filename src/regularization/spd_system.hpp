// dsreg — internal: what the solvers of solvers.cpp need to know of the SPD matrix R of R x = b,
// whether R is assembled (solve_spd) or applied from the mesh (regularize(): no scalar matrix in
// memory unless a direct solver needs it).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <optional>
#include <vector>

#include "block_sparse.hpp"
#include "dsreg/solvers.hpp"
#include "regularization_operator.hpp"
#include "smoothed_aggregation.hpp"

namespace dsreg::detail {

class SpdSystem {
public:
    virtual ~SpdSystem() = default;
    virtual std::int64_t unknowns() const = 0;
    /// y = R x
    virtual void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const = 0;
    /// ‖R‖∞, the largest absolute row sum
    virtual double infinity_norm() const = 0;
    /// The 3×3 diagonal blocks of R.
    virtual const std::vector<Eigen::Matrix3d>& diagonal_blocks() const = 0;
    /// min_i (R t_d)_i / mean_i R_ii over the translations t_d: the weight of the data term
    /// relative to the whole diagonal (see solvers.cpp).
    virtual double data_weight_ratio() const = 0;
    /// The multigrid hierarchy of R.
    virtual std::unique_ptr<Multigrid> multigrid(const AmgSettings& settings) const = 0;
    /// R assembled (scalar CSR, both triangles), for the direct solver.
    virtual const Eigen::SparseMatrix<double>& matrix() const = 0;
};

/// An assembled matrix (which must outlive the system).
class AssembledSystem : public SpdSystem {
public:
    explicit AssembledSystem(const Eigen::SparseMatrix<double>& R);
    std::int64_t unknowns() const override { return R_.rows(); }
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override;
    double infinity_norm() const override { return infinity_norm_; }
    const std::vector<Eigen::Matrix3d>& diagonal_blocks() const override { return diagonal_; }
    double data_weight_ratio() const override;
    std::unique_ptr<Multigrid> multigrid(const AmgSettings& settings) const override;
    const Eigen::SparseMatrix<double>& matrix() const override { return R_; }

private:
    const Eigen::SparseMatrix<double>& R_;
    std::vector<Eigen::Matrix3d> diagonal_;
    double infinity_norm_ = 0;
};

/// R of a mesh, applied matrix-free (the operator must outlive the system).
/// `smallest_data_weight` is α·min_i α_i w0_i.
class OperatorSystem : public SpdSystem {
public:
    OperatorSystem(const RegularizationOperator& R, double smallest_data_weight);
    std::int64_t unknowns() const override { return R_.unknowns(); }
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override { R_.multiply(x, y); }
    double infinity_norm() const override { return summary_.infinity_norm; }
    /// Computed again from the operator if multigrid() released them.
    const std::vector<Eigen::Matrix3d>& diagonal_blocks() const override;
    double data_weight_ratio() const override;
    /// Releases the diagonal blocks once the hierarchy is built (it keeps its own, inverted).
    std::unique_ptr<Multigrid> multigrid(const AmgSettings& settings) const override;
    const Eigen::SparseMatrix<double>& matrix() const override;

private:
    const RegularizationOperator& R_;
    mutable RegularizationOperator::Summary summary_;
    double smallest_data_weight_;
    mutable std::optional<Eigen::SparseMatrix<double>> assembled_;
};

/// solve_spd() for either kind of system (the report's residual and error bound included).
SolveReport solve_system(const SpdSystem& system, const Eigen::VectorXd& b, Eigen::VectorXd& x, const SolverOptions& options);

/// CG preconditioned by one V-cycle of `amg` (a hierarchy of R), with the stop of `options`; fills
/// the report's solver, iterations and hierarchy figures (not the residual). False if it did not
/// converge within max_iterations.
bool solve_with_multigrid(const SpdSystem& system, const Multigrid& amg, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                          const SolverOptions& options, int max_iterations, SolveReport& report);

/// The options with what regularize() fills in: the smallest eigenvalue bound α·min α_i w0_i
/// (if not given) and max_error from max_error_voxels and the smallest voxel side.
SolverOptions completed_options(const SolverOptions& options, const RegularizationWeights& weights, std::int64_t vertex_count,
                                double smallest_spacing);

/// R x = b of eq. (22–23) for one mesh, matrix-free: the operator over the mesh and the links of
/// its fairness term (fairness_links of the surface), the right-hand side α W0_α p. The mesh data
/// must outlive it.
class MeshSystem {
public:
    MeshSystem(const PointMatrix& positions, const FaceMatrix& quads, const VertexLinks& links, const PointMatrix& normals,
               const RegularizationWeights& weights);
    MeshSystem(const MeshSystem&) = delete;
    MeshSystem& operator=(const MeshSystem&) = delete;
    const OperatorSystem& system() const { return system_; }
    const Eigen::VectorXd& rhs() const { return rhs_; }

private:
    RegularizationOperator operator_;
    Eigen::VectorXd rhs_;
    OperatorSystem system_;
};

}  // namespace dsreg::detail
