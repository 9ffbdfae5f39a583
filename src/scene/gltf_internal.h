// Shared pieces of the glTF loader (accessors, materials, nodes), private to src/scene: the tinygltf include
// with its warnings silenced, and the context every part reports errors through.
#pragma once

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#include <tiny_gltf.h>
#pragma GCC diagnostic pop

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "scene/scene.h"

namespace npt::scene::gltf {

struct Context {
    const tinygltf::Model& model;
    std::string file;  // the path as given, prefix of every message
};

// Accessor readers: validate the accessor, its buffer view and buffer (bounds, types, counts) before reading.
// `what` says what the accessor is for, e.g. "POSITION of mesh 'floor'".
std::vector<Vec3> read_vec3(const Context& ctx, int accessor, const std::string& what);
std::vector<Vec2> read_texcoords(const Context& ctx, int accessor, const std::string& what);
std::vector<uint32_t> read_indices(const Context& ctx, int accessor, const std::string& what);

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
