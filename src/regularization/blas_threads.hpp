// dsreg — internal: the thread count of the BLAS under CHOLMOD's supernodal factorizations.
#pragma once

#include <Eigen/Core>

namespace dsreg::detail {

/// Gives the BLAS (OpenBLAS) as many threads as OpenMP has (omp_get_max_threads(): OMP_NUM_THREADS
/// or omp_set_num_threads, at most the processors available, as OpenBLAS itself would take),
/// unless the user chose a count for the BLAS itself (OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS).
/// Every CHOLMOD factorization dsreg makes sets the count first (use_blas_threads_for: this one, or
/// one thread for a small factorization): the bits of a factor depend on how many threads the
/// BLAS splits its dense blocks over, so the count must follow from the thread count asked for and
/// the matrix, and from nothing else (once it followed the load average: a busy machine gave
/// another mesh than an idle one; and the state left by an earlier call leaked into the next run
/// in the same process). Nothing happens inside a parallel region or if the BLAS is not OpenBLAS.
void use_blas_threads();

/// CHOLMOD factorizations below this many flops (the count of their analysis) run with the BLAS
/// at one thread: their dense blocks are too small to share, and OpenBLAS's threads, which spin
/// while they wait, made them up to 50 times slower on cores busy with other work (lobster.vol's
/// small components, 2.2·10^7 flops: 2.19 s with two BLAS threads at load 4, 0.044 s with one;
/// docs/solvers.md, "Shared cores").
constexpr double kThreadedBlasMinFlops = 1e8;

/// use_blas_threads() for a factorization of `flops`, one thread below kThreadedBlasMinFlops:
/// still a function of the matrix and the thread count asked for, never of the machine's state.
void use_blas_threads_for(double flops);

/// Analyses `matrix` and factors it with `cholesky` (an Eigen CHOLMOD decomposition), the BLAS
/// threads set by use_blas_threads_for from the analysis. info() tells the outcome.
template <class Cholesky, class Matrix>
void factorize_with_cholmod(Cholesky& cholesky, const Matrix& matrix) {
    cholesky.analyzePattern(matrix);
    if (cholesky.info() != Eigen::Success) return;
    use_blas_threads_for(cholesky.cholmod().fl);
    cholesky.factorize(matrix);
}

/// While alive, OpenBLAS runs every call on its caller's thread alone (one BLAS thread), so that
/// CHOLMOD factorizations may run side by side on OpenMP's threads without queueing for the
/// BLAS's own threads; the destructor gives back use_blas_threads()'s count. A count the user
/// chose is kept, and so is the BLAS's state inside a parallel region; `serial()` says whether
/// calls from several threads at once now each run on their own thread (true for a BLAS other
/// than OpenBLAS, which dsreg cannot set: the reference BLAS and BLIS are reentrant).
class OneBlasThread {
public:
    OneBlasThread();
    ~OneBlasThread();
    OneBlasThread(const OneBlasThread&) = delete;
    OneBlasThread& operator=(const OneBlasThread&) = delete;
    bool serial() const { return serial_; }

private:
    bool serial_ = false;
    bool changed_ = false;
};

}  // namespace dsreg::detail
