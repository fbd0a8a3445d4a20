// dsreg distributed — the owned rows of R in a PETSc matrix, solved by CG + algebraic multigrid
// (distributed_stages.hpp).
#include <petscksp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "../regularization/regularization_operator.hpp"
#include "distributed_stages.hpp"
#include "dsreg/error.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/text.hpp"

namespace dsreg::distributed {

[[noreturn]] void petsc_failure(MPI_Comm comm, const std::string& what, int code) {
    const char* text = nullptr;
    char* specific = nullptr;
    PetscErrorMessage(PetscErrorCode(code), &text, &specific);
    std::fprintf(stderr, "dsreg-mpi: error: PETSc failed in %s: %s%s%s\n", what.c_str(), text ? text : "error",
                 specific ? ": " : "", specific ? specific : "");
    std::fflush(stderr);
    MPI_Abort(comm, 1);
    std::abort();
}

namespace {

#define DSREG_PETSC(call)                                           \
    do {                                                            \
        const PetscErrorCode code_ = (call);                        \
        if (code_ != 0) petsc_failure(comm, #call, int(code_)); \
    } while (false)

/// The stop of the serial solvers (conjugate_gradient.hpp): the error bound ‖r‖/λ below
/// max_error, or the residual at rounding level (‖r‖ ≤ 1e-15·(‖R‖∞‖x‖ + ‖b‖)).
struct StopRule {
    double absolute = 0;      ///< max_error · λ
    double matrix_norm = 0;   ///< ‖R‖∞
    double rhs_norm = 0;      ///< ‖b‖₂
    static constexpr double backward_error = 1e-15;

    double floor(double solution_norm) const { return backward_error * (matrix_norm * solution_norm + rhs_norm); }
};

PetscErrorCode error_bound_test(KSP ksp, PetscInt, PetscReal rnorm, KSPConvergedReason* reason, void* context) {
    const StopRule& stop = *static_cast<const StopRule*>(context);
    *reason = KSP_CONVERGED_ITERATING;
    if (!std::isfinite(rnorm)) {
        *reason = KSP_DIVERGED_NANORINF;
        return 0;
    }
    if (rnorm <= stop.absolute) {
        *reason = KSP_CONVERGED_ATOL;
        return 0;
    }
    Vec x = nullptr;
    PetscCall(KSPGetSolution(ksp, &x));
    PetscReal norm = 0;
    PetscCall(VecNorm(x, NORM_2, &norm));
    if (rnorm <= stop.floor(norm)) *reason = KSP_CONVERGED_RTOL;
    return 0;
}

/// Calls visit(row, columns, values) for each owned scalar row of R in global numbering (rows
/// 3v + d, v the vertex's global number), in increasing row order: the rows of the block's
/// patch, computed from its mesh, field and weights (R is never assembled on the patch), with
/// the entries of the assembled matrix (assemble_matrix): a block with an alignment part in
/// full, the others (c·I3) as their diagonal.
template <class Visit>
void for_each_owned_row(const BlockStages& block, const VertexNumbering& numbering, Visit visit) {
    const SurfacePatch& patch = block.patch;
    const DigitalSurface& s = patch.surface;
    const VertexLinks links = vertex_links(s.quads, s.vertex_count());
    const detail::RegularizationOperator R(s.quads, links, block.field.normals, block.weights, s.vertex_count());
    detail::RegularizationOperator::Row blocks(s.vertex_count());
    std::vector<PetscInt> columns;
    std::vector<PetscScalar> values;
    PetscInt row = PetscInt(3 * numbering.first);
    for (std::int64_t j = 0; j < patch.vertex_count(); ++j) {
        if (!patch.vertex_owned[std::size_t(j)]) continue;
        R.row(j, blocks, true);
        for (int d = 0; d < 3; ++d, ++row) {
            columns.clear();
            values.clear();
            for (std::size_t q = 0; q < blocks.columns.size(); ++q) {
                const PetscInt first_column = PetscInt(3 * numbering.index[std::size_t(blocks.columns[q])]);
                for (int c = 0; c < 3; ++c) {
                    if (!blocks.full[q] && c != d) continue;
                    columns.push_back(first_column + c);
                    values.push_back(blocks.blocks[q](d, c));
                }
            }
            visit(row, columns, values);
        }
    }
}

/// Sets a PETSc option unless PETSC_OPTIONS gave it.
void default_option(MPI_Comm comm, const char* name, const char* value) {
    PetscBool given = PETSC_FALSE;
    DSREG_PETSC(PetscOptionsHasName(nullptr, nullptr, name, &given));
    if (!given) DSREG_PETSC(PetscOptionsSetValue(nullptr, name, value));
}

/// GAMG's settings for R (measured on goursat, docs/scaling.md): smoothing by the inverse 3×3
/// diagonal blocks (the alignment term couples the coordinates of a vertex; point Jacobi took
/// 329 CG iterations instead of 45 at h = 0.5), no squared graph on the first level (its
/// aggressive coarsening took 72), and the memory-lean choices: plain (unsmoothed) aggregation
/// and the all-at-once Galerkin product. At h = 0.1 on 4 ranks they bring each rank's peak from
/// 522 MiB to 297 MiB (the serial run: 650 MiB) for 47 iterations instead of 22; PETSC_OPTIONS
/// "-pc_gamg_agg_nsmooths 1" takes the faster, larger hierarchy.
void default_multigrid_options(MPI_Comm comm) {
    default_option(comm, "-mg_levels_pc_type", "pbjacobi");
    default_option(comm, "-pc_gamg_square_graph", "0");
    default_option(comm, "-pc_gamg_agg_nsmooths", "0");
    int size = 1;
    MPI_Comm_size(comm, &size);
    if (size > 1) default_option(comm, "-matptap_via", "allatonce");  // MPIAIJ only (SeqAIJ has no such product)
}

}  // namespace

PetscSolution solve_with_petsc(MPI_Comm comm, BlockStages block, const VertexNumbering& numbering, double max_error,
                               double smallest_eigenvalue) {
    if (3 * numbering.total > std::int64_t(std::numeric_limits<PetscInt>::max()))
        throw Error("the surface has " + std::to_string(numbering.total) + " vertices: this PETSc has " +
                    std::to_string(8 * sizeof(PetscInt)) + "-bit indices, at most " +
                    std::to_string(std::numeric_limits<PetscInt>::max() / 3) +
                    " vertices (use a PETSc built with --with-64-bit-indices)");
    PetscSolution solution;
    double started = MPI_Wtime();
    const PetscInt local = PetscInt(3 * numbering.owned);
    const PetscInt first = PetscInt(3 * numbering.first), last = first + local;

    // Preallocation (columns of this rank's rows, the others), then the rows themselves; ‖R‖∞.
    std::vector<PetscInt> diagonal_count, off_diagonal_count;
    double row_sum = 0;
    for_each_owned_row(block, numbering, [&](PetscInt, const std::vector<PetscInt>& columns, const std::vector<PetscScalar>& values) {
        const auto inside = std::count_if(columns.begin(), columns.end(), [&](PetscInt c) { return c >= first && c < last; });
        diagonal_count.push_back(PetscInt(inside));
        off_diagonal_count.push_back(PetscInt(columns.size()) - PetscInt(inside));
        double sum = 0;
        for (const PetscScalar v : values) sum += std::abs(v);
        row_sum = std::max(row_sum, sum);
    });
    Mat A = nullptr;
    DSREG_PETSC(MatCreate(comm, &A));
    DSREG_PETSC(MatSetSizes(A, local, local, PETSC_DETERMINE, PETSC_DETERMINE));
    DSREG_PETSC(MatSetType(A, MATAIJ));
    DSREG_PETSC(MatSetBlockSize(A, 3));
    DSREG_PETSC(MatSeqAIJSetPreallocation(A, 0, diagonal_count.data()));
    DSREG_PETSC(MatMPIAIJSetPreallocation(A, 0, diagonal_count.data(), 0, off_diagonal_count.data()));
    DSREG_PETSC(MatSetOption(A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
    diagonal_count = {};
    off_diagonal_count = {};
    for_each_owned_row(block, numbering, [&](PetscInt row, const std::vector<PetscInt>& columns, const std::vector<PetscScalar>& values) {
        DSREG_PETSC(MatSetValues(A, 1, &row, PetscInt(columns.size()), columns.data(), values.data(), INSERT_VALUES));
    });
    DSREG_PETSC(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    DSREG_PETSC(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    DSREG_PETSC(MatSetOption(A, MAT_SYMMETRIC, PETSC_TRUE));
    DSREG_PETSC(MatSetOption(A, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
    // R is SPD (eq. 25): told so, GAMG skips symmetrizing its graph (a transpose and a sum per
    // level; MAT_SYMMETRIC alone does not): at h = 0.1 on 4 ranks, 220 -> 200 MiB per rank.
    DSREG_PETSC(MatSetOption(A, MAT_SPD, PETSC_TRUE));
    MatInfo info;
    DSREG_PETSC(MatGetInfo(A, MAT_GLOBAL_SUM, &info));
    solution.matrix_nonzeros = std::int64_t(info.nz_used);

    // b, the warm start p, and the translations (the near-null space of K, eq. 25).
    Vec x = nullptr, b = nullptr, residual = nullptr;
    DSREG_PETSC(MatCreateVecs(A, &x, &b));
    DSREG_PETSC(VecDuplicate(b, &residual));
    Vec translations[3] = {nullptr, nullptr, nullptr};
    {
        PetscScalar *xs = nullptr, *bs = nullptr;
        DSREG_PETSC(VecGetArray(x, &xs));
        DSREG_PETSC(VecGetArray(b, &bs));
        std::int64_t r = 0;
        for (std::int64_t j = 0; j < block.patch.vertex_count(); ++j) {
            if (!block.patch.vertex_owned[std::size_t(j)]) continue;
            for (int d = 0; d < 3; ++d, ++r) {
                xs[r] = block.patch.surface.vertices(j, d);
                bs[r] = block.system.rhs[3 * j + d];
            }
        }
        DSREG_PETSC(VecRestoreArray(x, &xs));
        DSREG_PETSC(VecRestoreArray(b, &bs));
        const double unit = 1.0 / std::sqrt(double(numbering.total));
        for (int d = 0; d < 3; ++d) {
            DSREG_PETSC(VecDuplicate(b, &translations[d]));
            PetscScalar* t = nullptr;
            DSREG_PETSC(VecGetArray(translations[d], &t));
            for (PetscInt q = 0; q < local; ++q) t[q] = q % 3 == d ? unit : 0.0;
            DSREG_PETSC(VecRestoreArray(translations[d], &t));
        }
    }
    block = BlockStages();  // PETSc holds the rows now: free the block before the multigrid setup
    MatNullSpace near_null = nullptr;
    DSREG_PETSC(MatNullSpaceCreate(comm, PETSC_FALSE, 3, translations, &near_null));
    DSREG_PETSC(MatSetNearNullSpace(A, near_null));

    StopRule stop;
    stop.absolute = max_error * smallest_eigenvalue;
    MPI_Allreduce(&row_sum, &stop.matrix_norm, 1, MPI_DOUBLE, MPI_MAX, comm);
    PetscReal norm = 0;
    DSREG_PETSC(VecNorm(b, NORM_2, &norm));
    stop.rhs_norm = norm;

    KSP ksp = nullptr;
    PC pc = nullptr;
    DSREG_PETSC(KSPCreate(comm, &ksp));
    DSREG_PETSC(KSPSetOperators(ksp, A, A));
    DSREG_PETSC(KSPSetType(ksp, KSPCG));
    DSREG_PETSC(KSPGetPC(ksp, &pc));
    DSREG_PETSC(PCSetType(pc, PCGAMG));
    DSREG_PETSC(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
    DSREG_PETSC(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
    DSREG_PETSC(KSPSetTolerances(ksp, 0.0, stop.absolute, PETSC_DEFAULT, 20000));
    DSREG_PETSC(KSPSetConvergenceTest(ksp, error_bound_test, &stop, nullptr));
    default_multigrid_options(comm);
    DSREG_PETSC(KSPSetFromOptions(ksp));  // PETSC_OPTIONS, e.g. -pc_type hypre -ksp_monitor
    solution.assembly_seconds = MPI_Wtime() - started;

    started = MPI_Wtime();
    PetscReal true_residual = 0;
    int iterations = 0;
    for (int attempt = 0; attempt < 5; ++attempt) {  // confirmed on the true residual, as the serial CG
        DSREG_PETSC(KSPSolve(ksp, b, x));
        KSPConvergedReason reason;
        DSREG_PETSC(KSPGetConvergedReason(ksp, &reason));
        PetscInt done = 0;
        DSREG_PETSC(KSPGetIterationNumber(ksp, &done));
        iterations += int(done);
        if (reason < 0)
            throw Error(std::string("PETSc's CG did not converge (") + KSPConvergedReasons[reason] + ") after " +
                        std::to_string(iterations) + " iterations");
        DSREG_PETSC(MatMult(A, x, residual));
        DSREG_PETSC(VecAYPX(residual, -1.0, b));
        DSREG_PETSC(VecNorm(residual, NORM_2, &true_residual));
        PetscReal solution_norm = 0;
        DSREG_PETSC(VecNorm(x, NORM_2, &solution_norm));
        if (true_residual <= stop.absolute || true_residual <= stop.floor(solution_norm)) break;
    }
    solution.solve_seconds = MPI_Wtime() - started;

    const char* pc_type = nullptr;
    DSREG_PETSC(PCGetType(pc, &pc_type));
    solution.report.solver = std::string("petsc-cg+") + (pc_type ? pc_type : "?");
    solution.report.iterations = iterations;
    solution.report.relative_residual = stop.rhs_norm > 0 ? true_residual / stop.rhs_norm : 0;
    solution.report.error_bound = true_residual / smallest_eigenvalue;
    PetscBool multigrid = PETSC_FALSE;
    DSREG_PETSC(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(pc), PCGAMG, &multigrid));
    if (multigrid) {
        PetscInt levels = 0;
        DSREG_PETSC(PCMGGetLevels(pc, &levels));
        solution.report.multigrid_levels = int(levels);
    }

    solution.owned_positions.resize(numbering.owned, 3);
    const PetscScalar* xs = nullptr;
    DSREG_PETSC(VecGetArrayRead(x, &xs));
    std::copy(xs, xs + local, solution.owned_positions.data());
    DSREG_PETSC(VecRestoreArrayRead(x, &xs));

    DSREG_PETSC(KSPDestroy(&ksp));
    DSREG_PETSC(MatNullSpaceDestroy(&near_null));
    for (Vec& t : translations) DSREG_PETSC(VecDestroy(&t));
    DSREG_PETSC(VecDestroy(&residual));
    DSREG_PETSC(VecDestroy(&b));
    DSREG_PETSC(VecDestroy(&x));
    DSREG_PETSC(MatDestroy(&A));
    return solution;
}

}  // namespace dsreg::distributed
