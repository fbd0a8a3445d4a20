// dsreg — the pipeline block by block (docs/scaling.md): what one block of the volume contributes
// (its patch of the digital surface, the normal field there, its exact rows of R, eq. 22–23), the
// block-wise streaming run of `dsreg regularize --block-size`, and the welded mesh as a
// PipelineResult, shared with the MPI driver (distributed.hpp).
//
// Streaming. The grid is cut into blocks of --block-size voxels, read one at a time. A first
// pass minimizes, for each block, the energy of eq. (1) restricted to the surface within its box
// grown by a halo of H voxels (a free boundary) and keeps the vertices the block owns. The error
// this leaves decays away from the halo's edge over about ℓ = sqrt(β/α) edges (the alignment
// term spreads a displacement along the normals, the data term pulls it back), so the halo is
// chosen from α and β (default_block_halo). --schwarz-sweeps then repeats the pass as an
// overlapping (multiplicative) Schwarz method on R x = b: each block solves for the vertices of
// its grown box with the others held at their current values, which converges to the
// whole-volume solution (by a factor of about exp(−H/ℓ) per sweep).
//
// The error bound. With r = R x̃ − b at the welded vertices x̃, ‖x̃ − x*‖²_R = rᵀR⁻¹r ≤ rᵀM⁻¹r for
// any M ≤ R; M = R without the terms of eq. (1) that straddle the cuts of a second, staggered set
// of blocks is block-diagonal, so rᵀM⁻¹r is a sum of one small solve per block. The staggered
// blocks are centred on the first ones' seams, where r lives (inside a block x̃ solves the
// block's equations). Then ‖x̃ − x*‖₂ ≤ ‖x̃ − x*‖_R / sqrt(α min w0) (solvers.hpp): a provable
// bound on the distance of every vertex to the whole-volume solution (a 2-norm over all of them,
// so pessimistic for the largest one, docs/scaling.md); it costs one more pass without halos.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/blocks.hpp"
#include "dsreg/pipeline.hpp"

