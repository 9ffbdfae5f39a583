#include "capture/path_continuity.h"

#include <algorithm>

namespace npt::capture {
namespace {

// Indices i whose step to i + 1 is a jump, with the median step (0 when there is no verdict).
std::vector<size_t> jump_indices(const std::vector<CameraPose>& poses, double factor, double& median) {
    median = 0;
    std::vector<size_t> jumps;
    if (poses.size() < 3) return jumps;
    std::vector<double> steps(poses.size() - 1);
    for (size_t i = 0; i + 1 < poses.size(); ++i) steps[i] = (poses[i + 1].centre - poses[i].centre).norm();
    std::vector<double> sorted = steps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    median = sorted[sorted.size() / 2];
    if (median <= 0) return jumps;
    for (size_t i = 0; i < steps.size(); ++i)
        if (steps[i] > factor * median) jumps.push_back(i);
    return jumps;
}

}  // namespace

std::vector<PathJump> find_path_jumps(const std::vector<CameraPose>& poses, double factor) {
    double median = 0;
    std::vector<PathJump> jumps;
    for (size_t i : jump_indices(poses, factor, median)) {
        const double step = (poses[i + 1].centre - poses[i].centre).norm();
        jumps.push_back({poses[i].name, poses[i + 1].name, step, step / median});
    }
    return jumps;
}

std::vector<PathJump> find_path_jumps(const ColmapModel& model, double factor) {
    std::vector<CameraPose> poses = colmap_poses(model);
    std::sort(poses.begin(), poses.end(),
              [](const CameraPose& a, const CameraPose& b) { return a.name < b.name; });
    return find_path_jumps(poses, factor);
}

std::vector<std::pair<size_t, size_t>> continuous_pieces(const std::vector<CameraPose>& poses,
                                                         double factor) {
    std::vector<std::pair<size_t, size_t>> pieces;
    if (poses.empty()) return pieces;
    double median = 0;
    size_t begin = 0;
    for (size_t i : jump_indices(poses, factor, median)) {
        pieces.emplace_back(begin, i + 1);
        begin = i + 1;
    }
    pieces.emplace_back(begin, poses.size());
    return pieces;
}

}  // namespace npt::capture
