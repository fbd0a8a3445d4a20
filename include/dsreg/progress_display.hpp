// dsreg — showing progress (progress.hpp) to a person: a live line on a terminal, or plain lines.
//
// progress_display() turns the ProgressEvents of the library into text on a stream:
//   - live (a terminal): one line, redrawn in place ("\r", erase to the end of the line), e.g.
//       dsreg: solve  62%  ~1.4 s left  amg iteration 12, error bound 3.1e-04 voxel (target 5e-05)
//     shown only once a stage has run `delay_seconds` (a step reported under another name inside
//     a stage, such as "solve" inside "regularize", counts from the stage's start), redrawn at
//     most every `interval_seconds`, erased when the stage finishes;
//   - not live (a pipe or a log, when asked): the same text as one line per update, at most one
//     every `interval_seconds`;
//   - with stage_summaries, one line as each stage finishes: "dsreg: solve       1.234 s  …".
// "Time left" extrapolates the stage's elapsed time linearly in its fraction (shown once 2 % is
// done). A live line is cut to `width` characters so that it never wraps.
#pragma once

#include <functional>
#include <ostream>
#include <string>

#include "dsreg/progress.hpp"

namespace dsreg {

struct ProgressDisplayOptions {
    bool live = true;              ///< redraw one line in place (a terminal); false: one line per update
    bool updates = true;           ///< show updates while a stage runs (false: only the summaries)
    bool stage_summaries = true;   ///< a line as each stage finishes
    double delay_seconds = 1.0;    ///< a stage shows its updates once it has run this long
    double interval_seconds = 0.1; ///< at most one update per interval (live: redraws)
    int width = 80;                ///< characters of a live line, at least 20
    std::string prefix = "dsreg: ";  ///< starts every line (dsreg-mpi: "dsreg-mpi: ")
    /// Monotonic time in seconds; empty: std::chrono::steady_clock (tests pass their own).
    std::function<double()> clock;
};

/// A callback that writes the events to `out` (which must outlive it) as described above.
ProgressCallback progress_display(std::ostream& out, ProgressDisplayOptions options);

}  // namespace dsreg
