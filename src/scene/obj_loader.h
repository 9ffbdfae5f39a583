// Wavefront OBJ + MTL loader (tinyobjloader): one world-space mesh per shape and material, MTL parameters
// mapped onto our glTF-style material (see docs/formats.md for the mapping).
#pragma once

#include <filesystem>

#include "core/transform.h"
#include "scene/scene.h"

namespace npt::scene {

// Appends the OBJ's meshes, materials and textures to `scene`, placed by `placement`. A missing MTL file is a
// warning (the default white Lambert material is used); a missing OBJ or a texture that cannot be read is an
// error.
void load_obj(const std::filesystem::path& path, Scene& scene, const Mat4& placement = Mat4::identity());

}  // namespace npt::scene
