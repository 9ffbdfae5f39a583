// Loop closure for the poses of a video. The sequential matcher pairs each frame with its next few only, so
// when the walk comes back to where it was (the end of a 360° capture meets its start, a second turn passes
// the first) those views are never matched: each step's small error then adds up along the path, and nothing
// ties the path's two ends together. From a first reconstruction this picks the pairs of frames far apart in
// time whose cameras stand near each other and look the same way; matched and triangulated, they close the
// loop before a final global bundle adjustment (run_colmap; docs/benchmarks.md, "Poses as accurate as before
// the speed-up").
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "capture/pose_alignment.h"

namespace npt::capture {

struct RevisitSettings {
    int overlap = 15;           // frames closer than this in name order are matched already (sequential)
    double max_angle_deg = 25;  // largest angle between the two cameras' viewing directions
    double max_distance_steps =
        6;                  // largest distance between the centres, in median steps between neighbours
    int max_per_frame = 4;  // nearest partners kept per frame (matching costs per pair)
};

// Pairs (earlier name, later name) of the name-sorted poses, each pair once, nearest first per frame. Empty
// for fewer than overlap + 2 poses.
std::vector<std::pair<std::string, std::string>> revisit_pairs(
    const std::vector<CameraPose>& poses_sorted_by_name, const RevisitSettings& settings = {});

}  // namespace npt::capture
