// dsreg — repair of the regularized mesh until it is valid (include/dsreg/validity_repair.hpp):
// a stronger data term on what is invalid, exact local solves of eq. (1).
#include "dsreg/validity_repair.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <omp.h>

#include "../common/disjoint_sets.hpp"
// The block rows of R, computed one vertex at a time (an internal header of the regularization
// module): the repair reads the rows of its region only, never the whole assembled matrix.
#include "../regularization/blas_threads.hpp"
#include "../regularization/conjugate_gradient.hpp"
#include "../regularization/held_solver.hpp"
#include "../regularization/regularization_operator.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"  // voxel_centres_inside
#include "dsreg/label_surface.hpp"
#include "incremental_validity.hpp"
#include "dsreg/solvers.hpp"

namespace dsreg {

namespace {

using Clock = std::chrono::steady_clock;
using SparseMatrix = Eigen::SparseMatrix<double>;

/// Relative residuals to which the large local systems are solved iteratively: in the exact
/// solves of the whole region, below the 1e-9 of the repair's reported stationarity with a
/// margin; in the rounds, whose windows only steer the repair (every part of the region is solved
/// exactly before the repair ends), far less.
constexpr double kExactPartTolerance = 1e-12;
constexpr double kRoundPartTolerance = 1e-6;
/// Pointel coordinates below this (per axis) make the keys of VoxelSides.
constexpr std::int64_t kKeySide = std::int64_t(1) << 21;
/// CG iterations allowed to each solve of a large bounded part (multigrid-preconditioned).
constexpr int kIterativePartIterations = 500;
/// Block-Jacobi CG iterations allowed to each solve of a large part in the rounds.
constexpr int kBlockJacobiIterations = 400;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double element_or_one(const Eigen::VectorXd& values, Eigen::Index i) { return values.size() ? values[i] : 1.0; }

void check_inputs(const DigitalSurface& surface, const PointMatrix& normals, const PointMatrix& positions,
                  const ValidityRepairOptions& o) {
    if (normals.rows() != surface.face_count() || positions.rows() != surface.vertex_count())
        throw Error("validity repair: " + std::to_string(normals.rows()) + " normals and " +
                    std::to_string(positions.rows()) + " positions for " + std::to_string(surface.face_count()) +
                    " faces and " + std::to_string(surface.vertex_count()) + " vertices");
    const bool ok = o.alpha_start > 1 && o.alpha_step > 1 && o.alpha_cap >= o.alpha_start && std::isfinite(o.alpha_cap) &&
                    o.alpha_grade > 1 && o.grade_rings >= 0 && o.region_rings >= o.grade_rings &&
                    o.window_rings >= 0 && o.split_offset >= 0 && o.split_offset < 0.5 && o.field_margin >= 0 &&
                    o.field_margin < 1 && o.max_rounds >= 0 &&
                    (!o.clamp_half_width || (*o.clamp_half_width > o.split_offset && *o.clamp_half_width < 0.5)) &&
                    o.voxel_half_width > o.split_offset && o.voxel_half_width < 0.5 && o.voxel_reach >= 0 &&
                    o.voxel_region_rings >= 0;
    if (!ok) throw Error("validity repair: invalid options");
    if (o.voxels && (o.voxels->grid.dims != surface.grid.dims ||
                     std::int64_t(o.voxels->mask.size()) != o.voxels->grid.voxel_count()))
        throw Error("validity repair: the volume's grid is not the surface's");
    if (o.voxels && *std::max_element(surface.grid.dims.begin(), surface.grid.dims.end()) >= kKeySide)
        throw Error("validity repair: voxel centres can be kept on grids of fewer than " + std::to_string(kKeySide) +
                    " voxels per axis");
}

/// The voxel centres a mesh puts on the wrong side (options.voxels), kept up to date as vertices
/// move (only the voxel rows that the moved vertices' triangles cover, before or after, are
/// classified again), and the vertices around a voxel: those at the pointels within `reach`
/// voxels of its cube.
class VoxelSides {
public:
    /// `corners`: the quads around each vertex of surface (the incremental check's), kept by reference.
    VoxelSides(const BinaryVolume& volume, const DigitalSurface& surface, const PointMatrix& positions,
               const VertexCorners& corners)
        : volume_(volume), surface_(surface), positions_(positions),
          triangles_(mesh_triangles(positions, surface.quads)), inside_(positions, triangles_, volume.grid),
          corners_(corners) {
        pointel_vertices_.reserve(std::size_t(surface.vertex_count()));
        for (std::int64_t v = 0; v < surface.vertex_count(); ++v)
            pointel_vertices_.emplace_back(key(surface.vertex_pointels(v, 0), surface.vertex_pointels(v, 1),
                                               surface.vertex_pointels(v, 2)),
                                           std::int32_t(v));
        std::sort(pointel_vertices_.begin(), pointel_vertices_.end());
        for (std::size_t v = 0; v < volume.mask.size(); ++v) {
            object_voxels_ += volume.mask[v] != 0 ? 1 : 0;
            if (is_wrong(v)) wrong_.push_back(std::int64_t(v));
        }
    }

    /// The object voxels of the volume (counted on the scan for the wrong ones).
    std::int64_t object_voxels() const { return object_voxels_; }

    /// The vertices in `moved` are now at their rows of `positions`.
    void update(const PointMatrix& positions, const std::vector<std::int32_t>& moved) {
        if (moved.empty()) return;
        std::vector<std::int32_t> quads;
        for (const std::int32_t v : moved) corners_.for_each_face(v, [&](std::int32_t q) { quads.push_back(q); });
        std::sort(quads.begin(), quads.end());
        quads.erase(std::unique(quads.begin(), quads.end()), quads.end());
        for (const std::int32_t v : moved) positions_.row(v) = positions.row(v);
        FaceMatrix moved_quads(Eigen::Index(quads.size()), 4);
        for (std::size_t k = 0; k < quads.size(); ++k) moved_quads.row(Eigen::Index(k)) = surface_.quads.row(quads[k]);
        const FaceMatrix split = mesh_triangles(positions_, moved_quads);  // 2 triangles per quad, in order
        std::vector<std::int32_t> changed;
        changed.reserve(2 * quads.size());
        for (std::size_t k = 0; k < quads.size(); ++k) {
            triangles_.row(2 * Eigen::Index(quads[k])) = split.row(2 * Eigen::Index(k));
            triangles_.row(2 * Eigen::Index(quads[k]) + 1) = split.row(2 * Eigen::Index(k) + 1);
            changed.push_back(2 * quads[k]), changed.push_back(2 * quads[k] + 1);
        }
        update_wrong(inside_.update(positions_, triangles_, changed));
    }

    /// Linear indices of the voxels whose centre the mesh (quads split along their shorter
    /// diagonal) puts on the other side than the volume, increasing.
    const std::vector<std::int64_t>& wrong() const { return wrong_; }

    /// The vertices at the pointels within `reach` voxels of the cube of `voxel` (linear index):
    /// pointels a with i − reach ≤ a ≤ i + 1 + reach on each axis, increasing.
    std::vector<std::int32_t> vertices_near(std::int64_t voxel, int reach) const {
        const Index3& dims = volume_.grid.dims;
        const std::int64_t i = voxel % dims[0], j = (voxel / dims[0]) % dims[1], k = voxel / (dims[0] * dims[1]);
        // Pointels run from 0 to dims on each axis.
        const auto low = [&](std::int64_t x) { return std::max<std::int64_t>(x - reach, 0); };
        const auto high = [&](std::int64_t x, int d) { return std::min<std::int64_t>(x + 1 + reach, dims[d]); };
        std::vector<std::int32_t> vertices;
        for (std::int64_t c = low(k); c <= high(k, 2); ++c)
            for (std::int64_t b = low(j); b <= high(j, 1); ++b) {
                // Pointels of one (b, c) line are consecutive in key order.
                const auto first = std::lower_bound(pointel_vertices_.begin(), pointel_vertices_.end(),
                                                    std::make_pair(key(low(i), b, c), std::int32_t(-1)));
                const std::int64_t last = key(high(i, 0), b, c);
                for (auto it = first; it != pointel_vertices_.end() && it->first <= last; ++it) vertices.push_back(it->second);
            }
        std::sort(vertices.begin(), vertices.end());
        return vertices;
    }

private:
    /// Orders pointels by (c, b, a); coordinates from 0 to dims < kKeySide (check_inputs).
    static std::int64_t key(std::int64_t a, std::int64_t b, std::int64_t c) { return a + kKeySide * (b + kKeySide * c); }

    bool is_wrong(std::size_t voxel) const { return inside_.is_inside(std::int64_t(voxel)) != (volume_.mask[voxel] != 0); }

