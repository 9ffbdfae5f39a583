// The NeRF field (hash grid -> density MLP -> + SH(direction) -> colour MLP) over a batch of samples on the
// CPU: forward with what backward needs, and backward to the parameters. The same maths as NerfFieldView,
// arranged as matrix products. One FieldBatch is one chunk processed by one thread; the hash-grid gradient of
// many chunks is accumulated afterwards by accumulate_grid_gradient, parallel over levels, so that every
// parameter's gradient is summed in sample order whatever the thread count.
#pragma once

#include <cstddef>
#include <vector>

#include "nerf/mlp_batch.h"
#include "nerf/nerf_model.h"

namespace npt::nerf {

struct FieldBatch {
    size_t n = 0;
    std::vector<float> encoded;   // [n][grid outputs]
    std::vector<float> color_in;  // [n][density outputs + 16]: density MLP output, then SH of the direction
    MlpActivations density_acts, color_acts;
    std::vector<float> density_out;  // [n][density outputs]: linear outputs, 0 = log-density
    std::vector<float> color_out;    // [n][3]: before the sigmoid
    std::vector<float> sigma;     // [n] activated density
    std::vector<Rgb> rgb;         // [n] sigmoid colour
    // Backward scratch.
    std::vector<float> d_color_in, d_density_out, d_encoded;
};

// Evaluates n samples at model-space positions with unit directions (dirs may be null when with_color is
// false: then only sigma is computed). Keeps what field_backward needs.
void field_forward(const NerfLayout& layout, const float* params, const Vec3* positions, const Vec3* dirs,
                   size_t n, bool with_color, FieldBatch& b);

// Given dLoss/dsigma and dLoss/drgb per sample (activated values), ADDS the MLP weight gradients to d_params
// (same layout as params; only the MLP ranges are touched) and leaves dLoss/d(encoding) in b.d_encoded.
void field_backward(const NerfLayout& layout, const float* params, const float* d_sigma, const Rgb* d_rgb,
                    FieldBatch& b, float* d_params);

// d_params[grid range] += the hash-grid gradient of every chunk's samples: chunk c's positions[c][i] with
// d_encoded chunks[c]->d_encoded. Parallel over levels (TBB); deterministic. reached (optional, one flag per
// grid entry): set to 1 for every entry a sample's corner falls in (Adam::step_sparse visits only those);
// a sample whose gradient at a level is zero (past its ray's stop) is skipped there, which changes no sum.
void accumulate_grid_gradient(const NerfLayout& layout, const std::vector<const Vec3*>& positions,
                              const std::vector<const FieldBatch*>& chunks, float* d_params,
                              uint8_t* reached = nullptr);

}  // namespace npt::nerf