namespace dsreg {

/// What every block of a run shares.
struct BlockPlan {
    LoadedVolume header;      ///< the volume without its voxels (probe_volume)
    PipelineOptions options;  ///< checked, with the normal field's radius filled in
    NormalFieldReach reach;
    Index3 read_margin{0, 0, 0};      ///< voxels read around a block's rows box, per axis
    std::int64_t surface_margin = 0;  ///< extra faces of the patch for fields that read the surface
};

/// Checks the options of a block-wise run, refusing those that need the whole surface at once
/// (--normals at, --normals-file, --clamp, local weight maps and files) and --max-memory (its
/// estimate is the whole-volume run's) with a dsreg::Error
/// naming the flag and `driver` (e.g. "--block-size" or "dsreg-mpi"), and the defaults measured on
/// the whole object (--ii-max-radius, --alpha-reach, --shrink-correction: refused when given);
/// probes the volume; fixes the radius of the normal field to the whole-volume one (the fixed-radius
/// field, not the adaptive default) and turns the thin-part weights and the shrink correction off.
/// So a block-wise run equals the whole-volume run of `options` of the plan, not of the defaults.
BlockPlan plan_block_run(const VolumeSource& source, const PipelineOptions& options, const std::string& driver);

/// What one block contributes. Its patch covers the vertices keyed in `rows` (⊇ owned).
struct BlockStages {
    VoxelBox owned, rows, read;        ///< boxes of the whole grid
    std::int64_t owned_object_voxels = 0;
    SurfacePatch patch;
    NormalField field;              ///< on the patch faces; exact on those around its row vertices
    RegularizationWeights weights;  ///< on the patch (metric filled in)
    RegularizationSystem system;    ///< R and b of the patch: rows of row vertices are the whole surface's
    double read_seconds = 0, surface_seconds = 0, normals_seconds = 0, assembly_seconds = 0;
};

/// Whether run_block_stages assembles R or leaves it to the caller (system.matrix empty; b and
/// the constant filled either way): dsreg-mpi writes the rows straight into PETSc's matrix.
enum class BlockAssembly { matrix_and_rhs, rhs_only };

/// Reads the block (block_read_box), extracts its patch, estimates the field and assembles R. A
/// block without faces gives an empty patch.
BlockStages run_block_stages(const VolumeSource& source, const BlockPlan& plan, const VoxelBox& owned, const VoxelBox& rows,
                             BlockAssembly assembly = BlockAssembly::matrix_and_rhs);

/// The voxels a block reads for the rows box `rows`: rows + the patch margin + the field's reach.
VoxelBox block_read_box(const BlockPlan& plan, const VoxelBox& rows);

/// The default halo (voxels) of the streaming mode: 2·sqrt(β/α) edges (the decay length of a
/// perturbation, twice), plus the patch margin; docs/scaling.md has the measurements.
std::int64_t default_block_halo(const PipelineOptions& options);

/// Solves for the row vertices of a patch with the others held: R_SS x_S = b_S − R_SO x_O, one
/// overlapping Schwarz step. `x` (3 entries per patch vertex, interleaved) holds on entry the
/// initial guess at the row vertices and the held values elsewhere, on exit the solution at the
/// row vertices. The solver's error bound uses α·min over the row vertices of α_i w0_i.
SolveReport solve_patch_rows(const BlockStages& block, Eigen::VectorXd& x, const SolverOptions& solver);

/// The first pass of the streaming mode: minimizes the energy of the patch faces whose voxel lies
/// in the rows box alone (a free boundary: as if the surface ended there) over their vertices,
/// from the guess in `x` (3 entries per patch vertex); writes their solution into `x`.
SolveReport solve_patch_free(const BlockStages& block, Eigen::VectorXd& x, const SolverOptions& solver);

/// The block's share of the streaming error bound: an upper bound on rᵀ M_b⁻¹ r, where r holds
/// the residual rows (R x̃ − b) of the block's owned vertices (3 entries per patch vertex, zero
/// elsewhere) and M_b is R restricted to the terms of eq. (1) that involve owned vertices only:
/// the data term of each owned vertex, the alignment of the faces whose corners are all owned,
/// the fairness of the owned vertices whose faces are all such faces. M = Σ_b M_b ≤ R (only
/// positive semi-definite terms are left out), so Σ_b rᵀ M_b⁻¹ r ≥ rᵀ R⁻¹ r = ‖x̃ − x*‖²_R.
double owned_energy_norm_bound(const BlockStages& block, const Eigen::VectorXd& residual, const SolverOptions& solver);

// Two-level correction (--coarse-spacing a). The error a block pass leaves is smooth (it varies
// over ℓ edges), which one-level Schwarz removes slowly. The coarse space: a lattice of nodes
// every a voxels over the grid's pointels; P_scalar interpolates trilinearly from the 8 nodes
// around a vertex's pointel (weights from the vertex's global key alone, so every block computes
// the same P). Vertex v moves along d_v, the field u on its key surfel (one unknown per node:
// P's row block of v is d_v ⊗ row v of P_scalar; the default), or in every direction (P =
// P_scalar ⊗ I3: --coarse-space xyz; it has the lower energy but slides vertices along the
// surface, where the energy is cheap: docs/scaling.md). The correction x̃ ← x̃ + P e with C e = g,
// C = Pᵀ R P, g = Pᵀ (b − R x̃), is the Galerkin (R-orthogonal) projection of the error x* − x̃
// onto range(P): it minimizes the energy ½ xᵀRx − bᵀx over x̃ + range(P), so the energy cannot go
// up (it falls by ½ gᵀe). C and g are sums over the blocks of the owned rows of R (exact in a
// block without halo), as for the bound.

/// The lattice of the coarse space over a grid of `dims` voxels.
struct CoarseLattice {
    Index3 dims{0, 0, 0};
    std::int64_t spacing = 0;  ///< voxels between nodes (> 0)

