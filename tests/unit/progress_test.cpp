// Progress: text formatting and the rate limits, with a fake clock and a string stream.
#include "core/progress.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace npt {
namespace {

struct FakeClock {
    double now = 100.0;  // not zero: the start time must not be assumed to be 0
};

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

ProgressSettings settings(ProgressSettings::Style style) {
    ProgressSettings s;
    s.style = style;
    s.bar_width = 10;
    return s;
}

TEST(ProgressFormat, Counts) {
    EXPECT_EQ(format_count(0), "0");
    EXPECT_EQ(format_count(999), "999");
    EXPECT_EQ(format_count(1234), "1.2k");
    EXPECT_EQ(format_count(1.2e6), "1.2M");
    EXPECT_EQ(format_count(3.45e9), "3.5G");
    EXPECT_EQ(format_count(-1), "?");
}

TEST(ProgressFormat, Durations) {
    EXPECT_EQ(format_eta_clock(12), "0:12");
    EXPECT_EQ(format_eta_clock(75), "1:15");
    EXPECT_EQ(format_eta_clock(3725), "1:02:05");
    EXPECT_EQ(format_eta_clock(NAN), "?:??");
    EXPECT_EQ(format_seconds(0.42), "0.4 s");
    EXPECT_EQ(format_seconds(12.3), "12 s");
    EXPECT_EQ(format_seconds(150), "2 min 30 s");
    EXPECT_EQ(format_seconds(7500), "2 h 5 min");
}

TEST(ProgressFormat, Bar) {
    EXPECT_EQ(format_bar(0.0, 10), "[..........]");
    EXPECT_EQ(format_bar(0.45, 10), "[####......]");
    EXPECT_EQ(format_bar(1.0, 10), "[##########]");
    EXPECT_EQ(format_bar(7.0, 4), "[####]");
    EXPECT_EQ(format_bar(NAN, 4), "[....]");
}

TEST(ProgressStyle, FollowsTerminalAndQuiet) {
    EXPECT_EQ(progress_style(true, false), ProgressSettings::Style::Bar);
    EXPECT_EQ(progress_style(false, false), ProgressSettings::Style::Lines);
    EXPECT_EQ(progress_style(true, true), ProgressSettings::Style::Silent);
    EXPECT_EQ(progress_style(false, true), ProgressSettings::Style::Silent);
}

TEST(ProgressLines, LineTextHasPercentRateAndEta) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Lines), out, [&] { return clock.now; });
    clock.now += 10.0;
    p.update(450, 1000);  // 45 per second, 550 left: 12.2 s
    EXPECT_EQ(out.str(), "render: 45% (45 samples/s, ETA 12 s)\n");
}

TEST(ProgressLines, AtMostEveryTwoSecondsAndEveryTenPercent) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Lines), out, [&] { return clock.now; });
    const uint64_t total = 1000;
    // Fast work: 1% every 0.1 s. Time allows a line every 2 s (20%), which is the tighter limit here.
    for (uint64_t done = 0; done <= total; done += 10) {
        p.update(done, total);
        clock.now += 0.1;
    }
    auto lines = lines_of(out.str());
    EXPECT_GE(lines.size(), 4u);
    EXPECT_LE(lines.size(), 5u);  // 100 updates over 10 s: at most one line per 2 s

    // Slow work: 1% every 1 s. A first line after 2 s (2%), then the 10% step is the tighter limit.
    std::ostringstream slow;
    FakeClock clock2;
    Progress q(settings(ProgressSettings::Style::Lines), slow, [&] { return clock2.now; });
    for (uint64_t done = 0; done <= total; done += 10) {
        q.update(done, total);
        clock2.now += 1.0;
    }
    lines = lines_of(slow.str());
    ASSERT_EQ(lines.size(), 10u) << slow.str();
    EXPECT_EQ(lines[0].rfind("render: 2%", 0), 0u) << lines[0];
    EXPECT_EQ(lines[1].rfind("render: 10%", 0), 0u) << lines[1];
    EXPECT_EQ(lines[9].rfind("render: 90%", 0), 0u) << lines[9];
    q.finish();  // 100% is printed once, by finish(), with the total time
    lines = lines_of(slow.str());
    ASSERT_EQ(lines.size(), 11u) << slow.str();
    EXPECT_EQ(lines[10], "render: 100% (10 samples/s, 101 s)");
}

TEST(ProgressLines, ShortRunPrintsOnlyTheFinalLine) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Lines), out, [&] { return clock.now; });
    for (uint64_t done = 0; done <= 100; ++done) {
        p.update(done, 100);
        clock.now += 0.01;
    }
    p.finish();
    p.finish();  // idempotent
    EXPECT_EQ(out.str(), "render: 100% (99 samples/s, 1.0 s)\n");
}

TEST(ProgressBar, RedrawsInPlaceAtMostTenTimesASecond) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Bar), out, [&] { return clock.now; });
    for (int i = 0; i <= 1000; ++i) {
        p.update(uint64_t(i), 1000);
        clock.now += 0.001;  // 1 s in all
    }
    const std::string s = out.str();
    const auto redraws = std::count(s.begin(), s.end(), '\r');
    EXPECT_GE(redraws, 9);
    EXPECT_LE(redraws, 12);
    EXPECT_EQ(s.find('\n'), std::string::npos);  // one line, redrawn
    clock.now = 101.0;
    p.finish();
    const std::string last = out.str().substr(out.str().rfind('\r'));
    EXPECT_EQ(last, "\rrender [##########] 100%  1.0k samples/s  1.0 s\x1b[K\n");
}

TEST(ProgressBar, ShowsEtaAsClock) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Bar), out, [&] { return clock.now; });
    clock.now += 10.0;
    p.update(450, 1000);
    EXPECT_EQ(out.str(), "\rrender [####......]  45%  45 samples/s  ETA 0:12\x1b[K");
}

TEST(ProgressSilent, PrintsNothing) {
    FakeClock clock;
    std::ostringstream out;
    Progress p(settings(ProgressSettings::Style::Silent), out, [&] { return clock.now; });
    for (int i = 0; i < 100; ++i) {
        clock.now += 1.0;
        p.update(uint64_t(i), 100);
    }
    p.finish();
    EXPECT_TRUE(out.str().empty());
}

TEST(ProgressThreads, ConcurrentUpdatesAreSafe) {
    std::ostringstream out;
    ProgressSettings s = settings(ProgressSettings::Style::Bar);
    s.bar_interval_s = 0.0;  // print as often as possible, to exercise the lock
    Progress p(s, out);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&p, t] {
            for (uint64_t i = 0; i < 2000; ++i) p.update(i * 4 + uint64_t(t), 8000);
        });
    for (auto& t : threads) t.join();
    p.finish();
    EXPECT_NE(out.str().find("100%"), std::string::npos);
}

}  // namespace
}  // namespace npt
