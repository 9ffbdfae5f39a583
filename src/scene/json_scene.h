// Our JSON scene format: includes glTF/OBJ files with placements, and sets the camera, environment and render
// settings on top. The format is documented in docs/formats.md.
#pragma once

#include <filesystem>

#include "scene/scene.h"

namespace npt::scene {

// Fills `scene` from a .json scene file; paths inside are relative to it. Throws npt::Error naming the file
// and the field (e.g. "scene.json: camera.look_at: expected an array of 3 numbers"); unknown keys are
// warnings.
void load_json_scene(const std::filesystem::path& path, const LoadOptions& options, Scene& scene);

}  // namespace npt::scene
