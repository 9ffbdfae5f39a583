// One volume in the scene, as the per-sample code sees it: where its cube sits (world -> local), the field in
// it (a grid), how the field's values become extinction and emission, and a coarse majorant grid for skipping
// empty space. Built on the host by VolumeSet (volume_set.h).
#pragma once

#include "core/platform.h"
#include "core/vec.h"
#include "media/grid.h"
#include "nerf/nerf_field.h"
#include "nerf/nerf_placement.h"
#include "nerf/occupancy_view.h"
#include "nerf/relight/intrinsic_field.h"
#include "nerf/ray_march.h"

namespace npt::media {

// Maximum density over blocks of k_majorant_block^3 voxels, covering the trilinear support of the field: cell
// c along an axis covers continuous index coordinates [-1 + B c, -1 + B (c + 1)), where the field depends on
// voxels B c - 1 .. B c + B. A cell whose maximum is 0 holds no medium and is skipped.
constexpr int k_majorant_block = 8;

struct MajorantView {
    int nx = 0, ny = 0, nz = 0;
    const float* max_density = nullptr;  // nx * ny * nz, x fastest
    NPT_HD float at(int i, int j, int k) const {
        return max_density[(size_t(k) * size_t(ny) + size_t(j)) * size_t(nx) + size_t(i)];
    }
};

// A NeRF model queried directly (a `.npt` file in the cube): the field, its occupancy grid for skipping empty
// space, and the map from the cube's local space into model space (nerf_placement.h).
struct NerfVolumeView {
    nerf::NerfFieldView field;
    nerf::OccupancyGridView occupancy;
    nerf::MarchParams march;  // aabb = the crop box in model space
    nerf::LocalToModel local_to_model;
    // Shading "relit" (relit_free_flight.h): the model scatters the scene's light with the BSDF of its
    // intrinsic fields instead of emitting its colour; `intrinsic` is valid exactly then.
    bool relit = false;
    nerf::IntrinsicFieldView intrinsic;
};

enum class VolumeKind : uint8_t { Grid, Nerf };

struct VolumeView {
    VolumeKind kind = VolumeKind::Grid;
    NerfVolumeView nerf;  // kind == Nerf
    Affine3 world_to_local;                  // inverse of the node's transform
    Vec3 local_min{-1.0f}, local_max{1.0f};  // the cube in local space
    GridView grid;          // kind == Grid
    MajorantView majorant;  // kind == Grid
    float density_scale = 1.0f;   // grid: sigma per WORLD unit = density_scale * density; NeRF: multiplies sigma
    float emission_scale = 1.0f;  // c = emission_scale * color
    float step_voxels = 0.25f;    // march step as a fraction of a voxel along the ray
    bool casts_shadows = true;
};

}  // namespace npt::media
