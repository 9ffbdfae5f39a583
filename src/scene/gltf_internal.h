// Shared pieces of the glTF loader (accessors, materials, nodes), private to src/scene: the tinygltf include
// with its warnings silenced, and the context every part reports errors through.
#pragma once

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#include <tiny_gltf.h>
#pragma GCC diagnostic pop

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "scene/animation.h"
#include "scene/scene.h"

namespace npt::scene::gltf {

struct Context {
    const tinygltf::Model& model;
    std::string file;  // the path as given, prefix of every message
    mutable std::set<std::string> clamped;  // fields already warned about (one warning per field and file)
};

// Clamps `value` into [lo, hi] (the glTF spec's range for `field`, e.g.
// "pbrMetallicRoughness.roughnessFactor"), warning once per field and file when it had to: Blender's rule for
// factors the spec bounds.
float clamp_field(const Context& ctx, float value, float lo, float hi, const std::string& field,
                  const std::string& owner);
Rgb clamp_field(const Context& ctx, Rgb value, float lo, float hi, const std::string& field,
                const std::string& owner);

// Checks the glTF JSON document against the parts of the glTF 2.0 schema and of the KHR extensions we read
// (types, required fields, indices that exist, the spec's value ranges); throws npt::Error naming the file
// and the field's path, e.g. "scene.gltf: meshes[0].primitives: expected an array of objects, got an
// integer".
void check_schema(const nlohmann::json& doc, const std::string& file);

// Accessor readers: validate the accessor, its buffer view and buffer (bounds, types, counts) before reading.
// `what` says what the accessor is for, e.g. "POSITION of mesh 'floor'".
std::vector<Vec3> read_vec3(const Context& ctx, int accessor, const std::string& what);
std::vector<Vec2> read_texcoords(const Context& ctx, int accessor, const std::string& what);
std::vector<uint32_t> read_indices(const Context& ctx, int accessor, const std::string& what);
// FLOAT components of an accessor of `type` (TINYGLTF_TYPE_SCALAR, _VEC3, _VEC4), flattened, as doubles.
std::vector<double> read_floats(const Context& ctx, int accessor, int type, const std::string& what);

// The file's node hierarchy at rest (TRS or matrix, parents from `children`), for animation.
std::vector<AnimationNode> rest_nodes(const Context& ctx);
// Checks every animation of the file and puts the one called `name` (empty: the first) in `out`, every
// animation's name in `names`. False when the file has none (an error when `name` was given).
bool read_animation(const Context& ctx, const std::string& name, Animation& out, std::vector<std::string>& names);

// Converts every glTF material (and the textures it uses) into scene.materials / scene.textures, at a fixed
// offset. One decoded texture per glTF image and colour space.
class MaterialTable {
  public:
    MaterialTable(const Context& ctx, Scene& scene);
    int material(int gltf_index);  // scene index; -1 gives the glTF default material, added on first use

  private:
    int texture(int gltf_texture, bool srgb, const std::string& material, const char* slot);

    const Context& m_ctx;
    Scene& m_scene;
    int m_offset = 0;
    int m_default = -1;
    std::map<std::pair<int, bool>, int> m_textures;  // (glTF image, sRGB) -> scene texture
};

}  // namespace npt::scene::gltf
