#include "serve/model_scene.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "core/temp_file.h"
#include "lights/environment.h"
#include "media/volume_set.h"
#include "nerf/relight/relight_env.h"

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
    nlohmann::json scene = {{"volumes", {{{"name", "model"}, {"file", model_file}}}},
                            {"camera", std::move(camera)},
                            {"render", {{"width", 640}, {"height", 480}, {"spp", 64}, {"max_depth", 4}}}};
    if (!options.environment_file.empty()) scene["environment"] = {{"file", options.environment_file}};
    return scene;
}

Image capture_sky(const nerf::NerfModel& model, int width, int height) {
    if (!model.relightable()) throw Error("capture_sky: the model is not relightable");
    const nerf::CaptureEnvironment& env = model.relight->capture_env;
    if (env.width < 1 || env.height < 1 || env.texels.size() != size_t(env.width) * size_t(env.height))
        throw Error("capture_sky: the model's capture environment is empty");
    // The placement the scene gives the volume: model_scene_json's cube ([-1, 1]^3, identity node, the default
    // placement), so a world direction is a local one.
    media::VolumeView view;
    media::fill_nerf_volume(model, media::VolumeDesc{}, Vec3(-1.0f), Vec3(1.0f), "capture sky", view);
    const nerf::LocalToModel& to_model = view.nerf.local_to_model;
    Image sky(width, height, 3);
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            float sin_theta;
            const Vec3 world = lights::equirect_direction(
                Vec2((float(i) + 0.5f) / float(width), (float(j) + 0.5f) / float(height)), &sin_theta);
            const nerf::EnvTaps taps = nerf::env_taps(env.width, env.height, normalize(to_model.vector(world)));
            Rgb radiance(0.0f);
            for (int k = 0; k < 4; ++k) radiance += env.texels[size_t(taps.index[k])] * taps.weight[k];
            float* px = sky.at(i, j);
            px[0] = radiance.x;
            px[1] = radiance.y;
            px[2] = radiance.z;
        }
    return sky;
}

std::string write_capture_sky(const fs::path& model_path, const nerf::NerfModel& model) {
    if (!model.relightable()) return {};
    fs::path sky = model_path;
    sky.replace_extension(".capture_sky.exr");
    std::error_code ec;
    if (!fs::exists(sky, ec)) {
        const fs::path tmp = sky.string() + ".tmp.exr";
        write_exr(tmp, capture_sky(model));
        fs::rename(tmp, sky);
        spdlog::info("wrote {}: the model's capture environment as the scene's sky (its relit shading then shows "
                     "the object lit as it was filmed)",
                     sky.string());
    }
    return sky.filename().string();
}

fs::path model_scene_path(const fs::path& model) {
    fs::path scene = model;
    scene.replace_extension(".serve.json");
    return scene;
}

fs::path scene_for_model(const fs::path& model, const ModelSceneOptions& options) {
    const fs::path scene = model_scene_path(model);
    std::error_code ec;
    if (fs::exists(scene, ec)) return scene;
    write_text_atomic(scene, model_scene_json(model.filename().string(), options).dump(2) + "\n");
    spdlog::info("wrote {}: the model in a volume cube{}{} (edit it in the viewer; nerfpt render renders it)",
                 scene.string(), options.object ? ", the object upright on y = 0" : "",
                 options.environment_file.empty() ? "" : ", under its capture sky");
    return scene;
}

}  // namespace npt::serve
