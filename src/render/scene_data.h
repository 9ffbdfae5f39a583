// Host-side owner of everything a SceneView points into: mesh views over the loaded scene's arrays, material
// and texture views, the light set and the camera. The scene::Scene must outlive it.
#pragma once

#include <memory>
#include <vector>

#include "lights/light_set.h"
#include "media/volume_set.h"
#include "render/scene_view.h"
#include "scene/animation.h"
#include "scene/scene.h"

namespace npt::render {

class SceneData {
  public:
    SceneData(const scene::Scene& scene, int width, int height);
    const SceneView& view() const { return m_view; }
    // After scene::pose_scene moved `scene` (the one constructed from): the moved meshes' views, the volumes'
    // placements, the lights and the camera rebuilt from the posed scene, so that the view is the one a
    // SceneData constructed from the posed scene would hold. Volumes' grids and models are not reloaded.
    void update(const scene::Scene& scene, const scene::PoseChanges& changes);

  private:
    std::vector<MeshView> m_meshes;
    std::vector<MaterialView> m_materials;
    std::vector<TextureView> m_textures;
    std::unique_ptr<lights::LightSet> m_lights;
    std::unique_ptr<media::VolumeSet> m_volumes;
    SceneView m_view;
    int m_width = 0, m_height = 0;
};

// The camera the scene selected, or a default view of the whole scene when it has none.
CameraView make_camera_view(const scene::Scene& scene, int width, int height);

}  // namespace npt::render
