// dsreg — the pipeline over MPI (the `dsreg-mpi` driver; docs/scaling.md). Built only when MPI
// and PETSc are found.
//
// The grid is cut into one block per rank (blocks_for_parts, blocks.hpp). Each rank reads its
// block plus a halo (the patch margins and the normal field's reach, block_pipeline.hpp),
// extracts its patch of the digital surface with the global keys of blocks.hpp (so split
// pointels on block faces and corners get the same vertices on every rank), estimates the field
// and assembles the rows of R (eq. 22–23) of the vertices it owns: bit for bit the rows of the
// whole-volume system. The rows go into one PETSc matrix (AIJ with block size 3; each rank's
// vertices are numbered consecutively, in key order), solved by PETSc's CG preconditioned with
// algebraic multigrid (GAMG, the three translations as near-null space; `-pc_type hypre` in
// PETSC_OPTIONS selects hypre's BoomerAMG instead), warm-started at the digital positions, with
// the serial solvers' provable stop: ‖x − x*‖₂ ≤ ‖R x − b‖₂ / (α min α_i w0_i) ≤ max_error
// (solvers.hpp), checked on the true residual. The owned faces and vertices are gathered on rank
// 0, welded in the whole-volume order (weld_pieces) and written there: the same mesh as
// `dsreg regularize` up to the solver's error, with the same vertex and face order.
//
// Errors: every stage that can fail on one rank alone (a file, memory) is followed by a
// collective check, so that all ranks throw the same dsreg::Error (the message of the lowest
// failing rank) instead of waiting for each other. PETSc failures end the run with MPI_Abort.
#pragma once

#include <mpi.h>

#include <functional>
#include <string>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/progress.hpp"

namespace dsreg {

/// MPI and PETSc for the lifetime of the object: initialized unless they already are, finalized
/// by the destructor if initialized here. PETSc reads its options from the PETSC_OPTIONS
/// environment variable only (the command line is dsreg's).
class DistributedSession {
public:
    DistributedSession(int* argc, char*** argv);
    ~DistributedSession();
    DistributedSession(const DistributedSession&) = delete;
    DistributedSession& operator=(const DistributedSession&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }

private:
    bool finalize_mpi_ = false;
    bool finalize_petsc_ = false;
    int rank_ = 0, size_ = 1;
};

/// Runs `work` on every rank of `comm`. If it throws on any rank, every rank throws a dsreg::Error
/// with the message of the lowest failing rank. `work` must not call MPI itself.
void run_collectively(MPI_Comm comm, const std::function<void()>& work);

/// The whole pipeline on every rank of `comm` (one block each). Rank 0 gets the welded
/// PipelineResult (with the "blocks" report: layout, per-rank counts, seconds and peak memory);
/// the other ranks get a result with only the counts. `progress` is called on rank 0 only.
/// Options that need the whole surface at once are refused (plan_block_run), as are the
/// streaming options (--block-size). Throws dsreg::Error on every rank alike.
PipelineResult run_distributed_pipeline(MPI_Comm comm, const VolumeSource& source, const PipelineOptions& options,
                                        const ProgressCallback& progress = {});

/// Writes the outputs on rank 0 (write_pipeline_outputs) and checks collectively.
void write_distributed_outputs(MPI_Comm comm, PipelineResult& result, const PipelineOptions& options,
                               const PipelineOutputs& outputs, const VolumeSource& source,
                               const ProgressCallback& progress = {});

}  // namespace dsreg
