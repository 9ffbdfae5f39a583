// The MLP of mlp.h over a batch of samples on the CPU, forward and backward, as matrix products (matmul.h).
// A batch is row-major [n][features]: one sample's features are contiguous. The functions are single-threaded
// and work on one chunk of a batch; the trainer runs chunks in parallel and sums weight gradients in chunk
// order, so results do not depend on the thread count.
#pragma once

#include <cstddef>
#include <vector>

#include "nerf/mlp.h"

namespace npt {
class Pcg32;
}

namespace npt::nerf {

// Xavier-uniform weights, as tiny-cuda-nn initialises its MLPs: layer by layer, each weight uniform in
// +-sqrt(6 / (inputs + outputs)), drawn from `rng` in order. Shared by the NeRF and the relight fields, whose
// trained numbers the tests compare, so the order of draws is part of the contract.
void init_mlp_xavier(const MlpShape& s, float* weights, Pcg32& rng);

// What the backward pass needs from the forward pass: every layer's post-activation output.
struct MlpActivations {
    std::vector<float> layer_outputs;  // layer after layer, [n][layer_outputs(l)] each; the last is the output
    size_t n = 0;
    const float* output(const MlpShape& s) const;
};

// out[n][outputs]. `keep` (optional) receives the activations for mlp_backward_batch.
void mlp_forward_batch(const MlpShape& s, const float* weights, const float* in, size_t n, float* out,
                       MlpActivations* keep);

// Given d_out[n][outputs] (the loss gradient w.r.t. the linear output), ADDS the weight gradient to d_weights
// (param_count floats) and, when d_in is not null, WRITES the input gradient d_in[n][inputs]. `in` is the
// batch the forward pass saw.
void mlp_backward_batch(const MlpShape& s, const float* weights, const float* in, const MlpActivations& acts,
                        const float* d_out, float* d_weights, float* d_in);

}  // namespace npt::nerf
