#include "core/executable.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "core/error.h"
#include "test_support.h"

namespace npt {
namespace {

TEST(RunLogged, ExitCodeLogAndCpuTime) {
    const std::filesystem::path log = test::temp_dir() / "run.log";
    // A shell loop that keeps one core busy for a fraction of a second.
    double cpu = -1;
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = run_logged(
        {"sh", "-c", "i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done; echo done; exit 3"}, log, &cpu);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(rc, 3);
    EXPECT_NE(test::read_text(log).find("done"), std::string::npos);
    // One thread: its CPU time is positive and, with the clocks' ticks of slack, at most the wall time.
    EXPECT_GT(cpu, 0.0);
    EXPECT_LE(cpu, wall + 0.02);
    // Without the pointer nothing is measured, and a program that is not there is an error.
    EXPECT_EQ(run_logged({"sh", "-c", "exit 0"}, log), 0);
    EXPECT_THROW(run_logged({"no-such-program-npt"}, log, &cpu), Error);
}

}  // namespace
}  // namespace npt
