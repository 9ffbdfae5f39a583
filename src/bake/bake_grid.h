// A trained NeRF sampled onto a voxel grid (nerfpt bake): σ and colour at voxel centres over a crop box,
// sparse (only voxels the occupancy grid marks occupied and whose σ passes a threshold), laid out in the
// volume cube's local axes exactly as nerf/nerf_placement.h maps a crop box onto the cube. The writers
// (grid_writers.h) turn it into .vdb, .nvdb or an instant-ngp raw grid.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/vec.h"
#include "nerf/nerf_model.h"
#include "nerf/nerf_placement.h"

namespace npt::bake {

// The cube's local box the crop is mapped onto (an unscaled volume node's mesh, docs/formats.md).
constexpr float k_local_min = -1.0f, k_local_max = 1.0f;
// Largest grid (voxels, dense count) we scan; beyond this the per-slab masks and int32 coordinates are not
// worth supporting (a 1290^3 grid, far above what the renderer's dense loader takes).
constexpr uint64_t k_max_bake_voxels = uint64_t(1) << 31;
// Largest --res: more would need more voxels than k_max_bake_voxels even for a flat crop.
constexpr int k_max_bake_resolution = 65536;

// What a bake's colour grid holds. Radiance: the NeRF's trained colour (the light of the capture), for
// emission-absorption renderers. Albedo: a relightable model's diffuse albedo (NerfModel::intrinsic()), for a
// renderer that scatters light with the grid (Blender's Principled Volume); view-independent, so no direction
// is averaged. An albedo grid rendered as emission glows with its albedo: radiance is the default for every
// model, albedo is asked for.
enum class BakeColour { radiance, albedo };

struct BakeSettings {
    std::optional<nerf::CropBox> crop;  // model space; default: the model's aabb, 0.5 -+ aabb_scale / 2
    int resolution = 256;               // voxels along the crop's longest side (when voxel_size is 0)
    float voxel_size = 0.0f;            // model units; > 0 overrides resolution
    std::optional<Vec3> direction;      // training-world axes; none: the average over colour_directions()
    std::optional<float> threshold;     // σ per model unit; none: default_threshold(model)
    BakeColour colour = BakeColour::radiance;
};

// Voxel counts and the voxel <-> model map. Index (i, j, k) runs along the cube's LOCAL x, y, z, i.e. model
// z, x, y (nerf_placement.h); the voxel centre is at local -1 + (index + 0.5) * 2 / dims on each axis.
struct BakeLayout {
    nerf::CropBox crop;
    int dims[3] = {1, 1, 1};  // local axes
    nerf::LocalToModel local_to_model;
    // Model units per local unit along the crop's longest side: density in a .vdb/.nvdb is σ_model times
    // this, i.e. σ per local unit, exact for a cubic crop in an unscaled cube (see docs/formats.md for other
    // crops).
    float model_per_local = 1.0f;

    uint64_t voxel_count() const { return uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]); }
    Vec3 local_center(int i, int j, int k) const;
    Vec3 model_center(int i, int j, int k) const { return local_to_model.point(local_center(i, j, k)); }
};

// Checks the settings against the model (crop inside the model's box, min < max, sizes) and computes the
// layout. Throws npt::Error naming the option (--crop, --res, --voxel) that is wrong.
BakeLayout make_bake_layout(const nerf::NerfModel& model, const BakeSettings& settings);

// The σ below which a voxel is dropped by default: an eighth of what the occupancy grid calls occupied,
// occupancy.threshold / (8 * min_step), so the bake keeps everything a ray march would see. 0.74 per model
// unit with the default config.
float default_threshold(const nerf::NerfModel& model);

// The 16 directions of a Fibonacci sphere, model axes, unit length: what `avg` averages the colour over for a
// model that does not store its training cameras' directions.
std::vector<Vec3> average_directions();

// At most this many directions are averaged over (the colour MLP runs once per voxel and direction).
constexpr size_t k_max_colour_directions = 16;

// The directions (model axes, unit) a bake's colour is averaged over, with their weights. The network's
// colour is trained only for directions a training camera looked along, so `avg` uses the model's
// view_directions: all of them when there are at most k_max_colour_directions, else that many picked by
// farthest-point sampling, each weighted by how many cameras lie nearest to it. A model without them
// (written before they were stored) gets average_directions(), equally weighted. `--direction`: that one.
struct ColourDirections {
    std::vector<Vec3> dirs;
    std::vector<float> weights;
};
ColourDirections colour_directions(const nerf::NerfModel& model, const BakeSettings& settings);

// The baked voxels, sparse, ordered by k, then j, then i. A voxel is listed when it has density (σ above the
// threshold, in an occupied cell) or when it neighbours one (3x3x3): those carry colour with σ = 0, so that
// trilinear interpolation at a surface's edge mixes in the right colour, not black.
struct BakedGrid {
    BakeLayout layout;
    float threshold = 0.0f;
    std::vector<int32_t> coords;  // 3 per voxel: i, j, k
    std::vector<float> sigma;     // per model unit; 0 for colour-only voxels
    // The NeRF's colour as its sRGB-encoded sigmoid outputs store it: for `avg`, the average in LINEAR light
    // over colour_directions(), each direction also weighted by the voxel's visibility from it (see
    // bake_grid.cpp), encoded back to sRGB.
    // With BakeColour::albedo: the intrinsic albedo (linear) at the voxel's centre, sRGB-encoded likewise.
    std::vector<Rgb> color;
    BakeColour colour = BakeColour::radiance;
    std::vector<uint8_t> has_density;  // 1: a density voxel; 0: colour only
    uint64_t density_voxels = 0;       // how many have has_density

    size_t size() const { return sigma.size(); }
};

using BakeProgress = std::function<void(uint64_t done, uint64_t total)>;

// Where a bake evaluates the field when not on the CPU (the GPU backend implements it, nerf/backend).
class BakeField {
  public:
    virtual ~BakeField() = default;
    // σ (per model unit) at the points.
    virtual void density(const std::vector<Vec3>& positions, std::vector<float>& sigma) = 0;
    // The colour (sigmoid outputs) at each point for each of `dirs` (unit, model axes): color[t * dirs.size()
    // + d] for point t and direction d.
    virtual void colors(const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                        std::vector<Rgb>& color) = 0;
};

// Checks that the model can be baked with these settings: albedo needs a relightable model and no direction.
// Throws npt::Error naming the option (--colour, --direction); `model_name` names the model in the message.
void check_colour_settings(const nerf::NerfModel& model, const BakeSettings& settings,
                           const std::string& model_name);

// Bakes the model: on the CPU (field == nullptr) in parallel over z-slabs (TBB), or with `field` over batches
// of slabs; the result does not depend on the thread count.
BakedGrid bake_model(const nerf::NerfModel& model, const BakeSettings& settings, const BakeProgress& progress = {},
                     BakeField* field = nullptr);

}  // namespace npt::bake