    /// wrong_ after the voxel rows `rows` (index j + ny·k, increasing) were classified again.
    void update_wrong(const std::vector<std::int64_t>& rows) {
        const std::int64_t nx = volume_.grid.dims[0];
        std::vector<std::int64_t> merged;
        merged.reserve(wrong_.size());
        auto old = wrong_.begin();
        for (const std::int64_t row : rows) {  // voxels nx·row … nx·row + nx − 1
            const std::int64_t first = nx * row, last = first + nx;
            while (old != wrong_.end() && *old < first) merged.push_back(*old++);
            while (old != wrong_.end() && *old < last) ++old;
            for (std::int64_t v = first; v < last; ++v)
                if (is_wrong(std::size_t(v))) merged.push_back(v);
        }
        merged.insert(merged.end(), old, wrong_.end());
        wrong_ = std::move(merged);
    }

    const BinaryVolume& volume_;
    const DigitalSurface& surface_;
    PointMatrix positions_;          ///< of the last update
    FaceMatrix triangles_;           ///< 2q, 2q + 1: quad q split along its shorter diagonal at positions_
    VoxelCentresInside inside_;      ///< the voxel centres inside the mesh of triangles_
    const VertexCorners& corners_;  ///< the quads around each vertex
    std::vector<std::int64_t> wrong_;  ///< the voxels whose centre is on the wrong side, increasing
    std::int64_t object_voxels_ = 0;
    std::vector<std::pair<std::int64_t, std::int32_t>> pointel_vertices_;  ///< (pointel key, vertex), sorted
};

/// Whether a voxel is left as noise: a vertex around it is one of options.noisy_voxels'.
bool left_as_noise(const VoxelSides& sides, std::int64_t voxel, const ValidityRepairOptions& o) {
    for (const std::int32_t v : sides.vertices_near(voxel, o.voxel_reach))
        if (std::size_t(v) < o.noisy_voxels.size() && o.noisy_voxels[std::size_t(v)]) return true;
    return false;
}

/// Eigen's approximate minimum degree ordering computed on the 3×3 block pattern of a part's
/// system (unknowns 3i + d) and expanded to the unknowns: the three coordinates of a vertex stay
/// together, as their dense block couples them anyway, and the ordering works on a graph of a
/// third of the nodes and a ninth of the entries (the scalar one was a tenth of the validity
/// stage of the 100-label map). Returns, as Eigen's orderings do, the inverse permutation.
struct BlockAmdOrdering {
    using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;

    template <class Matrix>
    void operator()(const Matrix& matrix, PermutationType& permutation) const {
        const Eigen::Index nodes = matrix.rows() / 3;
        std::vector<Eigen::Triplet<double, int>> pattern;
        pattern.reserve(std::size_t(matrix.nonZeros() / 3 + nodes));
        for (Eigen::Index j = 0; j < matrix.outerSize(); ++j) {
            Eigen::Index last = -1;  // rows increase within a column: a block once per column
            for (typename Matrix::InnerIterator it(matrix, j); it; ++it)
                if (it.row() / 3 != last) last = it.row() / 3, pattern.emplace_back(int(last), int(j / 3), 1.0);
        }
        Eigen::SparseMatrix<double, Eigen::ColMajor, int> blocks(nodes, nodes);
        blocks.setFromTriplets(pattern.begin(), pattern.end());
        PermutationType block_permutation;
        Eigen::AMDOrdering<int>()(blocks, block_permutation);
        permutation.resize(matrix.rows());
        for (Eigen::Index k = 0; k < nodes; ++k)
            for (int d = 0; d < 3; ++d) permutation.indices()[3 * k + d] = 3 * block_permutation.indices()[k] + d;
    }
};
using PartCholesky = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, BlockAmdOrdering>;

/// Solves with R whose held coordinates are decoupled (held_solver.hpp) by Eigen's simplicial
/// Cholesky on one symbolic analysis: for the box QPs of small parts, where CHOLMOD's supernodal
/// analysis and BLAS calls cost more than the factorization.
class SimplicialHeldSolver : public detail::HeldSolver {
public:
    explicit SimplicialHeldSolver(const Eigen::SparseMatrix<double>& R) : R_(R), work_(R), diagonal_(R.diagonal()) {
        R_.makeCompressed();
        work_.makeCompressed();
        cholesky_.analyzePattern(R_);
    }
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override { y = R_ * x; }
    const Eigen::VectorXd& diagonal() const override { return diagonal_; }
    void hold(const std::vector<bool>& held) override {
        detail::mask_held(R_, held, work_);
        cholesky_.factorize(work_);
        ++factorizations_;
        if (cholesky_.info() != Eigen::Success) throw Error("validity repair: a local system is not positive definite");
    }
    bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double) override {
        y = cholesky_.solve(rhs);
        return true;
    }
    bool exact() const override { return true; }
    int factorizations() const override { return factorizations_; }

private:
    Eigen::SparseMatrix<double> R_, work_;  ///< work_: R_'s pattern, the held rows and columns masked
    Eigen::VectorXd diagonal_;
    PartCholesky cholesky_;
    int factorizations_ = 0;
};

/// CG on R with the held coordinates decoupled (held_solver.hpp), preconditioned by its 3×3
/// diagonal blocks (the held coordinates' rows and columns reduced to their diagonal): for the box
/// QPs of the large parts in the rounds, which only steer the repair. No hierarchy to build, and
/// a window's held boundary keeps its system well conditioned (as the unbounded parts of the
/// rounds, solve_large_part).
class BlockJacobiHeldSolver : public detail::HeldSolver {
public:
    BlockJacobiHeldSolver(const Eigen::SparseMatrix<double>& R, int max_iterations)
        : R_(R), diagonal_(R.diagonal()), blocks_(std::size_t(R.rows() / 3), Eigen::Matrix3d::Zero()),
          inverses_(blocks_.size()), held_(std::size_t(R.rows()), false), max_iterations_(max_iterations) {
        Eigen::VectorXd row_sums = Eigen::VectorXd::Zero(R.rows());
        for (Eigen::Index j = 0; j < R.outerSize(); ++j)
            for (Eigen::SparseMatrix<double>::InnerIterator it(R, j); it; ++it) {
                row_sums[it.row()] += std::abs(it.value());
                if (it.row() / 3 == j / 3) blocks_[std::size_t(j / 3)](it.row() % 3, j % 3) = it.value();
            }
        infinity_norm_ = row_sums.size() ? row_sums.maxCoeff() : 0.0;
        invert_blocks();
    }
    void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override { y = R_ * x; }
    const Eigen::VectorXd& diagonal() const override { return diagonal_; }
    void hold(const std::vector<bool>& held) override {
        held_ = held;
        held_indices_.clear();
        for (std::size_t q = 0; q < held.size(); ++q)
            if (held[q]) held_indices_.push_back(Eigen::Index(q));
        invert_blocks();
    }
    bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& y, double tolerance) override {
        Eigen::VectorXd free_part;
        const detail::LinearOperator product = [&](const Eigen::VectorXd& x, Eigen::VectorXd& out) {
            detail::held_product([&](const Eigen::VectorXd& y, Eigen::VectorXd& z) { z = R_ * y; }, held_indices_, diagonal_, x,
                                 free_part, out);
        };
        const detail::Preconditioner block_jacobi = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
            z.resize(r.size());
            for (std::size_t v = 0; v < inverses_.size(); ++v) z.segment<3>(3 * Eigen::Index(v)) = inverses_[v] * r.segment<3>(3 * Eigen::Index(v));
        };
        detail::CgStop stop;
        stop.absolute_residual = tolerance;
        stop.max_iterations = max_iterations_;
        const detail::CgResult cg = detail::preconditioned_conjugate_gradient(product, infinity_norm_, rhs, y, block_jacobi, stop);
        iterations_ += cg.iterations;
        return cg.converged;
    }
    bool exact() const override { return false; }
    int iterations() const override { return iterations_; }

private:
    /// The inverse of each diagonal block with its held rows and columns reduced to the diagonal.
    void invert_blocks() {
        for (std::size_t v = 0; v < blocks_.size(); ++v) {
            Eigen::Matrix3d block = blocks_[v];
            for (int d = 0; d < 3; ++d) {
                if (!held_[3 * v + std::size_t(d)]) continue;
                const double kept = block(d, d);
                block.row(d).setZero();
                block.col(d).setZero();
                block(d, d) = kept;
            }
            inverses_[v] = block.inverse();
        }
    }

    const Eigen::SparseMatrix<double>& R_;
    Eigen::VectorXd diagonal_;
    std::vector<Eigen::Matrix3d> blocks_, inverses_;
    std::vector<bool> held_;
    std::vector<Eigen::Index> held_indices_;
    double infinity_norm_ = 0;
    int max_iterations_;
    int iterations_ = 0;
};

