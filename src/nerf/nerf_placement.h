// Where a NeRF sits in a scene: the model's crop box (in model space, instant-ngp's coordinates) is mapped onto
// the `volume` cube's local box, axis by axis in the orientation of the TRAINING WORLD (the transforms.json
// cameras' space). Model space is that world with its axes cycled (model x, y, z = world y, z, x, see
// ngp_world_to_model), so local x runs along world x = model z, local y along model x, local z along model y:
// a NeRF-synthetic object (Z up in its world) stands along the cube's local +Z. Rotate the node (e.g. -90
// degrees about X in a Y-up glTF scene) to stand it up. The baked grids (nerfpt bake) use the same map.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct CropBox {
    Vec3 min{0.0f, 0.0f, 0.0f};  // model space
    Vec3 max{1.0f, 1.0f, 1.0f};
};

// Model space <-> training-world axis order (a permutation, no scaling).
NPT_HD NPT_INLINE Vec3 model_to_world_axes(Vec3 m) { return {m.z, m.x, m.y}; }
NPT_HD NPT_INLINE Vec3 world_axes_to_model(Vec3 w) { return {w.y, w.z, w.x}; }

// The affine map cube-local -> model space: p_model = offset + scale * P(p_local), with P the axis
// permutation above and scale per model axis.
struct LocalToModel {
    Vec3 scale;   // model units per local unit, per MODEL axis
    Vec3 offset;  // model position of local (0, 0, 0)

    NPT_HD NPT_INLINE Vec3 point(Vec3 local) const { return offset + scale * world_axes_to_model(local); }
    NPT_HD NPT_INLINE Vec3 vector(Vec3 local) const { return scale * world_axes_to_model(local); }
    NPT_HD NPT_INLINE Vec3 inverse_point(Vec3 model) const {
        return model_to_world_axes((model - offset) / scale);
    }
};

// local_min/local_max: the cube's local box; crop: the part of model space that fills it.
NPT_HD NPT_INLINE LocalToModel local_to_model(Vec3 local_min, Vec3 local_max, const CropBox& crop) {
    const Vec3 lmin = world_axes_to_model(local_min), lmax = world_axes_to_model(local_max);
    LocalToModel m;
    m.scale = (crop.max - crop.min) / (lmax - lmin);
    m.offset = crop.min - m.scale * lmin;
    return m;
}

}  // namespace npt::nerf
