// dsreg — progress of long work, and how to interrupt it.
//
// Long stages (reading, integral invariants, the solve, …) report how far they are through a
// ProgressCallback. The library calls it only from the thread that called it, never from inside
// an OpenMP parallel region, so the callback may throw to stop the work: the exception (e.g.
// dsreg::Interrupted, thrown by the Python module on Ctrl-C) leaves the library like any other,
// with nothing written. An empty callback costs nothing.
#pragma once

#include <functional>
#include <string>

#include "dsreg/error.hpp"

namespace dsreg {

struct ProgressEvent {
    std::string stage;      ///< "read", "surface", "normals", "solve", …
    double fraction = -1;   ///< of the stage done, in [0, 1]; −1 when unknown
    std::string detail;     ///< e.g. "iteration 12, error bound 3.1e-04 voxel"; may be empty
    bool finished = false;  ///< the stage is over: `detail` sums it up, `seconds` is its wall time
    double seconds = 0;
};

using ProgressCallback = std::function<void(const ProgressEvent&)>;

/// Calls `progress` if it is set.
inline void report_progress(const ProgressCallback& progress, const std::string& stage, double fraction,
                            const std::string& detail = {}) {
    if (progress) progress(ProgressEvent{stage, fraction, detail});
}

/// Thrown (by a progress callback) to abandon the work in progress.
class Interrupted : public Error {
public:
    Interrupted() : Error("interrupted") {}
};

}  // namespace dsreg
