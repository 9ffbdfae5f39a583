// Adam with L2 on the MLP weights, the learning-rate schedule's value for this step and the parameter EMA, as
// nerf/adam.cpp (the CPU reference), one thread per parameter. The same kernel refreshes the fp16 copy of the
// MLP weights that the tensor-core kernels read. A non-finite gradient leaves its parameter untouched and
// raises a flag that the trainer turns into an error.
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>

namespace npt::nerf::cuda {

struct AdamArgs {
    float* params = nullptr;
    const float* grads = nullptr;
    float* m = nullptr;
    float* v = nullptr;
    float* ema = nullptr;
    __half* mlp_half = nullptr;    // fp16 copy of params [0, half_count)
    uint64_t count = 0;
    uint32_t l2_end = 0;           // L2 on [0, l2_end): the MLP weights
    uint32_t half_count = 0;
    float lr = 0, beta1 = 0, beta2 = 0, epsilon = 0, l2 = 0;
    float correction1 = 1, correction2 = 1;  // 1 / (1 - beta^t)
    float ema_decay = 0;
    uint32_t* nonfinite = nullptr;  // set to 1 when a gradient is NaN or infinite
};
void adam_step(const AdamArgs& a, cudaStream_t s);

// out = ema * scale (the bias-corrected average), and its fp16 MLP copy.
void scale_params(const float* ema, float scale, uint64_t count, float* out, __half* mlp_half,
                  uint32_t half_count, cudaStream_t s);
// fp16 copy of [0, n) of params.
void to_half(const float* params, uint32_t n, __half* out, cudaStream_t s);

}  // namespace npt::nerf::cuda
