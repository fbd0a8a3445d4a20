// dsreg pipeline — the block-wise streaming run (include/dsreg/block_pipeline.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/error.hpp"
#include "dsreg/text.hpp"

namespace dsreg {

namespace {

/// The row of vertex `vertex_key`'s key surfel (the face its key names) in ascending `face_keys`,
/// or −1 if that face is not there.
std::int64_t key_face_row(const std::vector<std::int64_t>& face_keys, std::int64_t vertex_key) {
    const std::int64_t key = vertex_key / 4;
    const auto face = std::lower_bound(face_keys.begin(), face_keys.end(), key);
    return face != face_keys.end() && *face == key ? std::int64_t(face - face_keys.begin()) : -1;
}

/// The latest positions of the vertices solved so far, by owning block.
class VertexStore {
public:
    explicit VertexStore(const BlockLayout& layout)
        : layout_(layout), keys_(std::size_t(layout.block_count())), positions_(std::size_t(layout.block_count())) {}

    std::int64_t owner(std::int64_t key) const { return layout_.block_of(key_voxel_of_vertex(layout_.dims, key)); }

    /// The owned vertices of `block` at positions x (3 entries per patch vertex).
    void keep(std::int64_t block, const SurfacePatch& patch, const Eigen::VectorXd& x) {
        auto& keys = keys_[std::size_t(block)];
        auto& positions = positions_[std::size_t(block)];
        keys.clear();
        for (std::int64_t i = 0; i < patch.vertex_count(); ++i)
            if (patch.vertex_owned[std::size_t(i)]) keys.push_back(patch.vertex_keys[std::size_t(i)]);
        positions.resize(std::int64_t(keys.size()), 3);
        std::int64_t row = 0;
        for (std::int64_t i = 0; i < patch.vertex_count(); ++i)
            if (patch.vertex_owned[std::size_t(i)]) positions.row(row++) = x.segment<3>(3 * i).transpose();
    }

    /// The stored position of vertex `key`, if its block has been solved.
    const double* find(std::int64_t key) const {
        const std::size_t block = std::size_t(owner(key));
        const auto& keys = keys_[block];
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        if (it == keys.end() || *it != key) return nullptr;
        return positions_[block].row(it - keys.begin()).data();
    }

    const PointMatrix& positions(std::int64_t block) const { return positions_[std::size_t(block)]; }

    /// x̃ += P e at every stored vertex; the direction of a vertex (coarse space along the normals)
    /// is the field on its key surfel, a face of the same block's piece.
    void add_coarse_correction(const CoarseLattice& lattice, const CoarseSolution& solution,
                               const std::vector<BlockPiece>& pieces) {
        for (std::size_t block = 0; block < keys_.size(); ++block) {
            const BlockPiece& piece = pieces[block];
            for (std::size_t i = 0; i < keys_[block].size(); ++i) {
                Eigen::Vector3d direction = Eigen::Vector3d::Zero();
                if (solution.unknowns_per_node == 1)  // the key surfel of an owned vertex is an owned face
                    direction = piece.face_normals.row(key_face_row(piece.face_keys, keys_[block][i])).transpose();
                positions_[block].row(std::int64_t(i)) += solution.displacement(lattice, keys_[block][i], direction).transpose();
            }
        }
    }

private:
    const BlockLayout& layout_;
    std::vector<std::vector<std::int64_t>> keys_;
    std::vector<PointMatrix> positions_;
};

/// x: 3 entries per patch vertex, from the store where solved, else the digital position p.
Eigen::VectorXd current_positions(const SurfacePatch& patch, const VertexStore& store) {
    Eigen::VectorXd x(3 * patch.vertex_count());
    for (std::int64_t i = 0; i < patch.vertex_count(); ++i) {
        const double* stored = store.find(patch.vertex_keys[std::size_t(i)]);
        for (int d = 0; d < 3; ++d) x[3 * i + d] = stored ? stored[d] : patch.surface.vertices(i, d);
    }
    return x;
}

/// The residual rows R x̃ − b of the owned vertices of a block (3 entries per patch vertex, zero
/// elsewhere) at the welded positions x̃ (every vertex of the patch solved).
Eigen::VectorXd owned_residual(const BlockStages& b, const Eigen::VectorXd& x) {
    const SurfacePatch& patch = b.patch;
    Eigen::VectorXd r = Eigen::VectorXd::Zero(3 * patch.vertex_count());
    for (std::int64_t j = 0; j < patch.vertex_count(); ++j) {
        if (!patch.vertex_owned[std::size_t(j)]) continue;
        for (int d = 0; d < 3; ++d) {
            const Eigen::Index c = Eigen::Index(3 * j + d);
            double sum = -b.system.rhs[c];
            for (Eigen::SparseMatrix<double>::InnerIterator it(b.system.matrix, c); it; ++it) sum += it.value() * x[it.row()];
            r[c] = sum;  // column c = row c (R is symmetric)
        }
    }
    return r;
}

/// What the bound pass accumulates over the blocks.
struct BoundTally {
    double energy_norm_squared = 0;  ///< Σ_b rᵀ M_b⁻¹ r ≥ ‖x̃ − x*‖²_R
    double residual_squared = 0, rhs_squared = 0;
    double smallest_eigenvalue = std::numeric_limits<double>::infinity();  ///< α·min α_i w0_i

