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

}  // namespace

void use_blas_threads() {
    static const OpenBlas blas;  // looked up once
    if (!blas.get || !blas.set || blas.user_choice || omp_in_parallel()) return;
    const int wanted = std::max(1, std::min(omp_get_max_threads(), omp_get_num_procs()));
    if (blas.get() != wanted) blas.set(wanted);
}

}  // namespace dsreg::detail
