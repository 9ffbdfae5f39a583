#include "capture/revisit_pairs.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace npt::capture {

std::vector<std::pair<std::string, std::string>> revisit_pairs(const std::vector<CameraPose>& poses,
                                                               const RevisitSettings& s) {
    std::vector<std::pair<std::string, std::string>> pairs;
    const size_t n = poses.size();
    const size_t overlap = size_t(std::max(0, s.overlap));
    if (n < overlap + 2 || s.max_per_frame <= 0) return pairs;
    std::vector<double> steps(n - 1);
    for (size_t i = 0; i + 1 < n; ++i) steps[i] = (poses[i + 1].centre - poses[i].centre).norm();
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    const double max_distance = s.max_distance_steps * steps[steps.size() / 2];
    if (!(max_distance > 0)) return pairs;
    const double min_cos = std::cos(s.max_angle_deg * M_PI / 180.0);
    // OpenGL camera-to-world: the camera looks down its -Z.
    const auto view = [&](size_t i) -> Eigen::Vector3d { return -poses[i].rotation.col(2); };
    std::set<std::pair<size_t, size_t>> chosen;
    for (size_t i = 0; i < n; ++i) {
        std::vector<std::pair<double, size_t>> near;  // distance, partner
        for (size_t j = 0; j < n; ++j) {
            if ((i > j ? i - j : j - i) <= overlap) continue;
            const double d = (poses[j].centre - poses[i].centre).norm();
            if (d <= max_distance && view(i).dot(view(j)) >= min_cos) near.emplace_back(d, j);
        }
        std::sort(near.begin(), near.end());
        if (near.size() > size_t(s.max_per_frame)) near.resize(size_t(s.max_per_frame));
        for (const auto& [d, j] : near) chosen.emplace(std::min(i, j), std::max(i, j));
    }
    for (const auto& [a, b] : chosen) pairs.emplace_back(poses[a].name, poses[b].name);
    return pairs;
}

}  // namespace npt::capture
