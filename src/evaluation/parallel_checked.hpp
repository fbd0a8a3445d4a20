// dsreg — evaluation: a parallel loop that reports errors thrown by its body.
#pragma once

#include <cstdint>
#include <exception>
#include <string>

#include "dsreg/error.hpp"

namespace dsreg::detail {

/// Runs body(i) for i in [0, n) in parallel (OpenMP); exceptions must not leave an OpenMP
/// region, so the first one is kept and rethrown afterwards as dsreg::Error.
template <class Body>
void parallel_for_checked(std::int64_t n, Body body) {
    std::string first_error;
    bool failed = false;
#pragma omp parallel for schedule(dynamic, 256)
    for (std::int64_t i = 0; i < n; ++i) {
        bool skip;
#pragma omp atomic read
        skip = failed;
        if (skip) continue;
        try {
            body(i);
        } catch (const std::exception& e) {
#pragma omp critical(dsreg_evaluation_error)
            {
                if (!failed) first_error = e.what();
#pragma omp atomic write
                failed = true;
            }
        }
    }
    if (failed) throw Error(first_error);
}

}  // namespace dsreg::detail
