// dsreg — progress events as a live terminal line or as plain lines.
#include "dsreg/progress_display.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>

#include "dsreg/text.hpp"

namespace dsreg {

namespace {

double steady_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// "solve  62%  ~1.4 s left  amg iteration 12, …" (fraction and time left when known).
std::string update_text(const std::string& prefix, const ProgressEvent& event, double elapsed) {
    std::string text = prefix + event.stage;
    if (event.fraction >= 0) {
        const double f = std::min(event.fraction, 1.0);
        text += "  " + format("%.0f", 100 * f) + "%";
        if (f >= 0.02 && f < 1) text += "  ~" + format("%.1f", elapsed * (1 - f) / f) + " s left";
    } else {
        text += "  " + format("%.1f", elapsed) + " s";
    }
    if (!event.detail.empty()) text += "  " + event.detail;
    return text;
}

std::string summary_text(const std::string& prefix, const ProgressEvent& event) {
    return prefix + event.stage + ' ' + format("%8.3f s", event.seconds) + (event.detail.empty() ? "" : "  " + event.detail);
}

class Display {
public:
    Display(std::ostream& out, ProgressDisplayOptions options) : out_(out), options_(std::move(options)) {
        if (!options_.clock) options_.clock = steady_seconds;
        options_.width = std::max(options_.width, 20);
    }

    void operator()(const ProgressEvent& event) {
        const double now = options_.clock();
        if (!running_) {  // a stage starts: the delay counts from here
            running_ = true;
            running_since_ = now;
        }
        if (event.stage != stage_) {  // a new stage, or a step inside one ("solve" inside "regularize")
            stage_ = event.stage;
            stage_started_ = now;
        }
        if (event.finished) {
            erase();
            if (options_.stage_summaries) out_ << summary_text(options_.prefix, event) << '\n' << std::flush;
            stage_.clear();
            running_ = false;
            last_update_ = -1;
            return;
        }
        if (!options_.updates || now - running_since_ < options_.delay_seconds) return;
        if (last_update_ >= 0 && now - last_update_ < options_.interval_seconds) return;
        last_update_ = now;
        std::string text = update_text(options_.prefix, event, now - stage_started_);
        if (options_.live) {
            if (int(text.size()) > options_.width - 1) text.resize(std::size_t(options_.width - 1));
            out_ << '\r' << text << "\033[K" << std::flush;
            shown_ = true;
        } else {
            out_ << text << '\n' << std::flush;
        }
    }

private:
    void erase() {
        if (!shown_) return;
        out_ << "\r\033[K" << std::flush;
        shown_ = false;
    }

    std::ostream& out_;
    ProgressDisplayOptions options_;
    std::string stage_;
    double stage_started_ = 0, running_since_ = 0, last_update_ = -1;
    bool running_ = false;  ///< between a stage's first event and its finished event
    bool shown_ = false;    ///< a live line is on the screen
};

}  // namespace

ProgressCallback progress_display(std::ostream& out, ProgressDisplayOptions options) {
    auto display = std::make_shared<Display>(out, std::move(options));
    return [display](const ProgressEvent& event) { (*display)(event); };
}

}  // namespace dsreg
