// Finding the external tools nerfpt drives (ffmpeg, ffprobe, colmap) before starting them, so that a missing
// one is a clear message instead of a shell's "command not found" in a log.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace npt {

// `name` itself when it contains a '/' and is executable; otherwise the first executable file `name` in a
// folder of PATH (an empty entry means the current folder). Empty when there is none.
std::filesystem::path find_executable(const std::string& name);

// Runs argv (argv[0] looked up on PATH) with stdout and stderr into `log`, and waits for it. The child starts
// with no signal blocked (nerfpt blocks SIGINT/SIGTERM in all its threads for its interrupt watcher), so
// Ctrl-C reaches it too. Returns its exit code, or 128 + the signal that ended it. Throws npt::Error when it
// cannot be started. When `cpu_seconds` is given, it receives the child's user + system CPU time (its own
// threads and the processes it waited for): unlike wall time, a measure of the work that does not depend on
// what else runs on the machine (docs/benchmarks.md times COLMAP this way).
int run_logged(const std::vector<std::string>& argv, const std::filesystem::path& log,
               double* cpu_seconds = nullptr);

}  // namespace npt
