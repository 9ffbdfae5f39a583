// core/temp_file: atomic writes through a temporary sibling, and the sweep of temporaries that killed
// processes left behind (a SIGKILL during a checkpoint left model.npt.tmp-PID forever).
#include "core/temp_file.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>

#include "test_support.h"

namespace npt {
namespace {

namespace fs = std::filesystem;

// The pid of a process that has exited and been reaped: no process has it (until the system reuses it).
pid_t dead_pid() {
    const pid_t pid = fork();
    if (pid == 0) _exit(0);
    int status = 0;
    waitpid(pid, &status, 0);
    return pid;
}

TEST(TempFile, StaleTemporariesOfDeadProcessesAreRemoved) {
    const fs::path dir = test::temp_dir();
    const fs::path target = dir / "model.npt";
    const std::string dead = std::to_string(dead_pid()), alive = std::to_string(getppid());
    const std::vector<std::string> stale = {"model.npt.tmp-" + dead, "model.npt.tmp-" + dead + "-123456"};
    const std::vector<std::string> kept = {
        "model.npt.tmp-" + alive,  // a live process: another writer of the same file
        "model.npt.tmp-" + alive + "-7",
        "model.npt.tmpfoo",       // not our form
        "model.npt.tmp-12x",      // not a pid
        "other.npt.tmp-" + dead,  // another file's
        "model.npt",
    };
    for (const auto& n : stale) test::write_file(dir / n, "x");
    for (const auto& n : kept) test::write_file(dir / n, "x");
    write_text_atomic(target, "new");  // the next write of model.npt sweeps
    for (const auto& n : stale) EXPECT_FALSE(fs::exists(dir / n)) << n;
    for (const auto& n : kept) EXPECT_TRUE(fs::exists(dir / n)) << n;
    EXPECT_EQ(test::read_text(target), "new");
    EXPECT_EQ(remove_stale_temporaries(target), 0);
}

TEST(TempFile, NamesCarryThePid) {
    const fs::path p = new_temp_path(test::temp_dir() / "a.exr");
    EXPECT_EQ(p.filename().string().rfind("a.exr.tmp-" + std::to_string(getpid()) + "-", 0), 0u) << p;
}

}  // namespace
}  // namespace npt