/// The neighbours of each vertex across every edge of the mesh, both ways, in increasing order.
/// On a closed manifold (any binary volume) these are the quad links; on a label complex they
/// also give a junction vertex its neighbours in the sheets, which the junction-aware fairness
/// links leave out (a junction point has no link at all): the region and the graded weights of
/// the repair must spread from a junction into the sheets that meet there.
VertexLinks edge_neighbours(const FaceMatrix& quads, std::int64_t vertex_count) {
    std::vector<std::vector<std::int32_t>> around(static_cast<std::size_t>(vertex_count));
    for (Eigen::Index f = 0; f < quads.rows(); ++f)
        for (int e = 0; e < 4; ++e) {
            const std::int32_t a = quads(f, e), b = quads(f, (e + 1) % 4);
            around[std::size_t(a)].push_back(b);
            around[std::size_t(b)].push_back(a);
        }
    VertexLinks links;
    links.offsets.assign(static_cast<std::size_t>(vertex_count + 1), 0);
    for (std::size_t v = 0; v < around.size(); ++v) {
        std::sort(around[v].begin(), around[v].end());
        around[v].erase(std::unique(around[v].begin(), around[v].end()), around[v].end());
        links.offsets[v + 1] = links.offsets[v] + std::int64_t(around[v].size());
        links.neighbors.insert(links.neighbors.end(), around[v].begin(), around[v].end());
    }
    return links;
}

/// Vertices within `rings` rings of `seeds` (seeds included) that pass `keep`, sorted.
template <class Keep>
std::vector<std::int32_t> rings_around(const VertexLinks& links, const std::vector<std::int32_t>& seeds, int rings,
                                       std::vector<char>& mark, Keep keep) {
    std::vector<std::int32_t> result, frontier;
    for (const std::int32_t v : seeds)
        if (!mark[std::size_t(v)]) mark[std::size_t(v)] = 1, frontier.push_back(v);
    result = frontier;
    for (int ring = 0; ring < rings; ++ring) {
        std::vector<std::int32_t> next;
        for (const std::int32_t v : frontier)
            for (std::int64_t k = links.offsets[std::size_t(v)]; k < links.offsets[std::size_t(v) + 1]; ++k) {
                const std::int32_t w = links.neighbors[std::size_t(k)];
                if (mark[std::size_t(w)]) continue;
                mark[std::size_t(w)] = 1;
                next.push_back(w);
            }
        result.insert(result.end(), next.begin(), next.end());
        frontier.swap(next);
    }
    for (const std::int32_t v : result) mark[std::size_t(v)] = 0;
    result.erase(std::remove_if(result.begin(), result.end(), [&](std::int32_t v) { return !keep(v); }), result.end());
    std::sort(result.begin(), result.end());
    return result;
}

/// The state of a repair: the α factors m_i, the held vertices, the corrected field, the region
/// and the current positions x. E' differs from E (R x = b, R read block row by block row for the
/// vertices solved: the region is usually a small part of the mesh) by
///   Σ_i (m_i − 1) α α_i w0_i |x_i − t_i|²  +  Σ_{corrected f} β β_f w2_f Σ_e [((x_a − x_b)·u'_f)² − ((x_a − x_b)·u_f)²]
///   + Σ_i (n_i − 1) γ γ_i w0_i |x_i − mean_{j ∈ link(i)} x_j|²   (n_i: fairness first, smooth_first),
/// which the local solves add to the rows they solve for.
class Repair {
public:
    Repair(const DigitalSurface& surface, const VertexLinks& links, std::vector<char> junction_turns,
           const PointMatrix& normals, const RegularizationWeights& weights, const PointMatrix& positions,
           const ValidityRepairOptions& options)
        : surface_(surface), weights_(weights), o_(options), links_(links),
          neighbours_(edge_neighbours(surface.quads, surface.vertex_count())),
          input_field_(normals), field_(normals), targets_(repair_targets(surface, options.split_offset)),
          x_(flatten_points(positions)), factor_(std::size_t(surface.vertex_count()), 1.0),
          fair_factor_(std::size_t(surface.vertex_count()), 1.0), fair_steps_(std::size_t(surface.vertex_count()), 0),
          held_(std::size_t(surface.vertex_count()), 0), junction_turn_(std::move(junction_turns)),
          in_region_(std::size_t(surface.vertex_count()), 0),
          corrected_(std::size_t(surface.face_count()), 0), changed_(std::size_t(surface.vertex_count()), 1),
          local_(std::size_t(surface.vertex_count()), -1), mark_(std::size_t(surface.vertex_count()), 0),
          rows_(surface.quads, links_, input_field_, weights, surface.vertex_count()),
          target_rhs_(detail::fairness_target_terms(links, weights, surface.vertex_count()).rhs) {
        for (int t = 0; t < omp_get_max_threads(); ++t) row_scratch_.emplace_back(surface.vertex_count());
        bounded_.assign(std::size_t(surface.vertex_count()), 0);
        if (o_.clamp_half_width)
            for (std::int64_t v = 0; v < surface.vertex_count(); ++v) bound_box(std::int32_t(v), *o_.clamp_half_width);
    }

    /// Bounds the vertices around the voxels of `wrong` (VoxelSides, options.voxels): along the
    /// axes of their own faces, `voxel_reach` voxels around at first, one more each time the
    /// voxel is found wrong again. Returns the vertices bounded now, increasing.
    std::vector<std::int32_t> bound_around(const VoxelSides& sides, const std::vector<std::int64_t>& wrong) {
        std::vector<std::int32_t> newly;
        for (const std::int64_t voxel : wrong)
            for (const std::int32_t v : sides.vertices_near(voxel, o_.voxel_reach + voxel_tries_[voxel]++))
                if (bound_faces_of(v)) newly.push_back(v);
        std::sort(newly.begin(), newly.end());
        newly.erase(std::unique(newly.begin(), newly.end()), newly.end());
        return newly;
    }

    std::int64_t bounded_vertex_count() const { return std::count(bounded_.begin(), bounded_.end(), 1); }

    /// One round on the invalid faces of `validity`: corrects the field, strengthens the data term,
    /// grows the region and re-solves the free region vertices within `window_rings` of the
    /// strengthened ones. `moved` and `refield` receive the vertices moved and the faces whose u
    /// changed.
    void round(const MeshValidity& validity, const std::vector<std::int32_t>& bounded, ValidityRepairReport& report,
               std::vector<std::int32_t>& moved, std::vector<std::int32_t>& refield) {
        const auto started = Clock::now();
        moved_ = &moved;
        refield = correct_field(validity.folded, report);
        for (const std::int32_t f : refield)
            for (int k = 0; k < 4; ++k) changed_[std::size_t(surface_.quads(f, k))] = 1;
        const std::vector<std::int32_t> invalid = vertices_to_strengthen(validity);
        std::vector<std::int32_t> strengthened = strengthen(invalid);
        strengthened.insert(strengthened.end(), bounded.begin(), bounded.end());  // the seeds of the region and window
        std::sort(strengthened.begin(), strengthened.end());
        strengthened.erase(std::unique(strengthened.begin(), strengthened.end()), strengthened.end());
        for (const std::int32_t v : strengthened) changed_[std::size_t(v)] = 1;
        const auto join_region = [&](const std::vector<std::int32_t>& seeds, int rings) {
            for (const std::int32_t v : rings_around(neighbours_, seeds, rings, mark_, [](std::int32_t) { return true; })) {
                if (!in_region_[std::size_t(v)]) changed_[std::size_t(v)] = 1;  // a new unknown of its part
                in_region_[std::size_t(v)] = 1;
            }
        };
        join_region(strengthened, o_.region_rings);
        // The bounded vertices' region reaches further: where it stops, the mesh stays at p*, which
        // the bounds have moved away from (a wider region brings the result nearer the minimizer
        // of the whole mesh under the bounds).
        if (!bounded.empty()) join_region(bounded, std::max(o_.region_rings, o_.voxel_region_rings));
        solve(rings_around(neighbours_, strengthened, o_.window_rings, mark_, [&](std::int32_t v) { return free_in_region(v); }),
              kRoundPartTolerance, report);
        report.solve_seconds += seconds_since(started);
    }

