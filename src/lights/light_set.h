// Host-side builder of the light set: collects punctual lights, emissive triangles and the environment from a
// loaded scene, computes their powers for selection and owns the arrays that LightSetView points into.
#pragma once

#include <vector>

#include "core/alias_table.h"
#include "core/distribution_2d.h"
#include "lights/light.h"
#include "scene/scene.h"

namespace npt::lights {

class LightSet {
  public:
    // The view points into the scene's texture texels (not copied: environment maps are large), so the scene
    // must outlive the LightSet; a temporary scene is refused at compile time.
    explicit LightSet(const scene::Scene& scene);
    explicit LightSet(const scene::Scene&& scene) = delete;
    LightSet(const LightSet&) = delete;  // the view holds pointers into this object's vectors
    LightSet& operator=(const LightSet&) = delete;

    LightSetView view() const;
    size_t size() const { return m_lights.size(); }  // number of lights, each emissive triangle counted
    size_t emissive_triangles() const { return m_emissive_triangles; }
    float scene_radius() const { return m_scene_radius; }  // of the bounding sphere used for distant lights
    // Selection weight (power, luminance) of each light, as given to the alias table; for tests and `info`.
    const std::vector<double>& powers() const { return m_powers; }

  private:
    std::vector<Light> m_lights;
    std::vector<double> m_powers;
    AliasTable m_selector;
    std::vector<int32_t> m_mesh_light_offset;
    std::vector<TextureView> m_textures;
    Distribution2D m_env_distribution;
    EnvironmentView m_environment;
    int32_t m_environment_light = -1;
    size_t m_emissive_triangles = 0;
    float m_scene_radius = 0.0f;
};

}  // namespace npt::lights
