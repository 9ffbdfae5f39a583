// Host-side owner of the scene's volumes: reads each `volume` cube's extras, loads its grid, builds the
// majorant grid, and exposes the VolumeView array the integrator reads. The scene must outlive it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/platform.h"
#include "media/majorant.h"
#include "media/placement.h"
#include "media/volume.h"
#include "media/volume_grid.h"
#include "nerf/nerf_model.h"
#include "scene/scene.h"

namespace npt::media {

// What a scene says about one volume (glTF node extras `{"volume": {...}}`, or the JSON scene's volume
// entry).
struct VolumeDesc {
    std::string file;            // resolved against the scene file's folder
    float density_scale = 1.0f;  // sigma per world unit = density_scale * density
    float emission_scale = 1.0f;
    bool casts_shadows = true;
    float step_voxels = 0.25f;  // ray-marching step in voxels along the ray
    // NeRF models only: the part of model space that fills the cube (default: the model's whole aabb).
    bool has_crop = false;
    nerf::CropBox crop;
};

// Parses `extras_json` of a VolumeInstance; `where` names it in errors ("scene.gltf: node 'volume'").
VolumeDesc parse_volume_desc(const std::string& extras_json, const std::string& where);

class VolumeSet {
  public:
    explicit VolumeSet(const scene::Scene& scene);
    VolumeSet(const scene::Scene&&) = delete;
    Span<const VolumeView> views() const { return {m_views.data(), m_views.size()}; }
    size_t size() const { return m_views.size(); }

  private:
    struct Owned {
        VolumeGrid grid;
        std::vector<float> majorant;
        int mx = 0, my = 0, mz = 0;
        std::unique_ptr<nerf::NerfModel> model;  // a `.npt` file: queried directly
    };
    std::vector<Owned> m_owned;
    std::vector<VolumeView> m_views;
};

}  // namespace npt::media
