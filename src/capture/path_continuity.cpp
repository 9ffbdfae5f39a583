#include "capture/path_continuity.h"

#include <algorithm>

#include "capture/pose_alignment.h"

namespace npt::capture {

std::vector<PathJump> find_path_jumps(const ColmapModel& model, double factor) {
    std::vector<CameraPose> poses = colmap_poses(model);
    std::sort(poses.begin(), poses.end(), [](const CameraPose& a, const CameraPose& b) { return a.name < b.name; });
    std::vector<PathJump> jumps;
    if (poses.size() < 3) return jumps;
    std::vector<double> steps(poses.size() - 1);
    for (size_t i = 0; i + 1 < poses.size(); ++i) steps[i] = (poses[i + 1].centre - poses[i].centre).norm();
    std::vector<double> sorted = steps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    if (median <= 0) return jumps;
    for (size_t i = 0; i < steps.size(); ++i)
        if (steps[i] > factor * median) jumps.push_back({poses[i].name, poses[i + 1].name, steps[i], steps[i] / median});
    return jumps;
}

}  // namespace npt::capture
