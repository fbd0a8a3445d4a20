// dsreg CLI — wall-clock timing of pipeline stages, progress messages and peak memory.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace dsreg::cli {

/// Times consecutive stages. With `verbose`, prints one line per finished stage on stderr.
class StageClock {
public:
    explicit StageClock(bool verbose) : verbose_(verbose) {}

    /// Ends the current stage (if any) and starts `name`.
    void start(const std::string& name);
    /// Ends the current stage, printing `detail` with it in verbose mode.
    void finish(const std::string& detail = "");

    const std::vector<std::pair<std::string, double>>& stage_seconds() const { return stages_; }
    double total_seconds() const;

private:
    using Clock = std::chrono::steady_clock;
    bool verbose_;
    std::string current_;
    Clock::time_point started_;
    std::vector<std::pair<std::string, double>> stages_;
};

/// Peak resident memory of this process so far, in bytes.
std::int64_t peak_memory_bytes();

/// "1.5 GiB", "230 MiB", ...
std::string human_bytes(double bytes);

}  // namespace dsreg::cli
