#include "capture/camera_rig.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/json_file.h"

namespace npt::capture {
namespace fs = std::filesystem;

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A number from the frame, else from the top level (instant-ngp allows both).
double number_field(const nlohmann::json& frame, const nlohmann::json& root, const char* key,
                    const std::string& where) {
    for (const nlohmann::json* j : {&frame, &root}) {
        const auto it = j->find(key);
        if (it == j->end()) continue;
        if (!it->is_number() || !std::isfinite(it->get<double>()) || it->get<double>() <= 0)
            throw Error(where + ": '" + key + "' must be a positive number");
        return it->get<double>();
    }
    return 0;
}

}  // namespace

RigSummary summarize_rig(const fs::path& json) {
    const std::string file = json.string();
    const nlohmann::json root = read_json_file(json);
    if (!root.is_object() || !root.contains("frames") || !root["frames"].is_array() || root["frames"].empty())
        throw Error(file + ": 'frames': expected a non-empty array");
    RigSummary rig;
    std::vector<double> distances, elevations;
    for (size_t i = 0; i < root["frames"].size(); ++i) {
        const nlohmann::json& fr = root["frames"][i];
        const std::string where = file + ": frames[" + std::to_string(i) + "]";
        const auto m = fr.find("transform_matrix");
        if (m == fr.end() || !m->is_array() || m->size() < 3)
            throw Error(where + ": 'transform_matrix': expected a 4x4 array");
        double p[3];
        for (int r = 0; r < 3; ++r) {
            const nlohmann::json& row = (*m)[size_t(r)];
            if (!row.is_array() || row.size() != 4 || !row[3].is_number())
                throw Error(where + ": 'transform_matrix': expected a 4x4 array of numbers");
            p[r] = row[3].get<double>();
            if (!std::isfinite(p[r])) throw Error(where + ": 'transform_matrix': not finite");
        }
        const double d = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        distances.push_back(d);
        elevations.push_back(d > 0 ? std::asin(std::clamp(p[2] / d, -1.0, 1.0)) * 180.0 / std::numbers::pi
                                   : 0);
        if (i == 0) {
            rig.width = int(number_field(fr, root, "w", where));
            rig.height = int(number_field(fr, root, "h", where));
            if (rig.width <= 0 || rig.height <= 0)
                throw Error(where + ": 'w'/'h': the image size is missing");
            const double fl_x = number_field(fr, root, "fl_x", where);
            const double angle_x = number_field(fr, root, "camera_angle_x", where);
            if (fl_x > 0)
                rig.fov_x_deg = 2.0 * std::atan(0.5 * rig.width / fl_x) * 180.0 / std::numbers::pi;
            else if (angle_x > 0)
                rig.fov_x_deg = angle_x * 180.0 / std::numbers::pi;
            else
                throw Error(where + ": neither 'fl_x' nor 'camera_angle_x' is given");
        }
    }
    rig.cameras = distances.size();
    rig.median_distance = median(distances);
    rig.median_elevation_deg = median(elevations);
    return rig;
}

}  // namespace npt::capture