    /// Solves the whole free region exactly; `moved` receives the vertices moved. A part that
    /// an earlier exact solve left at its minimizer, and whose system has not changed since (no
    /// vertex of it or coupled to it moved or changed weight, no face of it changed field), is
    /// left as it is: solving it again would give the same positions (lobster.vol: two of its three
    /// large parts in the second and third exact solves).
    void solve_region(ValidityRepairReport& report, std::vector<std::int32_t>& moved) {
        const auto started = Clock::now();
        moved_ = &moved;
        std::vector<std::int32_t> region;
        for (std::size_t i = 0; i < in_region_.size(); ++i)
            if (free_in_region(std::int64_t(i))) region.push_back(std::int32_t(i));
        solve(region, kExactPartTolerance, report, /*skip_unchanged=*/true);
        std::fill(changed_.begin(), changed_.end(), 0);
        report.solve_seconds += seconds_since(started);
    }

    /// Relative residual ‖A x − b‖ / ‖b‖ of E' on the free region (its stationarity; the KKT
    /// residual of the box QP with the clamp boxes). A x is summed row by row from the operator:
    /// the region's matrix, as large as the region's whole system, is never assembled (on
    /// lobster.vol it was the peak of the run).
    double region_residual() {
        std::vector<std::int32_t> region;
        for (std::size_t i = 0; i < in_region_.size(); ++i)
            if (free_in_region(std::int64_t(i))) region.push_back(std::int32_t(i));
        if (region.empty()) return 0;
        for (std::size_t k = 0; k < region.size(); ++k) local_[std::size_t(region[k])] = std::int32_t(k);
        Eigen::VectorXd b, x;
        visit_part_system(region, [](Eigen::Index, Eigen::Index, double) {}, b);
        gather(region, x);
        const auto multiply = [&](const Eigen::VectorXd& y) {
            Eigen::VectorXd product = Eigen::VectorXd::Zero(y.size()), unused;
            visit_part_system(region, [&](Eigen::Index r, Eigen::Index c, double value) { product[r] += value * y[c]; }, unused);
            return product;
        };
        double residual = 0;
        if (any_bounds_) {
            Eigen::VectorXd lower, upper;
            bounds_of(region, lower, upper);
            residual = box_qp_optimality(multiply, b, lower, upper, x, o_.qp.tolerance).kkt_residual;
        } else {
            residual = (multiply(x) - b).norm() / std::max(b.norm(), 1e-300);
        }
        for (const std::int32_t v : region) local_[std::size_t(v)] = -1;
        return residual;
    }

    PointMatrix positions() const { return unflatten_points(x_); }
    /// Puts the positions back to `x` (a state of this repair); returns the vertices that change.
    std::vector<std::int32_t> restore(const Eigen::VectorXd& x) {
        std::vector<std::int32_t> changed;
        for (Eigen::Index v = 0; v < x.size() / 3; ++v)
            if (x.segment<3>(3 * v) != x_.segment<3>(3 * v)) changed.push_back(std::int32_t(v));
        for (const std::int32_t v : changed) changed_[std::size_t(v)] = 1;
        x_ = x;
        return changed;
    }
    const Eigen::VectorXd& state() const { return x_; }
    const PointMatrix& field() const { return field_; }

    void finish(ValidityRepairResult& result) const {
        result.alpha_factors.resize(surface_.vertex_count());
        result.fairness_factors.resize(surface_.vertex_count());
        for (std::int64_t i = 0; i < surface_.vertex_count(); ++i) {
            result.alpha_factors[i] = factor_[std::size_t(i)];
            result.fairness_factors[i] = fair_factor_[std::size_t(i)];
            if (in_region_[std::size_t(i)]) result.region.push_back(std::int32_t(i));
            if (held_[std::size_t(i)]) result.held.push_back(std::int32_t(i));
            result.report.strengthened_vertices += factor_[std::size_t(i)] > 1 ? 1 : 0;
            result.report.smoothed_vertices += fair_factor_[std::size_t(i)] > 1 ? 1 : 0;
        }
        result.report.region_vertices = std::int64_t(result.region.size());
        result.report.held_vertices = std::int64_t(result.held.size());
        result.targets = targets_;
    }

private:
    /// Replaces u on the folded faces whose u points into the object or along the face; returns them.
    std::vector<std::int32_t> correct_field(const std::vector<std::int32_t>& folded, ValidityRepairReport& report) {
        std::vector<std::int32_t> corrected;
        for (const std::int32_t f : folded) {
            if (!lift_into_surfel_half_space(surface_, field_, f, o_.field_margin)) continue;
            corrected_[std::size_t(f)] = 1;
            corrected.push_back(f);
            ++report.field_corrections;
        }
        return corrected;
    }

    /// The vertices whose data term a round strengthens: every corner of an intersecting or
    /// degenerate face; of a folded face, the apex of each corner triangle turned against u (the
    /// vertex on the wrong side of the diagonal between its two neighbours in the quad, whose
    /// target, a corner of the digital square, is on the right side), or every corner once those
    /// apexes are all held. Sorted, each once.
    std::vector<std::int32_t> vertices_to_strengthen(const MeshValidity& validity) const {
        std::vector<std::int32_t> vertices;
        for (const std::int32_t f : validity.intersecting_faces)
            for (int k = 0; k < 4; ++k) vertices.push_back(surface_.quads(f, k));
        for (const std::int32_t f : validity.folded) {
            std::array<Eigen::Vector3d, 4> quad;
            for (int k = 0; k < 4; ++k) quad[std::size_t(k)] = x_.segment<3>(3 * Eigen::Index(surface_.quads(f, k)));
            const std::array<bool, 4> folded = folded_corners(quad, field_.row(f).transpose());
            const std::size_t first = vertices.size();
            bool all_held = true;
            for (int k = 0; k < 4; ++k) {
                if (!folded[std::size_t(k)]) continue;
                vertices.push_back(surface_.quads(f, k));
                all_held = all_held && held_[std::size_t(surface_.quads(f, k))];
            }
            // All four when the apexes are held already, or when none is found (the check's
            // triangles, based at another corner, may round a nearly flat corner the other way):
            // so every folded face strengthens something, and the repair still ends valid.
            if (vertices.size() == first || all_held)
                for (int k = 0; k < 4; ++k) vertices.push_back(surface_.quads(f, k));
        }
        std::sort(vertices.begin(), vertices.end());
        vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
        return vertices;
    }

    /// One step up for each invalid vertex: m_i × alpha_step (at least alpha_start), or held at
    /// its target once m_i reached alpha_cap; the rings around get at least m / alpha_grade per
    /// ring (grade_rings rings), so that the pulled vertices join the rest smoothly. Returns every
    /// vertex whose factor or hold changed.
    std::vector<std::int32_t> strengthen(const std::vector<std::int32_t>& invalid) {
        std::vector<std::int32_t> changed;
        for (const std::int32_t v : invalid) {
            changed.push_back(v);
            if (smooth_first(v)) {
                double& n = fair_factor_[std::size_t(v)];
                if (n == 1) fair_vertices_.push_back(v);
                n = std::max(n * o_.fairness_step, o_.fairness_start);
                ++fair_steps_[std::size_t(v)];
                for (std::int64_t k = links_.offsets[std::size_t(v)]; k < links_.offsets[std::size_t(v) + 1]; ++k)
                    changed_[std::size_t(links_.neighbors[std::size_t(k)])] = 1;  // rows of its term
                continue;
            }
            double& m = factor_[std::size_t(v)];
            if (m < o_.alpha_cap) {
                m = std::max(m * o_.alpha_step, o_.alpha_start);
            } else if (!held_[std::size_t(v)]) {
                held_[std::size_t(v)] = 1;
                x_.segment<3>(3 * Eigen::Index(v)) = targets_.row(v).transpose();
                moved_->push_back(v);
                changed_[std::size_t(v)] = 1;
            }
        }
        std::vector<std::int32_t> frontier;
        for (const std::int32_t v : invalid)
            if (factor_[std::size_t(v)] > 1 && !junction_turn(v)) frontier.push_back(v);
        for (int ring = 0; ring < o_.grade_rings; ++ring) {
            std::vector<std::int32_t> next;
            for (const std::int32_t v : frontier)
                for (std::int64_t k = neighbours_.offsets[std::size_t(v)]; k < neighbours_.offsets[std::size_t(v) + 1]; ++k) {
                    const std::int32_t w = neighbours_.neighbors[std::size_t(k)];
                    const double graded = factor_[std::size_t(v)] / o_.alpha_grade;
                    if (graded <= std::max(factor_[std::size_t(w)], 1.0)) continue;
                    factor_[std::size_t(w)] = graded;
                    next.push_back(w);
                }
            changed.insert(changed.end(), next.begin(), next.end());
            frontier.swap(next);
        }
        std::sort(changed.begin(), changed.end());
        changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
        index_fair_terms();
        return changed;
    }

