// What the viewer changes in a loaded scene: a volume's placement (translation, rotation, scale of its node) and
// fill (density and emission scale, crop box, shading), punctual lights' intensity, the viewer's camera. Plain
// C++ over scene::Scene (no Boost); the render worker (viewer.h) applies these, scene_save.h writes them back.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/transform.h"
#include "scene/scene.h"
#include "serve/protocol.h"

namespace npt::serve {

// A node's transform as translation, rotation (unit quaternion x y z w) and scale. From a matrix with shear
// the nearest rotation is taken (the shear is lost); a mirroring matrix gets a negative x scale.
struct Trs {
    V3 translation{0, 0, 0};
    V4 rotation{0, 0, 0, 1};
    V3 scale{1, 1, 1};
    Mat4 matrix() const;
};
Trs decompose(const Mat4& m);

// The camera a CameraMsg describes (orthonormalised; fov vertical).
scene::Camera camera_from_message(const CameraMsg& m);

// Moves volume `v` to `trs` (its local_to_world = T R S). Throws npt::Error (the volume left as it was) when the
// placement leaves the world bounds.
void place_volume(scene::VolumeInstance& v, const Trs& trs);

// Rewrites the fill fields of `v`'s extras ("volume": density_scale, emission_scale, crop, shading) from `m`.
// Returns true when something changed (the volume must be reloaded).
bool edit_volume_fill(scene::VolumeInstance& v, const VolumeMsg& m);

// The `volume` object of v's extras (empty object when none).
nlohmann::json volume_extras(const scene::VolumeInstance& v);

// The scene as the page sees it: cameras (of the file), volumes (placement, local box, fill, whether a NeRF),
// punctual lights. `light_scales` has one entry per scene light.
nlohmann::json describe_scene(const scene::Scene& scene, size_t file_cameras, const std::vector<double>& light_scales);

nlohmann::json describe_camera(const scene::Camera& c);

}  // namespace npt::serve
