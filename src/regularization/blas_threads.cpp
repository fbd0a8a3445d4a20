#include "blas_threads.hpp"

#include <dlfcn.h>
#include <omp.h>

#include <algorithm>
#include <cstdlib>

namespace dsreg::detail {

namespace {

using GetThreads = int (*)();
using SetThreads = void (*)(int);

struct OpenBlas {
    GetThreads get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    SetThreads set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    bool user_choice = std::getenv("OPENBLAS_NUM_THREADS") != nullptr || std::getenv("GOTO_NUM_THREADS") != nullptr;
};

const OpenBlas& open_blas() {
    static const OpenBlas blas;  // looked up once
    return blas;
}

/// Unless the user chose the count, inside a parallel region, or the BLAS is not OpenBLAS.
void set_blas_threads(int wanted) {
    const OpenBlas& blas = open_blas();
    if (!blas.get || !blas.set || blas.user_choice || omp_in_parallel()) return;
    if (blas.get() != wanted) blas.set(wanted);
}

}  // namespace

void use_blas_threads() { set_blas_threads(std::max(1, std::min(omp_get_max_threads(), omp_get_num_procs()))); }

void use_blas_threads_for(double flops) {
    if (flops < kThreadedBlasMinFlops)
        set_blas_threads(1);
    else
        use_blas_threads();
}

OneBlasThread::OneBlasThread() {
    const OpenBlas& blas = open_blas();
    if (!blas.get) {
        serial_ = true;  // another BLAS: reentrant, and not dsreg's to set
        return;
    }
    const bool was_serial = blas.get() == 1;
    set_blas_threads(1);
    serial_ = blas.get() == 1;
    changed_ = serial_ && !was_serial;
}

OneBlasThread::~OneBlasThread() {
    if (changed_) use_blas_threads();
}

}  // namespace dsreg::detail
