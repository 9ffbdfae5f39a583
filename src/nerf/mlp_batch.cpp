// Batched MLP forward and backward as matrix products over a chunk of samples (see mlp_batch.h).
#include "nerf/mlp_batch.h"

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "nerf/matmul.h"

namespace npt::nerf {
namespace {

// Offset of layer l's outputs in MlpActivations::layer_outputs.
size_t activation_offset(const MlpShape& s, size_t n, int l) {
    size_t off = 0;
    for (int i = 0; i < l; ++i) off += n * size_t(s.layer_outputs(i));
    return off;
}

}  // namespace

void init_mlp_xavier(const MlpShape& s, float* weights, Pcg32& rng) {
    for (int l = 0; l < s.layer_count(); ++l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const float limit = std::sqrt(6.0f / float(ni + no));
        float* lw = weights + s.layer_offset(l);
        for (int i = 0; i < ni * no; ++i) lw[i] = (2.0f * rng.next_float() - 1.0f) * limit;
    }
}

const float* MlpActivations::output(const MlpShape& s) const {
    return layer_outputs.data() + activation_offset(s, n, s.hidden_layers);
}

void mlp_forward_batch(const MlpShape& s, const float* weights, const float* in, size_t n, float* out,
                       MlpActivations* keep) {
    const int rows = int(n);
    // Without `keep`, hidden layers ping-pong between two scratch buffers.
    std::vector<float> scratch;
    if (keep) {
        keep->n = n;
        keep->layer_outputs.resize(activation_offset(s, n, s.layer_count()));
    } else {
        scratch.resize(2 * n * size_t(s.width));
    }
    const float* x = in;
    for (int l = 0; l < s.layer_count(); ++l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const bool last = l == s.hidden_layers;
        float* y = keep ? keep->layer_outputs.data() + activation_offset(s, n, l)
                        : (last ? out : scratch.data() + size_t(l & 1) * n * size_t(s.width));
        // y[n][no] = x[n][ni] W^T with W stored [no][ni].
        matmul(rows, no, ni, x, ni, false, weights + s.layer_offset(l), ni, true, y, no, false);
        if (!last)
            for (size_t i = 0; i < n * size_t(no); ++i) y[i] = std::max(y[i], 0.0f);
        x = y;
    }
    if (keep) std::copy_n(x, n * size_t(s.outputs), out);
}

void mlp_backward_batch(const MlpShape& s, const float* weights, const float* in, const MlpActivations& acts,
                        const float* d_out, float* d_weights, float* d_in) {
    const size_t n = acts.n;
    const int rows = int(n);
    // g holds the gradient w.r.t. the current layer's pre-activation output; two buffers ping-pong.
    std::vector<float> scratch(2 * n * size_t(s.width));
    const float* g = d_out;
    for (int l = s.hidden_layers; l >= 0; --l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const float* x = l == 0 ? in : acts.layer_outputs.data() + activation_offset(s, n, l - 1);
        const float* w = weights + s.layer_offset(l);
        // dW[no][ni] += g^T x, summed over the samples.
        matmul(no, ni, rows, g, no, true, x, ni, false, d_weights + s.layer_offset(l), ni, true);
        if (l == 0) {
            if (d_in) matmul(rows, ni, no, g, no, false, w, ni, false, d_in, ni, false);
            break;
        }
        // Gradient w.r.t. the previous layer's output (g W), then through its ReLU: zero where the ReLU
        // output was zero (the subgradient 0 at the kink, as the per-sample code's fmaxf implies).
        float* dx = scratch.data() + size_t(l & 1) * n * size_t(s.width);
        matmul(rows, ni, no, g, no, false, w, ni, false, dx, ni, false);
        for (size_t i = 0; i < n * size_t(ni); ++i)
            if (!(x[i] > 0.0f)) dx[i] = 0.0f;
        g = dx;
    }
}

}  // namespace npt::nerf
