// A trained (or training) NeRF: its configuration, where it sits relative to the training cameras, its
// parameters and its occupancy grid. The parameter array is laid out as instant-ngp's snapshots are:
// density MLP weights, colour MLP weights, then the hash grid. NerfFieldView is the NPT_HD per-point query
// the path tracer and the GPU use; training evaluates the same maths batched (nerf_network.h).
#pragma once

#include <math.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "core/platform.h"
#include "core/transform.h"
#include "core/vec.h"
#include "nerf/adam.h"
#include "nerf/hash_encoding.h"
#include "nerf/mlp.h"
#include "nerf/nerf_config.h"
#include "nerf/occupancy_grid.h"
#include "nerf/ray_march.h"
#include "nerf/sh_encoding.h"

namespace npt::nerf {

// Where each part of the parameter array starts, and the shapes that read it.
struct NerfLayout {
    HashGridConfig grid;  // with per_level_scale resolved for the model's aabb_scale
    MlpShape density;     // inputs: grid.output_dims()
    MlpShape color;       // inputs: density.outputs + 16 (SH degree 4)
    size_t density_offset = 0, color_offset = 0, grid_offset = 0, total = 0;
};

NerfLayout make_layout(const NerfConfig& config, float aabb_scale);

// The density activation: exp, with the gradient clamped as instant-ngp does (exp of the clamped input).
NPT_HD NPT_INLINE float density_activation(float raw) { return expf(fminf(raw, 15.0f)); }
NPT_HD NPT_INLINE float density_activation_grad(float raw) { return expf(clampf(raw, -15.0f, 15.0f)); }
NPT_HD NPT_INLINE float sigmoidf(float x) { return 1.0f / (1.0f + expf(-x)); }

// The field at one point, for renderers: plain pointers, copyable to the GPU.
struct NerfFieldView {
    NerfLayout layout;
    const float* params = nullptr;

    // sigma (per model-space unit) at a model-space point.
    NPT_HD float density(Vec3 p) const {
        float enc[k_max_mlp_width], out[k_max_mlp_width];
        hash_encode(layout.grid, params + layout.grid_offset, p, enc);
        mlp_forward(layout.density, params + layout.density_offset, enc, out);
        return density_activation(out[0]);
    }
    // sigma and colour (sigmoid outputs, the stored sRGB-encoded values) seen from unit direction d.
    NPT_HD void query(Vec3 p, Vec3 d, float* sigma, Rgb* rgb) const {
        float enc[k_max_mlp_width], col_in[k_max_mlp_width], out[k_max_mlp_width];
        hash_encode(layout.grid, params + layout.grid_offset, p, enc);
        mlp_forward(layout.density, params + layout.density_offset, enc, col_in);
        *sigma = density_activation(col_in[0]);
        sh_encode_deg4(d, col_in + layout.density.outputs);
        mlp_forward(layout.color, params + layout.color_offset, col_in, out);
        *rgb = Rgb(sigmoidf(out[0]), sigmoidf(out[1]), sigmoidf(out[2]));
    }
};

// What only training needs: the raw (not averaged) parameters and the optimizer's state. Randomness is a
// function of (seed, step), so the step is all that is needed to continue exactly.
struct TrainingState {
    std::vector<float> params;
    AdamState adam;
    double elapsed_seconds = 0;  // training time so far, for --time across resumes
    uint32_t rays_per_step = 0;  // the adaptive batch size in rays for the next step (0: not yet known)
};

struct NerfModel {
    NerfConfig config;
    float aabb_scale = 1.0f;
    // Training-camera (world) space to model space: instant-ngp's p * scale + offset followed by its axis cycle
    // (x, y, z) <- (y, z, x), so that model space is instant-ngp's and its snapshots import unchanged.
    Mat4 world_to_model;
    std::vector<float> params;  // what renders: the averaged (EMA) parameters
    OccupancyGrid occupancy;
    std::optional<TrainingState> training;

    NerfLayout layout() const { return make_layout(config, aabb_scale); }
    NerfFieldView field() const { return {layout(), params.data()}; }
    MarchParams march_params() const;
};

// A fresh model for a data set: parameters initialised (hash grid uniform in +-1e-4, MLP weights
// Xavier-uniform, from config.training.seed), every occupancy cell occupied.
NerfModel create_model(const NerfConfig& config, float aabb_scale, const Mat4& world_to_model);

// instant-ngp's world-to-model map for a data set's scale and offset.
Mat4 ngp_world_to_model(float scale, Vec3 offset);

}  // namespace npt::nerf