    /// Indexes the raised fairness terms by the vertices whose rows they reach (the raised vertex
    /// and its link), each vertex's in the order they were raised: fair_term_offsets_ and
    /// fair_term_entries_, rebuilt when vertices were raised since.
    void index_fair_terms() {
        if (fair_terms_indexed_ == fair_vertices_.size()) return;
        fair_terms_indexed_ = fair_vertices_.size();
        const auto for_each_row = [&](std::int32_t i, auto visit) {
            visit(i);
            for (std::int64_t k = links_.offsets[std::size_t(i)]; k < links_.offsets[std::size_t(i) + 1]; ++k)
                visit(links_.neighbors[std::size_t(k)]);
        };
        fair_term_offsets_.assign(std::size_t(surface_.vertex_count()) + 1, 0);
        for (const std::int32_t i : fair_vertices_) for_each_row(i, [&](std::int32_t v) { ++fair_term_offsets_[std::size_t(v) + 1]; });
        for (std::size_t v = 0; v + 1 < fair_term_offsets_.size(); ++v) fair_term_offsets_[v + 1] += fair_term_offsets_[v];
        fair_term_entries_.resize(std::size_t(fair_term_offsets_.back()));
        std::vector<std::int64_t> cursor(fair_term_offsets_.begin(), fair_term_offsets_.end() - 1);
        for (std::size_t t = 0; t < fair_vertices_.size(); ++t)
            for_each_row(fair_vertices_[t], [&](std::int32_t v) { fair_term_entries_[std::size_t(cursor[std::size_t(v)]++)] = std::int32_t(t); });
    }

    /// Whether v is at the inner corner of a turn of a junction curve (strengthened alone).
    bool junction_turn(std::int32_t v) const { return !junction_turn_.empty() && junction_turn_[std::size_t(v)]; }

    /// Whether a fold at v raises its fairness this round rather than its data term (not where
    /// the fairness weight is 0: nothing to raise).
    bool smooth_first(std::int32_t v) const {
        return fair_steps_[std::size_t(v)] < o_.fairness_steps && std::size_t(v) < o_.smooth_first.size() &&
               o_.smooth_first[std::size_t(v)] && weights_.gamma * detail::fairness_weight(weights_, v) > 0;
    }

    bool free_in_region(std::int64_t v) const { return in_region_[std::size_t(v)] && !held_[std::size_t(v)]; }

    /// Minimizes E' over `vertices` (sorted, free region vertices), every other vertex held:
    /// each connected part (under the coupling of R) on its own; `tolerance`: the relative residual
    /// of the iterative solves of large parts. With `skip_unchanged`, the parts whose system has
    /// not changed since the last exact solve (changed_) are not solved again.
    void solve(const std::vector<std::int32_t>& vertices, double tolerance, ValidityRepairReport& report,
               bool skip_unchanged = false) {
        for (const std::int32_t v : vertices) mark_[std::size_t(v)] = 1;
        detail::DisjointSets<> parts(mark_.size());  // the connected parts of the region
        std::vector<char> touched(vertices.size(), 0);  ///< the vertex or one coupled to it changed
        for (std::size_t k = 0; k < vertices.size(); ++k) {
            const std::int32_t v = vertices[k];
            touched[k] = changed_[std::size_t(v)];
            rows_.for_each_coupled(v, [&](std::int32_t c) {
                if (mark_[std::size_t(c)]) parts.unite(v, c);
                touched[k] |= changed_[std::size_t(c)];
            });
        }
        std::vector<std::int64_t> index_of_root(mark_.size(), -1);
        std::vector<std::vector<std::int32_t>> groups;
        std::vector<char> group_touched;
        for (std::size_t k = 0; k < vertices.size(); ++k) {
            std::int64_t& index = index_of_root[std::size_t(parts.find(vertices[k]))];
            if (index < 0) index = std::int64_t(groups.size()), groups.emplace_back(), group_touched.push_back(0);
            groups[std::size_t(index)].push_back(vertices[k]);
            group_touched[std::size_t(index)] |= touched[k];
        }
        for (const std::int32_t v : vertices) mark_[std::size_t(v)] = 0;
        if (skip_unchanged) {
            std::size_t kept = 0;
            for (std::size_t k = 0; k < groups.size(); ++k) {
                if (!group_touched[k]) continue;
                if (k != kept) groups[kept].swap(groups[k]);
                ++kept;
            }
            groups.resize(kept);
        }
        // The parts share no unknown and no coupling: they are solved side by side (each reads the
        // positions around it, which no other part writes), the small ones first. A part solved
        // beside others runs on one thread (nested OpenMP regions are inactive, the BLAS under
        // the box QPs' CHOLMOD at one thread), so the large ones go side by side only when none
        // holds more than 2/3 of their vertices (one part gains about 1.2–1.4× from two threads).
        // lobster.vol's rounds 1–4 have three or four of 2–8K vertices, its exact solves two
        // multigrid parts of 9K and 14K vertices: side by side, its local solves take 1.10 s
        // instead of 1.33, and the two hierarchies (+19 MiB) stay below the peak of the solve.
        std::vector<std::size_t> small, large;
        std::size_t large_vertices = 0, largest = 0;
        for (std::size_t k = 0; k < groups.size(); ++k) {
            if (is_small(groups[k])) {
                small.push_back(k);
                continue;
            }
            large.push_back(k);
            large_vertices += groups[k].size();
            largest = std::max(largest, groups[k].size());
        }
        std::vector<std::vector<std::int32_t>> moved(groups.size());
        std::vector<char> converged(groups.size(), 1);
        const auto solve_side_by_side = [&](const std::vector<std::size_t>& which, int chunk, bool together) {
            std::vector<char> failed(which.size(), 0);
            // The box QPs factor with the BLAS: side by side only if each call then runs on its own
            // thread (a count the user set above one would queue them); the other parts use the
            // BLAS only in a rare fallback.
            std::optional<detail::OneBlasThread> blas;
            if (together && !blas.emplace().serial() && any_bounds_) together = false;
#pragma omp parallel for schedule(dynamic, chunk) if (together)
            for (std::size_t k = 0; k < which.size(); ++k) {
                try {
                    converged[which[k]] = solve_part(groups[which[k]], tolerance, moved[which[k]]);
                } catch (...) {
                    failed[k] = 1;  // no exception may leave the parallel loop
                }
            }
            if (std::find(failed.begin(), failed.end(), 1) != failed.end())
                throw Error("validity repair: a local system is not positive definite");
        };
        solve_side_by_side(small, 8, small.size() > 16);
        solve_side_by_side(large, 1, large.size() > 1 && 3 * largest <= 2 * large_vertices);
        for (std::size_t k = 0; k < groups.size(); ++k) {
            moved_->insert(moved_->end(), moved[k].begin(), moved[k].end());
            for (const std::int32_t v : moved[k]) changed_[std::size_t(v)] = 1;
            report.converged = report.converged && converged[k];
        }
        report.parts_solved += std::int64_t(groups.size());
    }

    /// Parts this small are solved several at once: by a simplicial Cholesky factorization, or
    /// with the clamp boxes by the box QP; larger ones by CG (multigrid CG in the exact solves) or
    /// the box QP, side by side when none dominates.
    static bool is_small(const std::vector<std::int32_t>& part) {
        constexpr std::size_t kSmallPartVertices = 2000;
        return part.size() <= kSmallPartVertices;
    }

