#include "serve/model_scene.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/temp_file.h"

namespace npt::serve {
namespace fs = std::filesystem;

namespace {

constexpr double k_yfov_deg = 40;
constexpr double k_pi = 3.14159265358979323846;

}  // namespace

nlohmann::json model_scene_json(const std::string& model_file, const ModelSceneOptions& options) {
    nlohmann::json camera = {
        {"position", {0.0, -4.0, 2.0}}, {"look_at", {0, 0, 0}}, {"up", {0, 0, 1}}, {"yfov_deg", k_yfov_deg}};
    if (options.object) {
        // The cube's local space is the object frame turned Y up (nerf/object_frame.h): the box's bounding
        // sphere fills the view's height, seen from the side at the given elevation.
        Vec3 lo, hi;
        nerf::object_local_box(*options.object, &lo, &hi);
        const Vec3 c = (lo + hi) * 0.5f;
        const double radius = 0.5 * double(length(hi - lo));
        const double distance = 1.1 * radius / std::sin(0.5 * k_yfov_deg * k_pi / 180);
        const double e = std::clamp(options.elevation_deg, -80.0, 80.0) * k_pi / 180;
        camera["position"] = {double(c.x), double(c.y) + distance * std::sin(e),
                              double(c.z) + distance * std::cos(e)};
        camera["look_at"] = {double(c.x), double(c.y), double(c.z)};
        camera["up"] = {0, 1, 0};
    }
    return {{"volumes", {{{"name", "model"}, {"file", model_file}}}},
            {"camera", std::move(camera)},
            {"render", {{"width", 640}, {"height", 480}, {"spp", 64}, {"max_depth", 4}}}};
}

fs::path scene_for_model(const fs::path& model, const ModelSceneOptions& options) {
    fs::path scene = model;
    scene.replace_extension(".serve.json");
    std::error_code ec;
    if (fs::exists(scene, ec)) return scene;
    write_text_atomic(scene, model_scene_json(model.filename().string(), options).dump(2) + "\n");
    spdlog::info("wrote {}: the model in a volume cube{} (edit it in the viewer; nerfpt render renders it)",
                 scene.string(), options.object ? ", the object upright on y = 0" : "");
    return scene;
}

}  // namespace npt::serve
