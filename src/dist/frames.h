// Splitting a shot into frames and frames into tasks, for render farms that run one process per task (SLURM job
// arrays, Flamenco, Deadline): the frame range syntax, each task's contiguous chunk, the output name of a frame and
// the seed of a frame. No MPI here: every function is a pure function of its arguments, so that any process
// computes the same split and the same seed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace npt::dist {

struct FrameRange {
    int first = 1, last = 1, step = 1;
    std::vector<int> frames() const;  // first, first + step, ... <= last
};

// "FIRST-LAST[:STEP]" or "FRAME" (frames 0..9999999, FIRST <= LAST, STEP >= 1); `option` names the option in
// the error, e.g. "--frames: '10-1' ...".
FrameRange parse_frame_range(const std::string& text, const std::string& option = "--frames");

// Task `index` of `count` (0 <= index < count): the index-th of `count` contiguous chunks of `frames`, whose sizes
// differ by at most one (the first `frames.size() % count` chunks one longer). Tasks beyond the frame count get
// none. The union over all tasks is `frames`, each frame once.
std::vector<int> task_frames(const std::vector<int>& frames, int index, int count);

struct TaskSlot {
    int index = 0, count = 1;
};
// The task of this process: --task-index/--task-count when given, else SLURM_ARRAY_TASK_ID and
// SLURM_ARRAY_TASK_COUNT (with SLURM_ARRAY_TASK_MIN subtracted, so that arrays numbered from 1 work), else task 0
// of 1. `getenv` is the environment lookup (std::getenv in the CLI, a map in tests). Throws npt::Error naming
// the option or variable when a value is not a whole number or index is not in [0, count).
TaskSlot resolve_task(std::optional<int> index, std::optional<int> count,
                      const char* (*getenv)(const char*));

// The output of frame `frame`: the last run of '#' in the file name replaced by the frame number, zero-padded
// to the run's length ("shot.####.exr", 7 -> "shot.0007.exr"). Throws npt::Error when the name has no '#'.
std::filesystem::path frame_path(const std::filesystem::path& pattern, int frame);
bool has_frame_pattern(const std::filesystem::path& pattern);

// The seed of frame `frame` of a shot rendered with `seed`: a 64-bit mix of both, so that neighbouring frames
// have unrelated sample patterns (no "screen door" that stays still while the camera moves) and a frame is the
// same image whichever process or task renders it.
uint64_t frame_seed(uint64_t seed, int frame);

}  // namespace npt::dist