    /// Adds block `M` at (row vertex r, column vertex c) of E' restricted to the part's vertices
    /// [first, last) (`part` sorted): into the part's matrix if c is in the part, else times x_c
    /// into the right-hand side. Whether r is in the part is looked up in `part`, not in local_:
    /// r may be the far corner of a corrected face, which R need not couple to the part (with
    /// γ = 0, or where the fairness links are empty), so it may belong to another part that a
    /// thread beside is solving and whose indices it is writing into local_. c, an edge
    /// neighbour of r, is coupled to r by R: in r's part or in none.
    template <class Entry>
    void add_block(const std::vector<std::int32_t>& part, std::int32_t r, std::int32_t c, const Eigen::Matrix3d& M, Entry& entry,
                   Eigen::VectorXd& b, std::size_t first, std::size_t last) const {
        if (!std::binary_search(part.begin() + std::ptrdiff_t(first), part.begin() + std::ptrdiff_t(last), r)) return;
        const std::int32_t lr = local_[std::size_t(r)], lc = local_[std::size_t(c)];
        if (lc >= 0) {
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) entry(3 * Eigen::Index(lr) + i, 3 * Eigen::Index(lc) + j, M(i, j));
        } else {
            b.segment<3>(3 * Eigen::Index(lr)) -= M * x_.segment<3>(3 * Eigen::Index(c));
        }
    }

    /// The stronger fairness terms (n_i − 1) γ γ_i w0_i |x_i − mean_{j ∈ link(i)} x_j|² (eq. 11–14)
    /// that reach the rows [first, last) of the part: their blocks e a_r a_c I3, with a_i = 1 and
    /// a_j = −1/|link(i)| per occurrence of j in the link. R's own fairness term i couples the same
    /// vertices, so they are all in the part or held.
    template <class Entry>
    void add_fairness_terms(const std::vector<std::int32_t>& part, Entry& entry, Eigen::VectorXd& b, std::size_t first,
                            std::size_t last) const {
        if (fair_term_offsets_.empty()) return;
        // The terms that reach the rows, in the order the vertices were raised (that of the sums
        // at each entry): looked up at the rows' vertices, not searched for among all the raised
        // ones (lobster.vol: 1 440 parts solved, up to 14 616 raised vertices).
        std::vector<std::int32_t> reaching;
        for (std::size_t k = first; k < last; ++k) {
            const std::size_t v = std::size_t(part[k]);
            reaching.insert(reaching.end(), fair_term_entries_.begin() + std::ptrdiff_t(fair_term_offsets_[v]),
                            fair_term_entries_.begin() + std::ptrdiff_t(fair_term_offsets_[v + 1]));
        }
        std::sort(reaching.begin(), reaching.end());
        reaching.erase(std::unique(reaching.begin(), reaching.end()), reaching.end());
        std::vector<std::pair<std::int32_t, double>> term;
        for (const std::int32_t raised : reaching) {
            const std::int32_t i = fair_vertices_[std::size_t(raised)];
            const std::int64_t begin = links_.offsets[std::size_t(i)], end = links_.offsets[std::size_t(i) + 1];
            if (end == begin) continue;
            const double e = (fair_factor_[std::size_t(i)] - 1) * weights_.gamma * detail::fairness_weight(weights_, i);
            // With e = 0 (γ γ_i w0_i = 0) R does not couple the term's vertices, so they may lie in
            // other parts, whose local indices local_ holds too when parts are solved side by side.
            if (!(e > 0)) continue;
            term.assign(1, {i, 1.0});
            for (std::int64_t k = begin; k < end; ++k) term.emplace_back(links_.neighbors[std::size_t(k)], -1.0 / double(end - begin));
            for (const auto& [r, ar] : term)
                for (const auto& [c, ac] : term)
                    add_block(part, r, c, e * ar * ac * Eigen::Matrix3d::Identity(), entry, b, first, last);
        }
    }

    /// The rows of E' for the part (local_ set): R_PP x_P = b_P − R_P,rest x_rest, plus the
    /// repair's terms. A block of R without an alignment part is c·I3 and gives its diagonal only,
    /// as in the assembled matrix. Calls entry(row, column, value) for each entry of R_PP + the
    /// repair's terms in the rows of the part's vertices [first, last), in the order of the rows
    /// except for the corrected faces' entries, which come last (entries at the same place add
    /// up), and fills those rows of b (b has the part's size).
    template <class Entry>
    void visit_part_system(const std::vector<std::int32_t>& part, Entry entry, Eigen::VectorXd& b, std::size_t first = 0,
                           std::size_t last = std::numeric_limits<std::size_t>::max()) const {
        last = std::min(last, part.size());
        assert(std::is_sorted(part.begin(), part.end()));  // add_block looks vertices up in it
        detail::RegularizationOperator::Row& row = row_scratch_[std::size_t(omp_get_thread_num())];
        b.resize(3 * Eigen::Index(part.size()));  // kept as it is when it has the size already
        for (std::size_t k = first; k < last; ++k) {
            const std::int32_t v = part[k];
            const Eigen::Index r = 3 * Eigen::Index(k);
            b.segment<3>(r) = weights_.alpha * detail::data_weight(weights_, v) * surface_.vertices.row(v).transpose();
            if (target_rhs_.size() > 0) b.segment<3>(r) += target_rhs_.segment<3>(3 * Eigen::Index(v));
            rows_.row(v, row, true);
            for (std::size_t q = 0; q < row.columns.size(); ++q) {
                const std::int32_t c = row.columns[q];
                const Eigen::Matrix3d& block = row.blocks[q];
                const std::int32_t column_local = local_[std::size_t(c)];
                if (column_local < 0) {
                    b.segment<3>(r) -= block * x_.segment<3>(3 * Eigen::Index(c));
                    continue;
                }
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        if (row.full[q] || i == j) entry(r + i, 3 * Eigen::Index(column_local) + j, block(i, j));
            }
            // Stronger data term (m − 1) α α_i w0_i |x_i − t_i|².
            const double extra = (factor_[std::size_t(v)] - 1) * weights_.alpha * element_or_one(weights_.vertex_alpha, v) *
                                 element_or_one(weights_.vertex_weights, v);
            if (extra > 0) {
                for (int d = 0; d < 3; ++d) entry(r + d, r + d, extra);
                b.segment<3>(r) += extra * targets_.row(v).transpose();
            }
        }
        add_fairness_terms(part, entry, b, first, last);
        // Corrected faces: their alignment blocks with u' instead of u (eq. 5–10).
        std::vector<std::int32_t> faces;
        for (std::size_t k = first; k < last; ++k)
            rows_.corners().for_each_face(part[k], [&](std::int32_t f) {
                if (corrected_[std::size_t(f)]) faces.push_back(f);
            });
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        for (const std::int32_t f : faces) {
            const Eigen::Vector3d u = field_.row(f).transpose(), u0 = input_field_.row(f).transpose();
            const double weight = weights_.beta * element_or_one(weights_.face_beta, f) * element_or_one(weights_.face_weights, f);
            const Eigen::Matrix3d M = weight * (u * u.transpose() - u0 * u0.transpose());
            for (int e = 0; e < 4; ++e) {
                const std::int32_t a = surface_.quads(f, e), c = surface_.quads(f, (e + 1) % 4);
                add_block(part, a, a, M, entry, b, first, last);
                add_block(part, c, c, M, entry, b, first, last);
                add_block(part, a, c, -M, entry, b, first, last);
                add_block(part, c, a, -M, entry, b, first, last);
            }
        }
    }

    /// The part's system assembled: R_PP + the repair's terms, and b. The rows are summed from
    /// their entries a few thousand vertices at a time and appended to a row-major matrix, then
    /// copied to column-major: the same matrix as one setFromTriplets of all the entries (each
    /// place sums its entries in the same order), without holding them all (16 bytes an entry:
    /// 42 MB for a 22K-vertex part of lobster.vol, the peak of its validity stage).
    void part_system(const std::vector<std::int32_t>& part, SparseMatrix& matrix, Eigen::VectorXd& b) const {
        constexpr std::size_t kChunkVertices = 4096;
        const Eigen::Index n = 3 * Eigen::Index(part.size());
        std::vector<Eigen::Triplet<double>> entries;
        const auto collect = [&](std::size_t first, std::size_t last) {  // the entries of [first, last), rows from 0
            const Eigen::Index offset = 3 * Eigen::Index(first);
            entries.clear();
            visit_part_system(
                part, [&](Eigen::Index r, Eigen::Index c, double value) { entries.emplace_back(r - offset, c, value); }, b, first, last);
        };
        if (part.size() <= kChunkVertices) {  // one chunk: straight to column-major
            collect(0, part.size());
            matrix.resize(n, n);
            matrix.setFromTriplets(entries.begin(), entries.end());
            return;
        }
        Eigen::SparseMatrix<double, Eigen::RowMajor> rows(n, n), chunk;
        for (std::size_t first = 0; first < part.size(); first += kChunkVertices) {
            const std::size_t last = std::min(part.size(), first + kChunkVertices);
            const Eigen::Index offset = 3 * Eigen::Index(first);
            collect(first, last);
            chunk.resize(3 * Eigen::Index(last - first), n);
            chunk.setFromTriplets(entries.begin(), entries.end());
            rows.reserve(std::max(chunk.nonZeros(), rows.nonZeros()));  // room for this many more (doubling)
            for (Eigen::Index r = 0; r < chunk.outerSize(); ++r) {
                rows.startVec(offset + r);
                for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(chunk, r); it; ++it)
                    rows.insertBack(offset + r, it.col()) = it.value();
            }
        }
        rows.finalize();
        matrix = rows;
    }

    void gather(const std::vector<std::int32_t>& part, Eigen::VectorXd& x) const {
        x.resize(3 * Eigen::Index(part.size()));
        for (std::size_t k = 0; k < part.size(); ++k) x.segment<3>(3 * Eigen::Index(k)) = x_.segment<3>(3 * Eigen::Index(part[k]));
    }

    void bounds_of(const std::vector<std::int32_t>& part, Eigen::VectorXd& lower, Eigen::VectorXd& upper) const {
        lower.resize(3 * Eigen::Index(part.size()));
        upper.resize(lower.size());
        for (std::size_t k = 0; k < part.size(); ++k) {
            lower.segment<3>(3 * Eigen::Index(k)) = lower_.segment<3>(3 * Eigen::Index(part[k]));
            upper.segment<3>(3 * Eigen::Index(k)) = upper_.segment<3>(3 * Eigen::Index(part[k]));
        }
    }

    /// |x_v,d − p_v,d| ≤ half_width · s_d on every axis d (the reversible mode's box).
    void bound_box(std::int32_t v, double half_width) {
        for (int d = 0; d < 3; ++d)
            for (const int side : {-1, 1}) bound_side(v, d, side, half_width);
    }

    /// |x_v,a − p_v,a| ≤ voxel_half_width·s_a on the axis a of each face of v (one slab per
    /// axis: the two planes of voxel centres on either side of the pointel). Returns whether a
    /// bound was added.
    bool bound_faces_of(std::int32_t v) {
        bool added = false;
        rows_.corners().for_each_face(v, [&](std::int32_t f) {
            for (const int side : {-1, 1})
                added = bound_side(v, surface_.surfels[std::size_t(f)].axis, side, o_.voxel_half_width) || added;
        });
        return added;
    }

    /// x_v,d ≥ p_v,d − half_width·s_d (side −1) or x_v,d ≤ p_v,d + half_width·s_d (side +1);
    /// returns whether the bound is new.
    bool bound_side(std::int32_t v, int d, int side, double half_width) {
        if (lower_.size() == 0) {  // the first bound: every other coordinate free
            lower_ = Eigen::VectorXd::Constant(3 * surface_.vertex_count(), -std::numeric_limits<double>::infinity());
            upper_ = Eigen::VectorXd::Constant(lower_.size(), std::numeric_limits<double>::infinity());
        }
        const Eigen::Index q = 3 * Eigen::Index(v) + d;
        const double limit = surface_.vertices(v, d) + side * half_width * surface_.grid.spacing[d];
        double& bound = side < 0 ? lower_[q] : upper_[q];
        if (bound == limit) return false;
        bound = limit;
        bounded_[std::size_t(v)] = 1;
        changed_[std::size_t(v)] = 1;
        any_bounds_ = true;
        return true;
    }

    /// min E' over the part from the current positions, the rest held (sparse Cholesky or
    /// multigrid CG; the box QP with the clamp boxes).
    /// `moved` receives the part's vertices that moved; returns whether the box QP converged.
    bool solve_part(const std::vector<std::int32_t>& part, double tolerance, std::vector<std::int32_t>& moved) {
        for (std::size_t k = 0; k < part.size(); ++k) local_[std::size_t(part[k])] = std::int32_t(k);
        SparseMatrix matrix;
        Eigen::VectorXd b, x;
        part_system(part, matrix, b);
        gather(part, x);
        bool converged = true;
        if (any_bounds_ && std::any_of(part.begin(), part.end(), [&](std::int32_t v) { return bounded_[std::size_t(v)] != 0; })) {
            // From the current positions: inside the boxes and close to the minimizer (only the
            // strengthened rows changed), so the active set iterations need no ADMM phase to find
            // the active set (lobster: 4-5 factorizations instead of 50 ADMM iterations and 7).
            // A vertex bounded this round may be outside its bounds: it starts on them.
            Eigen::VectorXd lower, upper;
            bounds_of(part, lower, upper);
            x = x.cwiseMax(lower).cwiseMin(upper);
            BoxQpOptions qp = o_.qp;
            qp.admm_max_iterations = 0;
            if (o_.clamp_half_width) {
                converged = solve_box_qp(matrix, b, lower, upper, x, qp).converged;
            } else if (is_small(part)) {
                SimplicialHeldSolver held(matrix);
                converged = detail::solve_box_qp_with(held, b, lower, upper, x, qp).converged;
            } else if (tolerance > kExactPartTolerance) {
                qp.tolerance = std::max(qp.tolerance, tolerance);
                BlockJacobiHeldSolver held(matrix, kBlockJacobiIterations);
                converged = detail::solve_box_qp_with(held, b, lower, upper, x, qp).converged;
            } else {
                // The voxels' bounds hold a few coordinates of a large part: the active set
                // iterations by multigrid CG on the free coordinates, no factor (a CHOLMOD
                // factorization per iteration took seconds on Al.100.vol's 20K-vertex parts).
                qp.tolerance = std::max(qp.tolerance, tolerance);
                const detail::AssembledSystem system(matrix);
                const std::unique_ptr<detail::Multigrid> amg = system.multigrid(detail::AmgSettings{});
                detail::IterativeHeldSolver held(system, *amg, kIterativePartIterations);
                converged = detail::solve_box_qp_with(held, b, lower, upper, x, qp).converged;
            }
        } else if (is_small(part)) {
            const PartCholesky llt(matrix);
            if (llt.info() != Eigen::Success) throw Error("validity repair: a local system is not positive definite");
            x = llt.solve(b);
        } else {
            solve_large_part(matrix, b, x, tolerance);
        }
        for (std::size_t k = 0; k < part.size(); ++k) {
            auto position = x_.segment<3>(3 * Eigen::Index(part[k]));
            if (position != x.segment<3>(3 * Eigen::Index(k))) moved.push_back(part[k]);
            position = x.segment<3>(3 * Eigen::Index(k));
            local_[std::size_t(part[k])] = -1;
        }
        return converged;
    }

    /// A large part from the current positions, which are close to its solution (only the
    /// strengthened rows changed). In the rounds, which only steer the repair, CG with the 3×3
    /// diagonal blocks: the strengthened data term makes the part far better conditioned than R,
    /// so it converges in tens of iterations with no set-up (lobster's 22K-vertex parts: 3x faster
    /// than multigrid CG, whose hierarchy is built anew for every part). In the exact solves,
    /// multigrid CG, whose error at a given residual is far smaller (block-Jacobi CG stopped at
    /// the same residual leaves errors of 1e-9, which change with the number of threads). Whatever
    /// fails hands over to the next: multigrid CG from where CG stopped, then CHOLMOD.
    static void solve_large_part(const SparseMatrix& matrix, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance) {
        const Eigen::VectorXd start = x;
        SolverOptions solver;
        solver.tolerance = tolerance;
        const bool exact = tolerance <= kExactPartTolerance;
        for (const SolverKind kind : {SolverKind::ConjugateGradient, SolverKind::Amg}) {
            if (exact && kind == SolverKind::ConjugateGradient) continue;
            solver.kind = kind;
            solver.max_iterations = kind == SolverKind::Amg ? 500 : kBlockJacobiIterations;
            try {
                solve_spd(matrix, b, x, solver);
                return;
            } catch (const Error&) {
                if (!x.allFinite()) x = start;  // a breakdown: start again from the positions
            }
        }
        x = start;
        solver.kind = SolverKind::Cholmod;
        solve_spd(matrix, b, x, solver);
    }

    const DigitalSurface& surface_;
    const RegularizationWeights& weights_;
    ValidityRepairOptions o_;
    const VertexLinks& links_;  ///< of the fairness term (E)
    VertexLinks neighbours_;  ///< across every edge: the rings of the region and of the grading
    const PointMatrix& input_field_;  ///< u as given (repair_validity's argument)
    PointMatrix field_;
    PointMatrix targets_;
    Eigen::VectorXd x_;
    std::vector<double> factor_;  ///< m_i
    std::vector<double> fair_factor_;         ///< n_i, the fairness factors (fairness_steps)
    std::vector<int> fair_steps_;             ///< times n_i was raised
    std::vector<std::int32_t> fair_vertices_;  ///< the i with n_i > 1, in the order they were raised
    /// Per vertex v, the positions in fair_vertices_ of the terms whose rows v is in (the raised
    /// vertex itself and its link): entries [offsets[v], offsets[v + 1]) (index_fair_terms);
    /// empty until the first vertex is raised.
    std::vector<std::int64_t> fair_term_offsets_;
    std::vector<std::int32_t> fair_term_entries_;
    std::size_t fair_terms_indexed_ = 0;  ///< fair_vertices_ indexed so far
    std::vector<char> held_;
    std::vector<char> junction_turn_;  ///< junction_turn_vertices, or empty (binary, grade_junction_turns)
    std::vector<char> in_region_;
    std::vector<char> corrected_;      ///< faces whose u was replaced
    /// Bounds of each coordinate, interleaved (3i + d), ±∞ where free: the clamp boxes of the
    /// reversible mode, the voxels' bounds (bound_around); empty until the first bound.
    Eigen::VectorXd lower_, upper_;
    std::vector<char> bounded_;  ///< per vertex: some coordinate has a finite bound
    bool any_bounds_ = false;
    std::unordered_map<std::int64_t, int> voxel_tries_;  ///< times each voxel was found wrong
    /// Vertices that moved, changed weight or hold, joined the region or touch a face whose field
    /// changed since the last exact solve of the region.
    std::vector<char> changed_;
    std::vector<std::int32_t> local_;  ///< index in the part being solved, −1 elsewhere
    std::vector<char> mark_;           ///< scratch, all 0 between calls
    detail::RegularizationOperator rows_;  ///< R of E, block row by block row
    Eigen::VectorXd target_rhs_;  ///< the fairness targets' part of b (fairness_target_terms), empty without them
    mutable std::vector<detail::RegularizationOperator::Row> row_scratch_;  ///< one per thread
    std::vector<std::int32_t>* moved_ = nullptr;
};

}  // namespace

