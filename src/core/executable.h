// Finding the external tools nerfpt drives (ffmpeg, ffprobe, colmap) before starting them, so that a missing
// one is a clear message instead of a shell's "command not found" in a log.
#pragma once

#include <filesystem>
#include <string>

namespace npt {

// `name` itself when it contains a '/' and is executable; otherwise the first executable file `name` in a
// folder of PATH (an empty entry means the current folder). Empty when there is none.
std::filesystem::path find_executable(const std::string& name);

}  // namespace npt
