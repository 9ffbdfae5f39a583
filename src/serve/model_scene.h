// The scene `nerfpt serve` shows a model in when it is given a model alone (MODEL.npt, or a capture's
// folder): MODEL.serve.json beside it, the model in a volume cube and a camera that frames it. Made once and
// kept: the viewer's saves go there, and `nerfpt render` renders it.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "nerf/object_frame.h"

namespace npt::serve {

struct ModelSceneOptions {
    // The object frame the model carries (a capture's): the volume then stands the object upright on y = 0 at
    // its real size ("placement": "object"), and the camera frames its box, Y up. Without it, the model's box
    // in a [-1, 1] cube, Z up, seen from (0, -4, 2).
    std::optional<nerf::ObjectFrame> object;
    double elevation_deg =
        20;  // the camera's height above the object's base plane, seen from its box's centre
};

// The JSON scene (docs/formats.md, "JSON scenes") holding `model_file` (relative to the scene).
nlohmann::json model_scene_json(const std::string& model_file, const ModelSceneOptions& options);

// MODEL.serve.json beside `model`: kept when it exists, else written (atomically) from model_scene_json.
std::filesystem::path scene_for_model(const std::filesystem::path& model, const ModelSceneOptions& options);

}  // namespace npt::serve