    /// The nodes with a non-zero trilinear weight at the vertex named `vertex_key` (1 to 8 of
    /// them; the weights sum to 1), named by their linear index on the lattice.
    struct Stencil {
        std::array<std::int64_t, 8> nodes{};
        std::array<double, 8> weights{};
        int count = 0;
    };
    Stencil stencil(std::int64_t vertex_key) const;
};

/// One block's share of the coarse system, on the nodes its patch's vertices touch.
struct CoarseShare {
    int unknowns_per_node = 3;             ///< 3 (P = P_scalar ⊗ I3) or 1 (along the vertices' directions)
    std::vector<std::int64_t> nodes;       ///< lattice nodes, ascending (local index = position)
    Eigen::SparseMatrix<double> galerkin;  ///< P_ownedᵀ R P, unknowns of a node interleaved
    Eigen::SparseMatrix<double> gram;      ///< P_owned,scalarᵀ P_owned,scalar (one entry per node pair)
    Eigen::VectorXd residual;              ///< P_ownedᵀ (b − R x̃)
    double energy = 0;                     ///< Σ over the owned vertices of ½ x̃ᵀ(R x̃) − bᵀx̃
};

/// The share of `block` (whose owned rows of R are exact) at positions x (3 entries per patch
/// vertex), given the residual rows r = R x − b of its owned vertices (zero elsewhere).
/// `directions`: empty for the coarse space of displacements in every direction (P = P_scalar ⊗
/// I3), or one unit row per patch vertex d_v for the space of displacements along them (P's row
/// block of v: d_v times the row v of P_scalar; one unknown per node).
CoarseShare coarse_share(const BlockStages& block, const CoarseLattice& lattice, const Eigen::VectorXd& x,
                         const Eigen::VectorXd& owned_residual, const PointMatrix& directions = PointMatrix());

/// The coarse correction e (3 entries per node) of the shares summed.
struct CoarseSolution {
    int unknowns_per_node = 3;
    std::vector<std::int64_t> nodes;  ///< every node touched, ascending
    Eigen::VectorXd correction;       ///< unknowns_per_node per node; 0 at the dropped nodes
    std::int64_t dropped_nodes = 0;   ///< nodes whose columns of P depend on the others' (see solve)
    double energy_before = 0;         ///< ½ x̃ᵀRx̃ − bᵀx̃
    double energy_decrease = 0;       ///< ½ gᵀe ≥ 0

    /// (P e) at the vertex named `vertex_key`, whose direction is `direction` (one unknown per node).
    Eigen::Vector3d displacement(const CoarseLattice& lattice, std::int64_t vertex_key,
                                 const Eigen::Vector3d& direction = Eigen::Vector3d::Zero()) const;
};

/// The coarse system summed over the blocks (global triplets, merged as they come: memory about
/// nodes × 27 × (9 + 1) entries).
class CoarseSystem {
public:
    void add(const CoarseShare& share);
    /// Solves C e = g by CHOLMOD on the nodes whose columns of P are independent: a node whose
    /// column of P_scalar lies (to rounding) in the span of the others' adds nothing to range(P)
    /// and would make C singular; such nodes are found from the pivots of an LDLᵀ of PᵀP and
    /// dropped. C = Pᵀ R P ⪰ λ_min(R) PᵀP ⊗ I3 is then positive definite.
    /// The entries are merged in place.
    CoarseSolution solve();

private:
    struct Entry {
        std::int64_t row, column;
        double value;
    };
    static void merge(std::vector<Entry>& entries);
    static void add_matrix(std::vector<Entry>& entries, const Eigen::SparseMatrix<double>& m, const std::vector<std::int64_t>& nodes,
                    int per_node);
    std::vector<Entry> galerkin_, gram_, residual_;
    std::size_t merged_size_ = 0;
    int unknowns_per_node_ = 3;
    double energy_ = 0;
};

/// The parts of a welded run that the blocks computed.
struct WeldedRun {
    WeldedSurface welded;
    NormalField field;  ///< description, radius, kernel (normals: taken from `welded`)
    std::int64_t object_voxels = 0;
    SolveReport solve;
    double assembly_seconds = 0, solve_seconds = 0;
    nlohmann::json blocks = nlohmann::json::object();  ///< the report's "blocks" object
    std::vector<std::pair<std::string, double>> stage_seconds;
};

/// The welded run as run_pipeline returns it: weights (the metric on the whole surface),
/// energies before and after, faces against the field, the report's extension fields.
PipelineResult welded_pipeline_result(WeldedRun run, const BlockPlan& plan);

/// Stage "validity" on a welded mesh, exactly as run_pipeline runs it after a whole-volume solve
/// (check, and repair unless options.validity is Check; nothing if Off: docs/validity.md), then
/// the faces against the field counted again; the stage is appended to result.stage_seconds.
/// Runs on one process: the welded mesh is whole there.
void check_and_repair_welded(const PipelineOptions& options, PipelineResult& result, const ProgressCallback& progress);

/// The block-wise streaming run (see above; stages reported to `progress`). Throws dsreg::Error.
PipelineResult run_streaming_pipeline(const VolumeSource& source, const PipelineOptions& options,
                                      const ProgressCallback& progress = {});

/// Writes one mesh per block of `layout` (its owned faces and their vertices, binary PLY with the
/// field u per face and each vertex's global key as the vertex property "key") into `folder`
/// (created if missing), and manifest.json listing the grid, each block's box, file and counts.
void write_block_fragments(const std::string& folder, const PipelineResult& result, const BlockLayout& layout);

}  // namespace dsreg
