// dsreg — internal: the thread count of the BLAS under CHOLMOD's supernodal factorizations.
#pragma once

namespace dsreg::detail {

/// Gives the BLAS (OpenBLAS) as many threads as OpenMP has (omp_get_max_threads(): OMP_NUM_THREADS
/// or omp_set_num_threads, at most the processors available, as OpenBLAS itself would take),
/// unless the user chose a count for the BLAS itself (OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS).
/// Called before every CHOLMOD factorization dsreg makes: the bits of a factor depend on how many
/// threads the BLAS splits its dense blocks over, so this count must follow from the thread count
/// asked for and from nothing else (once it followed the load average: a busy machine gave
/// another mesh than an idle one; and the state left by an earlier call leaked into the next run
/// in the same process). Nothing happens inside a parallel region or if the BLAS is not OpenBLAS.
void use_blas_threads();

}  // namespace dsreg::detail
