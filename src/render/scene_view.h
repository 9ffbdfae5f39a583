// The scene as the per-sample code sees it: plain structs of spans, the same on the CPU and (copied to device
// memory) on the GPU. Built from a scene::Scene by SceneData (scene_data.h), which owns the arrays.
#pragma once

#include "core/platform.h"
#include "core/texture.h"
#include "core/vec.h"
#include "lights/light.h"
#include "media/volume.h"

namespace npt::render {

struct MaterialView {
    Rgb base_color{1.0f};
    int32_t base_color_texture = -1;
    float metallic = 1.0f;
    float roughness = 1.0f;
    int32_t metallic_roughness_texture = -1;
    int32_t normal_texture = -1;
    float normal_scale = 1.0f;
    Rgb emission{0.0f};
    int32_t emissive_texture = -1;
    float specular = 1.0f;
    Rgb specular_color{1.0f};
    float transmission = 0.0f;
    float ior = 1.5f;
    bool double_sided = false;
    NPT_HD bool emits() const { return emission.x > 0.0f || emission.y > 0.0f || emission.z > 0.0f; }
};

struct MeshView {
    const Vec3* positions = nullptr;
    const Vec3* normals = nullptr;  // null: flat shading with the geometric normal
    const Vec2* uvs = nullptr;      // null: uv = barycentrics
    const uint32_t* indices = nullptr;
    uint32_t triangle_count = 0;
    uint32_t material = 0;
};

// Pinhole camera with a box pixel filter (see docs/formats.md for the exact pixel footprint).
struct CameraView {
    Vec3 position;
    Vec3 right, up, forward;
    float tan_half_fov_y = 0.36397f;
    float aspect = 1.0f;  // width / height of the image plane
    int width = 1, height = 1;
};

struct SceneView {
    Span<const MeshView> meshes;
    Span<const MaterialView> materials;
    Span<const TextureView> textures;
    lights::LightSetView lights;
    Span<const media::VolumeView> volumes;  // the `volume` cubes: emission-absorption, never surfaces
    CameraView camera;
};

}  // namespace npt::render
