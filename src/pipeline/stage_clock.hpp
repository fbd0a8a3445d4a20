// dsreg pipeline — wall-clock timing of consecutive stages, reported as progress events.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/progress.hpp"

namespace dsreg {

/// Times consecutive stages; reports each start ({stage, 0}) and end ({stage, 1, detail,
/// finished, seconds}) to `progress`.
class StageClock {
public:
    explicit StageClock(ProgressCallback progress) : progress_(std::move(progress)) {}

    /// Ends the current stage (if any) and starts `name`.
    void start(const std::string& name);
    /// Ends the current stage, with `detail` summing it up.
    void finish(const std::string& detail = "");

    const std::vector<std::pair<std::string, double>>& stage_seconds() const { return stages_; }
    const ProgressCallback& progress() const { return progress_; }

private:
    using Clock = std::chrono::steady_clock;
    ProgressCallback progress_;
    std::string current_;
    Clock::time_point started_;
    std::vector<std::pair<std::string, double>> stages_;
};

}  // namespace dsreg
