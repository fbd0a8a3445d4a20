#include "stage_clock.hpp"

#include <sys/resource.h>

#include <cstdio>

#include "dsreg/pipeline.hpp"

namespace dsreg {

void StageClock::start(const std::string& name) {
    if (!current_.empty()) finish();
    current_ = name;
    started_ = Clock::now();
    report_progress(progress_, name, 0.0);
}

void StageClock::finish(const std::string& detail) {
    if (current_.empty()) return;
    const double seconds = std::chrono::duration<double>(Clock::now() - started_).count();
    stages_.emplace_back(current_, seconds);
    const std::string stage = std::move(current_);
    current_.clear();
    if (progress_) progress_(ProgressEvent{stage, 1.0, detail, true, seconds});
}

std::int64_t peak_memory_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return std::int64_t(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

std::string human_bytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 4) {
        bytes /= 1024.0;
        ++u;
    }
    char text[32];
    std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
    return text;
}

}  // namespace dsreg