    void add(const BlockStages& b, const Eigen::VectorXd& x, const SolverOptions& solver) {
        const Eigen::VectorXd r = owned_residual(b, x);
        energy_norm_squared += owned_energy_norm_bound(b, r, solver);
        residual_squared += r.squaredNorm();
        for (std::int64_t j = 0; j < b.patch.vertex_count(); ++j)
            if (b.patch.vertex_owned[std::size_t(j)]) rhs_squared += b.system.rhs.segment<3>(3 * j).squaredNorm();
        smallest_eigenvalue = std::min(smallest_eigenvalue, smallest_eigenvalue_bound(b.weights, b.patch.vertex_owned));
    }
    /// ‖x̃ − x*‖₂ ≤ ‖x̃ − x*‖_R / sqrt(λ_min(R)), λ_min(R) ≥ α min α_i w0_i (solvers.hpp).
    double error_bound() const { return std::sqrt(energy_norm_squared / smallest_eigenvalue); }
};

bool has_owned_faces(const SurfacePatch& patch) {
    return std::find(patch.face_owned.begin(), patch.face_owned.end(), 1) != patch.face_owned.end();
}

/// Stage timings summed over the blocks.
struct BlockTimes {
    double read = 0, surface = 0, normals = 0, regularize = 0;
    void add(const BlockStages& b) {
        read += b.read_seconds;
        surface += b.surface_seconds;
        normals += b.normals_seconds;
        regularize += b.assembly_seconds;
    }
};

void finish_stage(const ProgressCallback& progress, const std::string& stage, double seconds, const std::string& detail) {
    if (progress) progress(ProgressEvent{stage, 1, detail, true, seconds});
}

}  // namespace

std::int64_t default_block_halo(const PipelineOptions& o) {
    // A vertex held at the wrong place (or a free boundary) moves the solution around it by an
    // amount that decays like exp(−d/ℓ) along the surface, ℓ ≈ sqrt(β/α) edges: the alignment
    // term spreads a displacement along the normals, the data term pulls it back (measured,
    // docs/scaling.md). Two decay lengths leave a few hundredths of a voxel on goursat.
    return std::int64_t(std::ceil(2.0 * std::sqrt(o.beta / o.alpha))) + kPatchFaceMargin;
}

namespace {

/// What the passes over the blocks build up.
struct StreamingState {
    explicit StreamingState(const BlockLayout& layout) : store(layout), pieces(std::size_t(layout.block_count())) {}
    VertexStore store;
    std::vector<BlockPiece> pieces;  ///< owned faces of each block (positions filled at the end)
    BlockTimes times;
    WeldedRun run;
    std::set<std::string> solvers;
    std::int64_t blocks_with_surface = 0, largest_read = 0, largest_patch = 0;
    int iterations = 0;
    nlohmann::json passes = nlohmann::json::array();
};

/// Progress through `passes` passes over the blocks: pass `pass`, `done` of its `count` blocks.
void report_pass(const ProgressCallback& progress, const std::string& name, int pass, int passes, std::int64_t done,
                 std::int64_t count) {
    report_progress(progress, "blocks", (pass + double(done) / double(count)) / passes,
                    name + ", block " + std::to_string(done) + "/" + std::to_string(count));
}

/// One pass over the blocks, the `pass`-th: the first (free boundaries, sweep 0) or a Schwarz sweep.
void solve_pass(const VolumeSource& source, const BlockPlan& plan, const BlockLayout& layout, std::int64_t halo, int sweep,
                int pass, int passes, const SolverOptions& solver, StreamingState& state, const ProgressCallback& progress) {
    double solve_seconds = 0;
    int iterations = 0;
    const std::string name = sweep == 0 ? "first pass" : "Schwarz sweep " + std::to_string(sweep);
    for (std::int64_t block = 0; block < layout.block_count(); ++block) {
        const VoxelBox owned = layout.box(block);
        const BlockStages b = run_block_stages(source, plan, owned, owned.grown(halo).clipped(layout.dims));
        state.times.add(b);
        report_pass(progress, name, pass, passes, block + 1, layout.block_count());
        if (sweep == 0) state.run.object_voxels += b.owned_object_voxels;
        if (!has_owned_faces(b.patch)) continue;
        Eigen::VectorXd x = current_positions(b.patch, state.store);
        const auto started = std::chrono::steady_clock::now();
        const SolveReport solve = sweep == 0 ? solve_patch_free(b, x, solver) : solve_patch_rows(b, x, solver);
        solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        iterations += solve.iterations;
        state.solvers.insert(solve.solver);
        state.store.keep(block, b.patch, x);
        if (sweep > 0) continue;
        state.pieces[std::size_t(block)] = patch_piece(b.patch, b.patch.surface.vertices, b.field.normals);
        ++state.blocks_with_surface;
        state.largest_read = std::max(state.largest_read, b.read.voxel_count());
        state.largest_patch = std::max(state.largest_patch, b.patch.face_count());
        if (state.run.field.description.empty()) {
            state.run.field = b.field;
            state.run.field.normals = PointMatrix();
        }
    }
    state.run.solve_seconds += solve_seconds;
    state.iterations += iterations;
    state.passes.push_back({{"kind", sweep == 0 ? "free boundaries" : "Schwarz sweep"},
                            {"solve_seconds", solve_seconds},
                            {"iterations", iterations}});
}

/// The field u on the key surfel of each patch vertex (its owner's face; zero where that face is
/// not in the patch): the direction of the coarse space along the normals. The same in every
/// block for the row vertices (the field is exact on their faces); throws unless every vertex of
/// an owned row of R is one.
PointMatrix key_face_normals(const BlockStages& b) {
    const SurfacePatch& patch = b.patch;
    PointMatrix directions = PointMatrix::Zero(patch.vertex_count(), 3);
    for (std::int64_t i = 0; i < patch.vertex_count(); ++i) {
        const std::int64_t face = key_face_row(patch.face_keys, patch.vertex_keys[std::size_t(i)]);
        if (face >= 0) directions.row(i) = b.field.normals.row(face);
    }
    for (std::int64_t j = 0; j < patch.vertex_count(); ++j) {
        if (!patch.vertex_owned[std::size_t(j)]) continue;
        for (Eigen::SparseMatrix<double>::InnerIterator it(b.system.matrix, Eigen::Index(3 * j)); it; ++it)
            if (!patch.vertex_row[std::size_t(it.row() / 3)])
                throw Error("coarse correction: a vertex of an owned row has no exact row (internal error)");
    }
    return directions;
}

/// Voxels around a block's owned box whose vertices get exact rows in the coarse pass: the
/// vertices of the owned rows lie within two edges of an owned vertex, their key voxels within 4.
constexpr std::int64_t kCoarseRowsMargin = 4;

/// The two-level step, the `pass`-th pass: the coarse system summed over the blocks, each grown
/// by kCoarseRowsMargin alone (its owned rows of R are exact, as in the bound pass), solved once,
/// and x̃ += P e at every stored vertex. Returns what the report keeps of it.
nlohmann::json coarse_pass(const VolumeSource& source, const BlockPlan& plan, const BlockLayout& layout,
                           const CoarseLattice& lattice, bool along_normals, int pass, int passes, StreamingState& state,
                           const ProgressCallback& progress) {
    const auto started = std::chrono::steady_clock::now();
    CoarseSystem system;
    for (std::int64_t block = 0; block < layout.block_count(); ++block) {
        const VoxelBox owned = layout.box(block);
        const BlockStages b = run_block_stages(source, plan, owned, owned.grown(kCoarseRowsMargin).clipped(layout.dims));
        state.times.add(b);
        report_pass(progress, "coarse correction", pass, passes, block + 1, layout.block_count());
        if (!has_owned_faces(b.patch)) continue;
        const Eigen::VectorXd x = current_positions(b.patch, state.store);
        const PointMatrix directions = along_normals ? key_face_normals(b) : PointMatrix();
        system.add(coarse_share(b, lattice, x, owned_residual(b, x), directions));
    }
    const auto solve_started = std::chrono::steady_clock::now();
    const CoarseSolution solution = system.solve();
    state.store.add_coarse_correction(lattice, solution, state.pieces);
    state.run.solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - solve_started).count();
    return {{"nodes", std::int64_t(solution.nodes.size())},
            {"dropped_nodes", solution.dropped_nodes},
            {"energy_before", solution.energy_before},
            {"energy_after", solution.energy_before - solution.energy_decrease},
            {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()}};
}

/// The bound pass: the residual rows at the welded vertices, block by block on blocks centred
/// on the seams, where the residual is (inside a block, x̃ solves the block's equations), so that
/// M_b keeps the couplings across each seam (no halo needed).
BoundTally bound_pass(const VolumeSource& source, const BlockPlan& plan, const BlockLayout& layout, int passes,
                      const SolverOptions& solver, StreamingState& state, const ProgressCallback& progress) {
    BoundTally tally;
    const BlockLayout staggered = staggered_blocks(layout);
    for (std::int64_t block = 0; block < staggered.block_count(); ++block) {
        const VoxelBox owned = staggered.box(block);
        const BlockStages b = run_block_stages(source, plan, owned, owned);
        state.times.add(b);
        report_pass(progress, "error bound", passes - 1, passes, block + 1, staggered.block_count());
        if (has_owned_faces(b.patch)) tally.add(b, current_positions(b.patch, state.store), solver);
    }
    return tally;
}

/// The report's blocks.coarse: the lattice and the space, the last coarse system's size, the time
/// of the coarse passes, the energy before the first correction and after the last, each correction.
nlohmann::json coarse_report(std::int64_t spacing, bool along_normals, const nlohmann::json& corrections) {
    nlohmann::json report = {
        {"spacing_voxels", spacing}, {"space", along_normals ? "normals" : "xyz"}, {"corrections", corrections}};
    if (corrections.empty()) return report;
    double seconds = 0;
    for (const auto& c : corrections) seconds += c["seconds"].get<double>();
    report["nodes"] = corrections.back()["nodes"];
    report["dropped_nodes"] = corrections.back()["dropped_nodes"];
    report["seconds"] = seconds;
    report["energy_before"] = corrections.front()["energy_before"];
    report["energy_after"] = corrections.back()["energy_after"];
    return report;
}

/// ", coarse correction along the normals every 8 voxels (2 × 5012 nodes, 1.3 s)" in the
/// regularize stage's detail, from coarse_report.
std::string coarse_detail(const nlohmann::json& report) {
    const auto& corrections = report["corrections"];
    if (corrections.empty()) return "";
    return ", coarse correction " + std::string(report["space"] == "normals" ? "along the normals" : "xyz") + " every " +
           std::to_string(report["spacing_voxels"].get<std::int64_t>()) + " voxels (" +
           std::to_string(corrections.size()) + " × " + std::to_string(report["nodes"].get<std::int64_t>()) + " nodes, " +
           format("%.1f", report["seconds"].get<double>()) + " s)";
}

}  // namespace

