// A bias-free fully connected network (tiny-cuda-nn's MLP shape): ReLU hidden layers, linear output. The
// per-sample forward here is NPT_HD, for the path tracer and the GPU; training runs the same maths batched
// (mlp_batch.h). Weights: layer after layer, each row-major [outputs][inputs], so that output o of a layer is
// dot(W[o], x).
#pragma once

#include <cmath>  // fmaxf
#include <cstddef>

#include "core/platform.h"

namespace npt::nerf {

constexpr int k_max_mlp_width = 128;  // bound for the per-sample scratch arrays

struct MlpShape {
    int inputs = 0;
    int width = 0;
    int hidden_layers = 0;  // >= 1
    int outputs = 0;

    NPT_HD NPT_INLINE int layer_count() const { return hidden_layers + 1; }
    NPT_HD NPT_INLINE int layer_inputs(int l) const { return l == 0 ? inputs : width; }
    NPT_HD NPT_INLINE int layer_outputs(int l) const { return l == hidden_layers ? outputs : width; }
    // Offset of layer l's weight matrix in the parameter array.
    NPT_HD NPT_INLINE size_t layer_offset(int l) const {
        size_t off = 0;
        for (int i = 0; i < l; ++i) off += size_t(layer_inputs(i)) * size_t(layer_outputs(i));
        return off;
    }
    NPT_HD NPT_INLINE size_t param_count() const { return layer_offset(layer_count()); }
};

// out[outputs] = W_L relu(... relu(W_0 in)). Inputs, width and outputs must be <= k_max_mlp_width.
NPT_HD NPT_INLINE void mlp_forward(const MlpShape& s, const float* weights, const float* in, float* out) {
    float buf[2][k_max_mlp_width];
    const float* x = in;
    for (int l = 0; l < s.layer_count(); ++l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const float* w = weights + s.layer_offset(l);
        const bool last = l == s.hidden_layers;
        float* y = last ? out : buf[l & 1];
        for (int o = 0; o < no; ++o) {
            float acc = 0.0f;
            for (int i = 0; i < ni; ++i) acc += w[o * ni + i] * x[i];
            y[o] = last ? acc : (acc > 0.0f ? acc : 0.0f);  // not fmaxf: a library call on the CPU
        }
        x = y;
    }
}

}  // namespace npt::nerf
