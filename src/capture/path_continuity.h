// A sanity check on poses from a video that the reprojection error cannot give: the camera moves a little
// between neighbouring frames, so a camera centre that leaps across the scene between two frames in name
// (= time) order means COLMAP placed part of the video wrongly — typically a symmetric object or a repeating
// floor matched to the wrong side. Such a model can still reproject to well under a pixel.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "capture/colmap_model.h"
#include "capture/pose_alignment.h"

namespace npt::capture {

struct PathJump {
    std::string from, to;  // image names, consecutive in name order
    double step = 0;       // distance between their centres
    double ratio = 0;      // step / the median step
};

// Consecutive poses (the caller sorts them by name) whose centres are more than `factor` times the median
// step apart. Empty for fewer than 3 poses.
std::vector<PathJump> find_path_jumps(const std::vector<CameraPose>& poses_sorted_by_name,
                                      double factor = 8.0);

// The same for a COLMAP model's registered images, sorted by name here.
std::vector<PathJump> find_path_jumps(const ColmapModel& model, double factor = 8.0);

// The name-sorted poses cut at every jump of find_path_jumps: [begin, end) index ranges, in order, covering
// all poses. One piece for a continuous path (or fewer than 3 poses); none for no poses.
std::vector<std::pair<size_t, size_t>> continuous_pieces(const std::vector<CameraPose>& poses_sorted_by_name,
                                                         double factor = 8.0);

}  // namespace npt::capture
