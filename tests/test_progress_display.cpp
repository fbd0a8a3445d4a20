// The progress display: live line redrawn in place and erased, plain lines, delay and throttle.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "dsreg/progress_display.hpp"

namespace dsreg {
namespace {

struct Fixture {
    std::ostringstream out;
    double now = 0;
    ProgressCallback display;

    explicit Fixture(ProgressDisplayOptions o) {
        o.clock = [this] { return now; };
        display = progress_display(out, o);
    }
    void at(double t, const std::string& stage, double fraction, const std::string& detail = {}) {
        now = t;
        display(ProgressEvent{stage, fraction, detail});
    }
    void finish(double t, const std::string& stage, double seconds, const std::string& detail) {
        now = t;
        ProgressEvent e{stage, 1.0, detail};
        e.finished = true;
        e.seconds = seconds;
        display(e);
    }
};

TEST(ProgressDisplay, LiveLineAppearsAfterTheDelayIsRedrawnInPlaceAndErasedAtTheEnd) {
    Fixture f{ProgressDisplayOptions{}};
    f.at(0.0, "solve", 0.0);
    f.at(0.5, "solve", 0.1, "amg iteration 3");
    EXPECT_EQ(f.out.str(), "") << "nothing before the stage has run a second";
    f.at(2.0, "solve", 0.5, "amg iteration 9, error bound 1.0e-03 voxel");
    // 2 s for half the work: about 2 s left
    EXPECT_EQ(f.out.str(), "\rdsreg: solve  50%  ~2.0 s left  amg iteration 9, error bound 1.0e-03 voxel\033[K");
    f.at(2.05, "solve", 0.6, "amg iteration 10");
    EXPECT_EQ(f.out.str().find("iteration 10"), std::string::npos) << "at most one redraw per 0.1 s";
    f.at(2.5, "solve", 0.8, "amg iteration 12");
    EXPECT_NE(f.out.str().find("\rdsreg: solve  80%"), std::string::npos);
    f.out.str("");
    f.finish(3.0, "solve", 3.0, "amg, 14 iterations");
    EXPECT_EQ(f.out.str(), "\r\033[Kdsreg: solve    3.000 s  amg, 14 iterations\n");
}

TEST(ProgressDisplay, EachStageWaitsForItsOwnDelayAndUnknownFractionsShowTheElapsedTime) {
    Fixture f{ProgressDisplayOptions{}};
    f.at(0.0, "read", 0.0);
    f.finish(0.2, "read", 0.2, "");
    f.out.str("");
    f.at(0.2, "normals", -1);
    f.at(1.0, "normals", -1);
    EXPECT_EQ(f.out.str(), "");
    f.at(1.7, "normals", -1);
    EXPECT_EQ(f.out.str(), "\rdsreg: normals  1.5 s\033[K");
}

TEST(ProgressDisplay, AStepInsideAStageCountsTheDelayFromTheStageStart) {
    Fixture f{ProgressDisplayOptions{}};
    f.at(0.0, "regularize", 0.0);
    f.at(0.8, "solve", 0.0, "amg iteration 1");
    EXPECT_EQ(f.out.str(), "");
    f.at(1.2, "solve", 0.2, "amg iteration 5");
    // shown 1.2 s after "regularize" started; time left from the 0.4 s of "solve" so far
    EXPECT_EQ(f.out.str(), "\rdsreg: solve  20%  ~1.6 s left  amg iteration 5\033[K");
    f.out.str("");
    f.finish(2.0, "regularize", 2.0, "amg");
    EXPECT_EQ(f.out.str(), "\r\033[Kdsreg: regularize    2.000 s  amg\n");
}

TEST(ProgressDisplay, PlainLinesForAPipeAndNothingButSummariesWithoutUpdates) {
    ProgressDisplayOptions plain;
    plain.live = false;
    plain.interval_seconds = 1.0;
    plain.stage_summaries = false;
    Fixture f{plain};
    f.at(0.0, "solve", 0.0);
    f.at(1.5, "solve", 0.25, "cg iteration 40");
    f.at(2.0, "solve", 0.5, "cg iteration 80");
    f.at(2.6, "solve", 0.75, "cg iteration 120");
    f.finish(3.0, "solve", 3.0, "cg");
    EXPECT_EQ(f.out.str(), "dsreg: solve  25%  ~4.5 s left  cg iteration 40\n"
                           "dsreg: solve  75%  ~0.9 s left  cg iteration 120\n");

    ProgressDisplayOptions summaries;
    summaries.updates = false;
    Fixture g{summaries};
    g.at(0.0, "solve", 0.0);
    g.at(5.0, "solve", 0.5, "amg iteration 9");
    g.finish(6.0, "solve", 6.0, "amg");
    EXPECT_EQ(g.out.str(), "dsreg: solve    6.000 s  amg\n");
}

TEST(ProgressDisplay, LiveLinesAreCutToTheWidth) {
    ProgressDisplayOptions o;
    o.width = 30;
    Fixture f{o};
    f.at(0.0, "solve", 0.0);
    f.at(2.0, "solve", 0.5, std::string(100, 'x'));
    EXPECT_EQ(f.out.str(), "\r" + std::string("dsreg: solve  50%  ~2.0 s left  xxx").substr(0, 29) + "\033[K");
}

}  // namespace
}  // namespace dsreg
