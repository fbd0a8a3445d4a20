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
