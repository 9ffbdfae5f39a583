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

// How a NeRF volume is shaded: Relit scatters the scene's light with its intrinsic fields (relightable models
// only), Emissive adds its trained colour as emission. Auto: Relit exactly when the model is relightable.
enum class VolumeShading : uint8_t { Auto, Relit, Emissive };

// How a NeRF model fills its cube. Box: the crop box (model space) is stretched onto the cube's local box.
// Object: the model's object frame (nerf/object_frame.h) is the cube's local space turned Y up, in object
// units (metres for a capture given --height), and the object's box is the volume: the node transform alone
// places the object, an identity one stands it on y = 0 at the origin. Auto: Object for a model that carries
// an object frame when no crop is given, else Box.
enum class VolumePlacement : uint8_t { Auto, Object, Box };

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
    VolumeShading shading = VolumeShading::Auto;  // "shading": "relit" | "emissive" (NeRF models only)
    VolumePlacement placement = VolumePlacement::Auto;  // "placement": "object" | "box" (NeRF models only)
};

// The shading a volume gets: `desc` for a model that is (or is not) relightable. Throws, naming `where` and the
// field, for "relit" on a model that is not relightable.
bool volume_is_relit(const VolumeDesc& desc, bool relightable, const std::string& where);

// Parses `extras_json` of a VolumeInstance; `where` names it in errors ("scene.gltf: node 'volume'").
VolumeDesc parse_volume_desc(const std::string& extras_json, const std::string& where);

// The NeRF parts of `v` (kind, field, occupancy, march, placement, its local box, shading) for model `m` in a
// cube with local box [local_min, local_max]; v points into m, which must outlive it. Throws, naming `where`,
// for a crop outside the model, "relit" on a model that is not relightable, "placement": "object" on a model
// without an object frame or with a crop.
void fill_nerf_volume(const nerf::NerfModel& m, const VolumeDesc& desc, Vec3 local_min, Vec3 local_max,
                      const std::string& where, VolumeView& v);

class VolumeSet {
  public:
    explicit VolumeSet(const scene::Scene& scene);
    VolumeSet(const scene::Scene&&) = delete;
    Span<const VolumeView> views() const { return {m_views.data(), m_views.size()}; }
    // Moves volume i to `inst`'s placement (an animation frame): what the constructor derives from
    // local_to_world, without reloading the grid or model.
    void set_placement(size_t i, const scene::VolumeInstance& inst);
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
    std::vector<float> m_density_scale;  // the scene's density_scale before any placement-dependent factor
    std::vector<char> m_per_longest_side;  // instant-ngp grids: density per unit of the cube's longest side
};

}  // namespace npt::media
