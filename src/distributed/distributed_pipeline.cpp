// dsreg distributed — the pipeline over MPI (include/dsreg/distributed.hpp).
#include <petscsys.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <cstring>
#include <utility>

#include "distributed_stages.hpp"
#include "dsreg/distributed.hpp"
#include "dsreg/error.hpp"
#include "dsreg/text.hpp"
#include "mpi_exchange.hpp"

namespace dsreg {

DistributedSession::DistributedSession(int* argc, char*** argv) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
        MPI_Init(argc, argv);
        finalize_mpi_ = true;
    }
    PetscBool petsc = PETSC_FALSE;
    PetscInitialized(&petsc);
    if (!petsc) {
        PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr);  // dsreg reports its own errors
        if (PetscInitializeNoArguments() != 0) {
            std::fprintf(stderr, "dsreg-mpi: error: PETSc could not be initialized\n");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
        finalize_petsc_ = true;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

DistributedSession::~DistributedSession() {
    if (finalize_petsc_) PetscFinalize();
    if (finalize_mpi_) MPI_Finalize();
}

void run_collectively(MPI_Comm comm, const std::function<void()>& work) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    std::string message;
    bool failed = true;
    try {
        work();
        failed = false;
    } catch (const std::bad_alloc&) {
        message = "out of memory";
    } catch (const std::exception& e) {
        message = e.what();
    }
    const int mine = failed ? rank : size;
    int lowest = size;
    MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, comm);
    if (lowest == size) return;
    distributed::broadcast_string(comm, message, lowest);
    throw Error(message);
}

namespace {

/// What each rank reports of its share, gathered on rank 0.
struct RankFigures {
    std::int64_t owned_faces = 0, owned_vertices = 0, patch_faces = 0, patch_vertices = 0, read_voxels = 0;
    std::int64_t peak_memory = 0;
    double read = 0, surface = 0, normals = 0, assembly = 0, petsc_assembly = 0, solve = 0;
};

nlohmann::json figures_json(const RankFigures& f, int rank) {
    return {{"rank", rank},
            {"owned_surfels", f.owned_faces},
            {"owned_vertices", f.owned_vertices},
            {"patch_surfels", f.patch_faces},
            {"patch_vertices", f.patch_vertices},
            {"read_voxels", f.read_voxels},
            {"peak_memory_bytes", f.peak_memory},
            {"seconds", {{"read", f.read}, {"surface", f.surface}, {"normals", f.normals}, {"assembly", f.assembly},
                         {"petsc_assembly", f.petsc_assembly}, {"solve", f.solve}}}};
}

double max_over_ranks(MPI_Comm comm, double value) {
    double largest = value;
    MPI_Allreduce(&value, &largest, 1, MPI_DOUBLE, MPI_MAX, comm);
    return largest;
}

std::int64_t sum_over_ranks(MPI_Comm comm, std::int64_t value) {
    std::int64_t sum = 0;
    MPI_Allreduce(&value, &sum, 1, MPI_INT64_T, MPI_SUM, comm);
    return sum;
}

/// α·min α_i w0_i over the owned vertices of every rank.
double smallest_eigenvalue_bound(MPI_Comm comm, const BlockStages& block) {
    const double smallest = dsreg::smallest_eigenvalue_bound(block.weights, block.patch.vertex_owned);
    double global = smallest;
    MPI_Allreduce(&smallest, &global, 1, MPI_DOUBLE, MPI_MIN, comm);
    return global;
}

template <class T>
std::vector<T> matrix_values(const Eigen::Matrix<T, Eigen::Dynamic, 3, Eigen::RowMajor>& m) {
    return std::vector<T>(m.data(), m.data() + m.size());
}

/// `values` (3 per row) as a matrix, freed as they are copied.
PointMatrix point_matrix(std::vector<double>& values) {
    PointMatrix m = Eigen::Map<const PointMatrix>(values.data(), std::int64_t(values.size() / 3), 3);
    values = std::vector<double>();
    return m;
}

/// Every rank's piece, on rank 0 (empty elsewhere); `piece` is consumed field by field, the
/// gathered arrays moved into the pieces (rank 0 holds the whole surface once, not twice).
std::vector<BlockPiece> gather_pieces(MPI_Comm comm, BlockPiece piece) {
    auto face_keys = distributed::gather_arrays(comm, std::exchange(piece.face_keys, {}));
    auto corners = distributed::gather_arrays(comm, std::exchange(piece.face_corners, {}));
    auto neighbors = distributed::gather_arrays(comm, std::exchange(piece.face_neighbors, {}));
    auto normals = distributed::gather_arrays(comm, matrix_values(std::exchange(piece.face_normals, PointMatrix())));
    auto vertex_keys = distributed::gather_arrays(comm, std::exchange(piece.vertex_keys, {}));
    auto positions = distributed::gather_arrays(comm, matrix_values(std::exchange(piece.positions, PointMatrix())));
    std::vector<BlockPiece> pieces(face_keys.size());
    for (std::size_t r = 0; r < pieces.size(); ++r) {
        BlockPiece& p = pieces[r];
        p.face_keys = std::move(face_keys[r]);
        p.face_corners = std::move(corners[r]);
        p.face_neighbors = std::move(neighbors[r]);
        p.face_normals = point_matrix(normals[r]);
        p.vertex_keys = std::move(vertex_keys[r]);
        p.positions = point_matrix(positions[r]);
    }
    return pieces;
}

/// The field's description (not its vectors) from `root`, the lowest rank with faces.
void broadcast_field_description(MPI_Comm comm, NormalField& field, int root) {
    distributed::broadcast_string(comm, field.description, root);
    distributed::broadcast_string(comm, field.input, root);
    std::string kernel = field.ii_kernel.value_or("");
    distributed::broadcast_string(comm, kernel, root);
    field.ii_kernel = kernel.empty() ? std::nullopt : std::optional<std::string>(kernel);
    double radius = field.radius.value_or(-1);
    int extrapolated = field.ii_extrapolated;
    MPI_Bcast(&radius, 1, MPI_DOUBLE, root, comm);
    MPI_Bcast(&extrapolated, 1, MPI_INT, root, comm);
    field.radius = radius >= 0 ? std::optional<double>(radius) : std::nullopt;
    field.ii_extrapolated = extrapolated != 0;
}

void finish_stage(const ProgressCallback& progress, const std::string& stage, double seconds, const std::string& detail) {
    if (progress) progress(ProgressEvent{stage, 1, detail, true, seconds});
}

std::int64_t count_set(const std::vector<char>& flags) { return std::count(flags.begin(), flags.end(), 1); }

}  // namespace

