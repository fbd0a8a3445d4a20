// dsreg distributed — internal: the stages of run_distributed_pipeline that talk to other ranks
// (include/dsreg/distributed.hpp).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/block_pipeline.hpp"
#include "dsreg/blocks.hpp"
#include "dsreg/solvers.hpp"

namespace dsreg::distributed {

/// The global numbering of the vertices: each rank's owned vertices are consecutive, in key
/// order, ranks in order (the row order of the PETSc matrix: vertex v has rows 3v, 3v+1, 3v+2).
struct VertexNumbering {
    std::vector<std::int64_t> index;  ///< of every patch vertex
    std::int64_t first = 0;           ///< index of this rank's first owned vertex
    std::int64_t owned = 0;           ///< vertices this rank owns
    std::int64_t total = 0;           ///< vertices of the whole surface
};

/// Numbers the owned vertices and asks their owners (the rank of the block holding a key's
/// voxel) for the numbers of the other patch vertices. Collective. Throws dsreg::Error on every
/// rank if some rank holds a vertex that its owner does not have (the seams would not match).
VertexNumbering number_vertices(MPI_Comm comm, const SurfacePatch& patch, const BlockLayout& layout);

struct PetscSolution {
    SolveReport report;
    PointMatrix owned_positions;  ///< the solution at the owned vertices, in their order
    double assembly_seconds = 0, solve_seconds = 0;
    std::int64_t matrix_nonzeros = 0;  ///< of the whole matrix
};

/// Assembles the owned rows of R into a PETSc matrix and solves R x = b with CG + algebraic
/// multigrid until ‖R x − b‖₂ / smallest_eigenvalue ≤ max_error (or rounding level). The rows
/// are computed from the block's patch, field and weights (its system.matrix is not read: run
/// the block stages with BlockAssembly::rhs_only). Consumes the block (freed once PETSc holds
/// its rows, before the multigrid setup). Collective.
PetscSolution solve_with_petsc(MPI_Comm comm, BlockStages block, const VertexNumbering& numbering, double max_error,
                               double smallest_eigenvalue);

/// Ends the run: prints "dsreg-mpi: PETSc error in WHAT: MESSAGE" and calls MPI_Abort.
[[noreturn]] void petsc_failure(MPI_Comm comm, const std::string& what, int code);

}  // namespace dsreg::distributed
