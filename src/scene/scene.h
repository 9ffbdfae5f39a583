// The loaded scene, independent of the file format it came from (glTF, OBJ, JSON scene) and of the backend
// that renders it. Geometry is flattened to world space at load time; render/ builds its own device views.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"

namespace npt::scene {

// Every loader checks that world-space data (after all transforms) is finite and within this bound: Embree
// refuses rays whose origin has a component beyond 1.8e18 (its FLT_LARGE), and the default view and ray
// offsets need room beyond the scene. Float positions this large have a spacing of 10^9 anyway.
constexpr float k_max_world_coordinate = 1e16f;

// Linear-light RGBA texels, row 0 at the top of the image (as stored in PNG/EXR), glTF uv (0,0) = top-left.
struct Texture {
    std::string name;  // file path or "<embedded #i>", for messages
    int width = 0;
    int height = 0;
    std::vector<float> rgba;  // width * height * 4
};

// The glTF metallic-roughness model plus the KHR extensions we honour. Texture indices are into
// Scene::textures, -1 when absent. Factors multiply the texture value, as in glTF.
struct Material {
    std::string name;
    Rgb base_color{1.0f};
    int base_color_texture = -1;     // sRGB-decoded at load
    float metallic = 1.0f;
    float roughness = 1.0f;
    int metallic_roughness_texture = -1;  // G = roughness, B = metallic (glTF)
    int normal_texture = -1;
    float normal_scale = 1.0f;
    Rgb emission{0.0f};              // emissiveFactor x KHR_materials_emissive_strength
    int emissive_texture = -1;       // sRGB-decoded at load
    float specular = 1.0f;           // KHR_materials_specular specularFactor; 0 means pure Lambert
    Rgb specular_color{1.0f};        // KHR_materials_specular specularColorFactor
    float transmission = 0.0f;       // KHR_materials_transmission
    float ior = 1.5f;                // KHR_materials_ior
    bool double_sided = false;
    bool is_volume = false;          // named "volume": a NeRF placeholder, never drawn as a surface
};

// A triangle mesh in world space. normals/uvs are either empty or one per position.
struct Mesh {
    std::string name;  // node name (or mesh name) for messages and `info`
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<Vec2> uvs;
    std::vector<uint32_t> indices;  // 3 per triangle, all < positions.size()
    int material = 0;
    size_t triangle_count() const { return indices.size() / 3; }
};

enum class PunctualType { Point, Spot, Directional };

// KHR_lights_punctual: intensity in candela (point/spot) or lux (directional), already multiplied into `intensity`.
struct PunctualLight {
    std::string name;
    PunctualType type = PunctualType::Point;
    Vec3 position;
    Vec3 direction{0, 0, -1};  // the direction light travels (world), for spot and directional
    Rgb intensity{1.0f};       // colour x intensity
    float inner_cone = 0.0f;   // radians
    float outer_cone = 0.7853981634f;
};

// Light arriving from infinity: a constant colour, or an equirectangular map times a strength.
// Direction convention of the map: see docs/formats.md (+Y up; u = 0.5 + atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi).
struct Environment {
    Rgb color{0.0f};
    int texture = -1;
    float strength = 1.0f;
    float rotation_y = 0.0f;  // radians about +Y
    bool is_black() const { return texture < 0 && color.x == 0 && color.y == 0 && color.z == 0; }
};

struct Camera {
    std::string name;
    Vec3 position;
    Vec3 right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};  // world axes of the camera, orthonormal
    float yfov = 0.6911112f;                              // vertical field of view, radians
    float aspect = 0.0f;                                  // 0: width / height of the image
};

// A cube whose material is named `volume`: where a NeRF or grid volume sits. Not rendered as a surface.
struct VolumeInstance {
    std::string name;        // node name
    Mat4 local_to_world;     // maps the cube's local box onto the world
    Vec3 local_min{-1.0f}, local_max{1.0f};  // the cube mesh's own bounds in local space
    std::string extras_json; // the node's `extras` (the volume's file, scales); empty if none
    std::filesystem::path declared_in;  // the file that declared it: messages, and relative grid paths
};

// Render settings a scene file may carry; the command line overrides them.
struct RenderSettings {
    int width = 640;
    int height = 480;
    int spp = 64;
    int max_depth = 16;
    uint64_t seed = 0;
    bool transparent = false;  // Film > Transparent: RGBA without the background (`nerfpt render --transparent`)
    double fps = 24.0;         // frames per second of a sequence (scene extras "fps"; `--fps` overrides)
};

struct SceneAnimation;  // scene/animation.h

struct Scene {
    std::filesystem::path source;
    std::vector<Mesh> meshes;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<PunctualLight> lights;
    Environment environment;
    std::vector<Camera> cameras;
    int camera = -1;  // index into cameras; -1: none (a default view is made)
    std::vector<VolumeInstance> volumes;
    RenderSettings settings;
    // Every scene file read (the scene, included files, MTL files, glTF buffers; textures are in `textures`,
    // grids in `volumes`), so that a command can refuse to write over one of them.
    std::vector<std::filesystem::path> files;
    // The animation the scene moves by (scene/animation.h: pose_scene), null when the file has none. Shared so
    // that a Scene stays copyable; a copy that is posed changes the other's bindings' state, not its objects.
    std::shared_ptr<SceneAnimation> animation;

    size_t triangle_count() const;
};

struct LoadOptions {
    std::string camera_name;     // empty: the first camera
    std::string animation_name;  // empty: the file's first animation (glTF `animations[].name`)
};

// Loads .gltf, .glb, .obj or .json (our scene format) by extension. Throws npt::Error naming file and field.
Scene load_scene(const std::filesystem::path& path, const LoadOptions& options = {});

}  // namespace npt::scene