PipelineResult run_distributed_pipeline(MPI_Comm comm, const VolumeSource& source, const PipelineOptions& options,
                                        const ProgressCallback& progress) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const ProgressCallback report = rank == 0 ? progress : ProgressCallback{};
    BlockPlan plan;
    BlockLayout layout;
    run_collectively(comm, [&] {
        if (options.blocks.enabled())
            throw Error("--block-size streams the volume through one process (dsreg regularize); dsreg-mpi solves the "
                        "whole surface at once, one block per rank");
        plan = plan_block_run(source, options, "dsreg-mpi");
        layout = blocks_for_parts(plan.header.volume.grid.dims, size);
    });
    BlockStages block;
    run_collectively(comm, [&] {  // R is not assembled on the patch: the solve writes its rows straight into PETSc
        block = run_block_stages(source, plan, layout.box(rank), layout.box(rank), BlockAssembly::rhs_only);
    });
    RankFigures figures;
    figures.owned_faces = count_set(block.patch.face_owned);
    figures.owned_vertices = count_set(block.patch.vertex_owned);
    figures.patch_faces = block.patch.face_count();
    figures.patch_vertices = block.patch.vertex_count();
    figures.read_voxels = block.read.voxel_count();
    figures.read = block.read_seconds;
    figures.surface = block.surface_seconds;
    figures.normals = block.normals_seconds;
    figures.assembly = block.assembly_seconds;
    const std::int64_t surfels = sum_over_ranks(comm, figures.owned_faces);
    const std::int64_t object_voxels = sum_over_ranks(comm, block.owned_object_voxels);
    // Stage times: the slowest rank's.
    std::vector<std::pair<std::string, double>> stage_seconds = {
        {plan.header.shape ? "digitize" : "read", max_over_ranks(comm, figures.read)},
        {"surface", max_over_ranks(comm, figures.surface)},
        {"normals", max_over_ranks(comm, figures.normals)}};
    finish_stage(report, stage_seconds[0].first, stage_seconds[0].second,
                 std::to_string(object_voxels) + " object voxels, " + std::to_string(size) + " blocks");
    finish_stage(report, "surface", stage_seconds[1].second, std::to_string(surfels) + " surfels");
    if (surfels == 0) throw empty_object_error(source, false);
    const int mine = figures.owned_faces > 0 ? rank : size;
    int described = size;
    MPI_Allreduce(&mine, &described, 1, MPI_INT, MPI_MIN, comm);
    broadcast_field_description(comm, block.field, described);
    finish_stage(report, "normals", stage_seconds[2].second, block.field.description);

    const double eigenvalue = smallest_eigenvalue_bound(comm, block);
    const distributed::VertexNumbering numbering = distributed::number_vertices(comm, block.patch, layout);
    const double max_error = options.max_error_voxels * plan.header.volume.grid.spacing.minCoeff();
    // What rank 0 needs of the block (positions filled after the solve), before the solve frees it.
    BlockPiece piece;
    run_collectively(comm, [&] { piece = patch_piece(block.patch, block.patch.surface.vertices, block.field.normals); });
    NormalField field = std::move(block.field);  // its description, for the result
    block.field.normals = std::move(field.normals);  // the vectors stay: the solve computes the rows of R from them
    distributed::PetscSolution solution = distributed::solve_with_petsc(comm, std::move(block), numbering, max_error, eigenvalue);
    piece.positions = std::move(solution.owned_positions);
    figures.petsc_assembly = solution.assembly_seconds;
    figures.solve = solution.solve_seconds;
    stage_seconds.emplace_back("regularize", max_over_ranks(comm, figures.assembly + figures.petsc_assembly + figures.solve));
    finish_stage(report, "regularize", stage_seconds.back().second,
                 solution.report.solver + ", " + std::to_string(solution.report.iterations) + " iterations, error bound " +
                     format("%.2e", solution.report.error_bound / plan.header.volume.grid.spacing.minCoeff()) + " voxel");

    std::vector<BlockPiece> pieces = gather_pieces(comm, std::move(piece));

    PipelineResult result;
    double weld_seconds = 0;
    run_collectively(comm, [&] {
        if (rank != 0) return;
        const double started = MPI_Wtime();
        WeldedRun run;
        run.welded = weld_pieces(pieces, plan.header.volume.grid);
        weld_seconds = MPI_Wtime() - started;
        run.field = field;
        run.object_voxels = object_voxels;
        run.solve = solution.report;
        run.assembly_seconds = figures.assembly + solution.assembly_seconds;
        run.solve_seconds = solution.solve_seconds;
        result = welded_pipeline_result(std::move(run), plan);
    });
    finish_stage(report, "weld", weld_seconds, std::to_string(surfels) + " surfels on rank 0");
    stage_seconds.emplace_back("weld", weld_seconds);
    run_collectively(comm, [&] {  // the repair's local solves run on rank 0, which holds the welded mesh
        if (rank != 0) return;
        result.stage_seconds = stage_seconds;
        check_and_repair_welded(plan.options, result, report);
    });

    figures.peak_memory = peak_memory_bytes();
    const auto all = distributed::gather_arrays(comm, std::vector<RankFigures>{figures});
    if (rank != 0) {
        result.input = plan.header.description;
        return result;
    }
    nlohmann::json ranks = nlohmann::json::array();
    std::int64_t largest_peak = 0;
    for (int r = 0; r < size; ++r) {
        ranks.push_back(figures_json(all[std::size_t(r)].front(), r));
        largest_peak = std::max(largest_peak, all[std::size_t(r)].front().peak_memory);
    }
    const Index3 counts = layout.block_counts();
    result.extension_report["blocks"] = {{"ranks", size},
                                         {"layout", counts},
                                         {"matrix_nonzeros", solution.matrix_nonzeros},
                                         {"largest_rank_peak_memory_bytes", largest_peak},
                                         {"per_rank", ranks}};
    result.block_layout = layout;
    return result;
}

void write_distributed_outputs(MPI_Comm comm, PipelineResult& result, const PipelineOptions& options,
                               const PipelineOutputs& outputs, const VolumeSource& source, const ProgressCallback& progress) {
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    run_collectively(comm, [&] {
        if (rank == 0) write_pipeline_outputs(result, options, outputs, source, progress);
    });
}

}  // namespace dsreg
