// The scene `nerfpt serve` shows a model in when it is given a model alone (MODEL.npt, or a capture's
// folder): MODEL.serve.json beside it, the model in a volume cube and a camera that frames it. Made once and
// kept: the viewer's saves go there, and `nerfpt render` renders it.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/image.h"
#include "nerf/nerf_model.h"
#include "nerf/object_frame.h"

namespace npt::serve {

struct ModelSceneOptions {
    // The object frame the model carries (a capture's): the volume then stands the object upright on y = 0 at
    // its real size ("placement": "object"), and the camera frames its box, Y up. Without it, the model's box
    // in a [-1, 1] cube, Z up, seen from (0, -4, 2).
    std::optional<nerf::ObjectFrame> object;
    double elevation_deg =
        20;  // the camera's height above the object's base plane, seen from its box's centre
    // The scene's sky ("environment": {"file": ...}, relative to the scene); empty: none. A relightable model is
    // given its capture environment (capture_sky below), so that its default "relit" shading shows it lit as it
    // was filmed instead of black.
    std::string environment_file;
};

// A relightable model's capture environment (nerf/relight: equirectangular in model-space directions) as the
// sky of the scene model_scene_json makes: an equirectangular linear RGB image in the scene's convention (+Y up,
// lights/environment.h), each texel's world direction taken through the volume's placement (the default cube,
// identity node) into model space. Throws npt::Error for a model that is not relightable.
Image capture_sky(const nerf::NerfModel& model, int width = 128, int height = 64);

// MODEL.capture_sky.exr beside `model` for a relightable model (written atomically when missing), else "": the
// name to put in ModelSceneOptions::environment_file.
std::string write_capture_sky(const std::filesystem::path& model_path, const nerf::NerfModel& model);

// The JSON scene (docs/formats.md, "JSON scenes") holding `model_file` (relative to the scene).
nlohmann::json model_scene_json(const std::string& model_file, const ModelSceneOptions& options);

// MODEL.serve.json beside `model`: where scene_for_model keeps the scene.
std::filesystem::path model_scene_path(const std::filesystem::path& model);

// MODEL.serve.json beside `model`: kept when it exists, else written (atomically) from model_scene_json.
std::filesystem::path scene_for_model(const std::filesystem::path& model, const ModelSceneOptions& options);

}  // namespace npt::serve