PointMatrix repair_targets(const DigitalSurface& surface, double split_offset) {
    const std::int64_t n = surface.vertex_count();
    // Vertices sorted by pointel: runs of more than one are the copies of a split pointel.
    const auto pointel = [&](std::int64_t i) {
        return std::array<std::int32_t, 3>{surface.vertex_pointels(i, 0), surface.vertex_pointels(i, 1),
                                           surface.vertex_pointels(i, 2)};
    };
    std::vector<std::int64_t> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) { return pointel(a) < pointel(b); });
    std::vector<char> split(std::size_t(n), 0);
    for (std::size_t k = 0; k + 1 < order.size(); ++k)
        if (pointel(order[k]) == pointel(order[k + 1])) split[std::size_t(order[k])] = split[std::size_t(order[k + 1])] = 1;

    // Each copy moves towards the mean of the centroids of its faces, measured in voxels.
    PointMatrix towards = PointMatrix::Zero(n, 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
        for (int k = 0; k < 4; ++k) centroid += surface.vertices.row(surface.quads(f, k));
        centroid /= 4.0;
        for (int k = 0; k < 4; ++k) {
            const std::int32_t v = surface.quads(f, k);
            if (split[std::size_t(v)]) towards.row(v) += centroid - surface.vertices.row(v);
        }
    }
    const Eigen::Array3d spacing = surface.grid.spacing.array();
    PointMatrix targets = surface.vertices;
    for (std::int64_t i = 0; i < n; ++i) {
        if (!split[std::size_t(i)]) continue;
        const Eigen::Array3d in_voxels = towards.row(i).transpose().array() / spacing;
        const double length = in_voxels.matrix().norm();
        if (length > 0) targets.row(i) += (split_offset / length * in_voxels * spacing).matrix().transpose();
    }
    return targets;
}

