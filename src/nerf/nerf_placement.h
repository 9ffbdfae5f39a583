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

// The affine map cube-local -> model space, p_model = L p_local + offset. For the box placement below L is the
// axis permutation above with a scale per model axis; for a model that carries its object frame
// (object_frame.h) it is a similarity with a rotation. The inverse of L is kept for normals and offsets.
struct LocalToModel {
    Vec3 row[3] = {Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 0, 0)};      // L, row by row
    Vec3 inv_row[3] = {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, 1, 0)};  // L^-1, row by row
    Vec3 offset;  // model position of local (0, 0, 0)

    NPT_HD NPT_INLINE Vec3 vector(Vec3 local) const {
        return {dot(row[0], local), dot(row[1], local), dot(row[2], local)};
    }
    NPT_HD NPT_INLINE Vec3 point(Vec3 local) const { return offset + vector(local); }
    // L^-1 v: a model-space vector back in local space.
    NPT_HD NPT_INLINE Vec3 inverse_vector(Vec3 model) const {
        return {dot(inv_row[0], model), dot(inv_row[1], model), dot(inv_row[2], model)};
    }
    NPT_HD NPT_INLINE Vec3 inverse_point(Vec3 model) const { return inverse_vector(model - offset); }
    // L^T n: how a model-space normal (a covector) reads in local space.
    NPT_HD NPT_INLINE Vec3 transpose_vector(Vec3 n) const { return row[0] * n.x + row[1] * n.y + row[2] * n.z; }
};

// local_min/local_max: the cube's local box; crop: the part of model space that fills it.
NPT_HD NPT_INLINE LocalToModel local_to_model(Vec3 local_min, Vec3 local_max, const CropBox& crop) {
    const Vec3 lmin = world_axes_to_model(local_min), lmax = world_axes_to_model(local_max);
    const Vec3 scale = (crop.max - crop.min) / (lmax - lmin);
    LocalToModel m;
    // model = scale * (local.y, local.z, local.x) + offset
    m.row[0] = Vec3(0, scale.x, 0);
    m.row[1] = Vec3(0, 0, scale.y);
    m.row[2] = Vec3(scale.z, 0, 0);
    m.inv_row[0] = Vec3(0, 0, 1.0f / scale.z);
    m.inv_row[1] = Vec3(1.0f / scale.x, 0, 0);
    m.inv_row[2] = Vec3(0, 1.0f / scale.y, 0);
    m.offset = crop.min - scale * lmin;
    return m;
}

}  // namespace npt::nerf
