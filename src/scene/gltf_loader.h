// glTF 2.0 (.gltf, .glb) loader: flattens the default scene's node hierarchy into world-space meshes,
// materials, textures, punctual lights, cameras and NeRF volume placeholders (material named `volume`).
#pragma once

#include <filesystem>

#include "core/transform.h"
#include "scene/scene.h"

namespace npt::scene {

// Appends the contents of a glTF file to `scene` (material and texture indices are offset accordingly),
// placing it with `placement` on top of its own node transforms. Cameras are appended; when
// `options.camera_name` is set the matching camera (node or camera name) becomes scene.camera, else the
// file's first camera does if the scene has none yet. The scene's `extras` set scene.settings and
// scene.environment.color.
void load_gltf(const std::filesystem::path& path, const LoadOptions& options, Scene& scene,
               const Mat4& placement = Mat4::identity());

}  // namespace npt::scene