ValidityRepairResult repair_validity(const DigitalSurface& surface, const PointMatrix& normals,
                                     const RegularizationWeights& weights, const PointMatrix& positions,
                                     const ValidityRepairOptions& options, const ProgressCallback& progress) {
    check_inputs(surface, normals, positions, options);
    ValidityRepairResult result;
    ValidityRepairReport& report = result.report;
    validity_internal::IncrementalValidity tracker(positions, surface.quads, normals);
    report.before = report.after = tracker.validity();
    // A label complex (a binary surface, labels {0, 1}, has no junction): its edges give both
    // the fairness links and the junction turns.
    const bool complex = may_have_junctions(surface);
    const ComplexEdges edges = complex ? complex_edges(surface) : ComplexEdges{};
    const VertexLinks links = complex ? fairness_links(surface, edges) : fairness_links(surface);
    report.energy_before = regularization_energy(positions, surface.vertices, surface.quads, links, normals, weights);
    report.energy_after = report.energy_before;
    report.check_seconds = report.before.seconds;
    // Voxel centres on the wrong side (options.voxels; the reversible mode keeps them all), and
    // of those the ones to put back: not those left as noise (decided once per voxel).
    std::optional<VoxelSides> sides;
    std::vector<std::int64_t> wrong, to_fix;
    std::unordered_map<std::int64_t, bool> noisy;
    double voxel_seconds = 0;
    const auto update_voxels = [&](const PointMatrix& at, const std::vector<std::int32_t>& moved) {
        const auto started = Clock::now();
        sides->update(at, moved);
        wrong = sides->wrong();
        to_fix.clear();
        for (const std::int64_t v : wrong) {
            const auto [it, added] = noisy.try_emplace(v, false);
            if (added) it->second = left_as_noise(*sides, v, options);
            if (!it->second) to_fix.push_back(v);
        }
        voxel_seconds += seconds_since(started);
    };
    if (options.voxels && !options.clamp_half_width) {
        const auto started = Clock::now();
        sides.emplace(*options.voxels, surface, positions, tracker.corners());
        voxel_seconds += seconds_since(started);
        update_voxels(positions, {});
        report.wrong_voxels_before = std::int64_t(wrong.size());
        report.outside_object_voxels_before = std::count_if(
            wrong.begin(), wrong.end(), [&](std::int64_t v) { return options.voxels->mask[std::size_t(v)] != 0; });
        report.voxels_put_back =
            !to_fix.empty() && (options.put_back_from_share <= 0 ||
                                double(report.outside_object_voxels_before) >=
                                    options.put_back_from_share * double(sides->object_voxels()));
    }
    const auto record_voxels = [&] {
        if (!sides) return;
        report.wrong_voxels_after = std::int64_t(wrong.size());
        report.noisy_wrong_voxels = std::int64_t(wrong.size() - to_fix.size());
    };
    const auto done = [&] { return report.after.valid() && (!report.voxels_put_back || to_fix.empty()); };
    if (done() || options.max_rounds == 0) {
        record_voxels();
        report.check_seconds += voxel_seconds;
        result.positions = positions;
        result.normals = normals;
        result.alpha_factors = Eigen::VectorXd::Ones(surface.vertex_count());
        result.fairness_factors = Eigen::VectorXd::Ones(surface.vertex_count());
        return result;
    }

    // Rounds on windows around what is invalid, then one exact solve of the whole region; again
    // if that solve undid the repair somewhere.
    Repair repair(surface, links,
                  complex && !options.grade_junction_turns ? junction_turn_vertices(surface, edges) : std::vector<char>(),
                  normals, weights, positions, options);
    MeshValidity& validity = report.after;
    std::vector<std::int32_t> moved_since_voxels;  // voxel sides only counted: updated once, at the end
    const auto update = [&](const std::vector<std::int32_t>& moved, const std::vector<std::int32_t>& refield) {
        const PointMatrix at = repair.positions();
        tracker.update(at, moved, refield, repair.field());
        validity = tracker.validity();
        if (report.voxels_put_back) update_voxels(at, moved);
        else if (sides) moved_since_voxels.insert(moved_since_voxels.end(), moved.begin(), moved.end());
    };
    Eigen::VectorXd last_valid;
    for (int exact_solves = 0; exact_solves < 3 && !done() && report.rounds < options.max_rounds; ++exact_solves) {
        while (!done() && report.rounds < options.max_rounds) {
            report_progress(progress, "repair", -1,
                            "round " + std::to_string(report.rounds + 1) + ": " +
                                std::to_string(validity.intersecting_pairs) + " intersecting pairs, " +
                                std::to_string(validity.folded_faces) + " folded faces" +
                                (report.voxels_put_back ? ", " + std::to_string(to_fix.size()) + " voxel centres on the wrong side" : ""));
            std::vector<std::int32_t> moved, refield;
            const std::vector<std::int32_t> bounded =
                report.voxels_put_back ? repair.bound_around(*sides, to_fix) : std::vector<std::int32_t>();
            repair.round(validity, bounded, report, moved, refield);
            ++report.rounds;
            update(moved, refield);
        }
        if (!validity.valid()) break;
        last_valid = repair.state();
        std::vector<std::int32_t> moved;
        repair.solve_region(report, moved);
        update(moved, {});
        report.exact = validity.valid();
    }
    if (!validity.valid() && last_valid.size() > 0) update(repair.restore(last_valid), {});  // valid, not exact
    report.max_kkt_residual = repair.region_residual();
    if (!moved_since_voxels.empty()) {
        std::sort(moved_since_voxels.begin(), moved_since_voxels.end());
        moved_since_voxels.erase(std::unique(moved_since_voxels.begin(), moved_since_voxels.end()), moved_since_voxels.end());
        update_voxels(repair.positions(), moved_since_voxels);
    }
    report.check_seconds = validity.seconds + voxel_seconds;
    record_voxels();
    report.bounded_vertices = repair.bounded_vertex_count();
    repair.finish(result);
    result.positions = repair.positions();
    result.normals = repair.field();
    report.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads, links, normals, weights);
    report.max_displacement_voxels =
        (result.positions - positions).rowwise().norm().maxCoeff() / surface.grid.spacing.minCoeff();
    return result;
}

}  // namespace dsreg
