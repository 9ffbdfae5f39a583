// Held-out views for a capture: transforms.json split into transforms_train.json and transforms_test.json,
// so that `nerfpt train` never sees the frames `nerfpt eval` scores it on (DATA folder + --split).
#pragma once

#include <cstddef>
#include <filesystem>

namespace npt::capture {

struct SplitCounts {
    size_t train = 0, test = 0;
};

// Every `every`-th frame in name order, starting at frame every/2 (so the held-out views are spread along the
// video, not bunched at its start), goes to transforms_test.json, the rest to transforms_train.json, both
// beside `json` and otherwise identical to it (intrinsics, aabb_scale, ...). Image paths stay valid: the
// files share the folder. Both are written atomically. Throws npt::Error naming the file when it cannot be
// read, has no "frames" array, has fewer than 2 frames, or every < 2 (a split needs frames on both sides).
SplitCounts split_transforms(const std::filesystem::path& json, int every);

}  // namespace npt::capture