PipelineResult run_streaming_pipeline(const VolumeSource& source, const PipelineOptions& options,
                                      const ProgressCallback& progress) {
    const BlockOptions& bo = options.blocks;
    for (int a = 0; a < 3; ++a)
        if (bo.block_size[a] <= 0) throw Error("--block-size: every block size must be positive");
    if (bo.halo && *bo.halo < 0) throw Error("--block-halo must be zero or positive");
    if (bo.schwarz_sweeps < 0) throw Error("--schwarz-sweeps must be zero or positive");
    if (bo.coarse_spacing < 0) throw Error("--coarse-spacing must be zero (off) or positive");
    const BlockPlan plan = plan_block_run(source, options, "--block-size");
    const VoxelGrid& grid = plan.header.volume.grid;
    const BlockLayout layout = blocks_of_size(grid.dims, bo.block_size);
    const std::int64_t halo = bo.halo ? *bo.halo : default_block_halo(options);
    SolverOptions solver;
    solver.kind = options.solver;
    solver.max_error = options.max_error_voxels * grid.spacing.minCoeff();

    StreamingState state(layout);
    const CoarseLattice lattice{grid.dims, bo.coarse_spacing};
    const bool coarse = bo.coarse_spacing > 0;
    const int passes = (2 + bo.schwarz_sweeps) + (coarse ? 1 + bo.schwarz_sweeps : 0);  // first, sweeps, coarse, bound
    int pass = 0;
    nlohmann::json corrections = nlohmann::json::array();
    for (int sweep = 0; sweep <= bo.schwarz_sweeps; ++sweep) {
        solve_pass(source, plan, layout, halo, sweep, pass++, passes, solver, state, progress);
        if (state.blocks_with_surface == 0) throw empty_object_error(source, false);
        if (coarse)
            corrections.push_back(
                coarse_pass(source, plan, layout, lattice, bo.coarse_along_normals, pass++, passes, state, progress));
    }
    const auto bound_started = std::chrono::steady_clock::now();
    const BoundTally tally = bound_pass(source, plan, layout, passes, solver, state, progress);
    const double bound_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - bound_started).count();

    WeldedRun& run = state.run;
    run.solve.solver = "blocks";
    for (const std::string& name : state.solvers) run.solve.solver += (run.solve.solver == "blocks" ? "/" : "+") + name;
    run.solve.relative_residual = std::sqrt(tally.residual_squared / tally.rhs_squared);
    run.solve.error_bound = tally.error_bound();
    run.solve.iterations = state.iterations;
    run.assembly_seconds = state.times.regularize;
    const double voxel = grid.spacing.minCoeff();
    run.blocks = {{"block_size", bo.block_size},
                  {"halo_voxels", halo},
                  {"halo_default", !bo.halo.has_value()},
                  {"blocks", layout.block_count()},
                  {"blocks_with_surface", state.blocks_with_surface},
                  {"schwarz_sweeps", bo.schwarz_sweeps},
                  {"passes", state.passes},
                  {"coarse", coarse_report(bo.coarse_spacing, bo.coarse_along_normals, corrections)},
                  {"bound_seconds", bound_seconds},
                  {"largest_block_read_voxels", state.largest_read},
                  {"largest_block_patch_faces", state.largest_patch},
                  {"error_bound", run.solve.error_bound},
                  {"error_bound_voxels", run.solve.error_bound / voxel}};
    for (std::int64_t block = 0; block < layout.block_count(); ++block)
        state.pieces[std::size_t(block)].positions = state.store.positions(block);

    const auto started = std::chrono::steady_clock::now();
    run.welded = weld_pieces(state.pieces, grid);
    const double weld_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const BlockTimes& t = state.times;
    const std::string read = plan.header.shape ? "digitize" : "read";
    const std::string surfels = std::to_string(run.welded.surface.face_count()) + " surfels";
    run.stage_seconds = {{read, t.read}, {"surface", t.surface}, {"normals", t.normals},
                         {"regularize", t.regularize + run.solve_seconds}, {"weld", weld_seconds}};
    finish_stage(progress, read, t.read, std::to_string(run.object_voxels) + " object voxels");
    finish_stage(progress, "surface", t.surface, surfels + " in " + std::to_string(state.blocks_with_surface) + " blocks");
    finish_stage(progress, "normals", t.normals, run.field.description);
    finish_stage(progress, "regularize", t.regularize + run.solve_seconds,
                 run.solve.solver + ", halo " + std::to_string(halo) + " voxels, first pass + " +
                     std::to_string(bo.schwarz_sweeps) + " Schwarz sweeps" + coarse_detail(run.blocks["coarse"]) +
                     ", error bound " +
                     format("%.2e", run.solve.error_bound / voxel) + " voxel");
    finish_stage(progress, "weld", weld_seconds, surfels + ", " + std::to_string(run.welded.surface.component_count) + " components");
    PipelineResult result = welded_pipeline_result(std::move(run), plan);
    check_and_repair_welded(plan.options, result, progress);
    result.block_layout = layout;
    return result;
}

}  // namespace dsreg
