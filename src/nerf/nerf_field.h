// The NeRF field at one point, NPT_HD for the path tracer and the GPU: the parameter layout (density MLP
// weights, colour MLP weights, then the hash grid: instant-ngp's snapshot order) and the per-point query.
// Training evaluates the same maths batched (field_batch.h).
#pragma once

#include <math.h>

#include <cstddef>

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/hash_encoding.h"
#include "nerf/mlp.h"
#include "nerf/sh_encoding.h"

namespace npt::nerf {

// Where each part of the parameter array starts, and the shapes that read it.
struct NerfLayout {
    HashGridConfig grid;  // with per_level_scale resolved for the model's aabb_scale
    MlpShape density;     // inputs: grid.output_dims()
    MlpShape color;       // inputs: density.outputs + 16 (SH degree 4)
    size_t density_offset = 0, color_offset = 0, grid_offset = 0, total = 0;
    // The hash grid covers the model's aabb (0.5 -+ aabb_scale / 2), not the unit cube: like instant-ngp, it is
    // fed the position relative to the aabb, (p - aabb_min) / aabb_scale.
    Vec3 aabb_min{0.0f, 0.0f, 0.0f};
    float inv_aabb_scale = 1.0f;
    NPT_HD NPT_INLINE Vec3 grid_position(Vec3 p) const { return (p - aabb_min) * inv_aabb_scale; }
};

// The density activation: exp, with the gradient clamped as instant-ngp does (exp of the clamped input).
NPT_HD NPT_INLINE float density_activation(float raw) { return expf(fminf(raw, 15.0f)); }
NPT_HD NPT_INLINE float density_activation_grad(float raw) { return expf(clampf(raw, -15.0f, 15.0f)); }
NPT_HD NPT_INLINE float sigmoidf(float x) { return 1.0f / (1.0f + expf(-x)); }

// The field at one point, for renderers: plain pointers, copyable to the GPU.
struct NerfFieldView {
    NerfLayout layout;
    const float* params = nullptr;
    HashLevels levels;  // hash_levels(layout.grid), computed once rather than per lookup

    NerfFieldView() = default;
    NPT_HD NerfFieldView(const NerfLayout& l, const float* p) : layout(l), params(p), levels(hash_levels(l.grid)) {}

    // sigma (per model-space unit) at a model-space point.
    NPT_HD float density(Vec3 p) const {
        float enc[k_max_mlp_width], out[k_max_mlp_width];
        out[0] = 0.0f;  // written by mlp_forward; set so that GCC cannot think it is read uninitialised
        hash_encode(layout.grid, levels, params + layout.grid_offset, layout.grid_position(p), enc);
        mlp_forward(layout.density, params + layout.density_offset, enc, out);
        return density_activation(out[0]);
    }
    // sigma and colour (sigmoid outputs, the stored sRGB-encoded values) seen from unit direction d.
    NPT_HD void query(Vec3 p, Vec3 d, float* sigma, Rgb* rgb) const {
        float enc[k_max_mlp_width], col_in[k_max_mlp_width], out[k_max_mlp_width];
        col_in[0] = out[0] = out[1] = out[2] = 0.0f;  // as in density()
        hash_encode(layout.grid, levels, params + layout.grid_offset, layout.grid_position(p), enc);
        mlp_forward(layout.density, params + layout.density_offset, enc, col_in);
        *sigma = density_activation(col_in[0]);
        sh_encode_deg4(d, col_in + layout.density.outputs);
        mlp_forward(layout.color, params + layout.color_offset, col_in, out);
        *rgb = Rgb(sigmoidf(out[0]), sigmoidf(out[1]), sigmoidf(out[2]));
    }
};

}  // namespace npt::nerf
