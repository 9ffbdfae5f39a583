#include "nerf/cuda/adam_kernels.h"

#include "core/cuda/device_buffer.h"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 256;

__global__ void __launch_bounds__(k_block) adam_kernel(AdamArgs a) {
    const uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= a.count) return;
    float g = a.grads[i];
    if (!isfinite(g)) {
        atomicOr(a.nonfinite, 1u);
        return;
    }
    float w = a.params[i];
    if (i < a.l2_end) g += a.l2 * w;
    const float m = a.beta1 * a.m[i] + (1.0f - a.beta1) * g;
    const float v = a.beta2 * a.v[i] + (1.0f - a.beta2) * g * g;
    a.m[i] = m;
    a.v[i] = v;
    w -= a.lr * (m * a.correction1) / (sqrtf(v * a.correction2) + a.epsilon);
    a.params[i] = w;
    a.ema[i] = a.ema_decay * a.ema[i] + (1.0f - a.ema_decay) * w;
    if (i < a.half_count) a.mlp_half[i] = __float2half_rn(w);
}

__global__ void scale_kernel(const float* ema, float scale, uint64_t count, float* out, __half* mlp_half,
                             uint32_t half_count) {
    const uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const float w = ema[i] * scale;
    out[i] = w;
    if (i < half_count) mlp_half[i] = __float2half_rn(w);
}

__global__ void to_half_kernel(const float* p, uint32_t n, __half* out) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) out[i] = __float2half_rn(p[i]);
}

unsigned blocks_for(uint64_t n) { return unsigned((n + k_block - 1) / k_block); }

}  // namespace

void adam_step(const AdamArgs& a, cudaStream_t s) {
    if (a.count == 0) return;
    adam_kernel<<<blocks_for(a.count), k_block, 0, s>>>(a);
    NPT_CUDA_CHECK_LAUNCH("adam_kernel");
}

void scale_params(const float* ema, float scale, uint64_t count, float* out, __half* mlp_half,
                  uint32_t half_count, cudaStream_t s) {
    if (count == 0) return;
    scale_kernel<<<blocks_for(count), k_block, 0, s>>>(ema, scale, count, out, mlp_half, half_count);
    NPT_CUDA_CHECK_LAUNCH("scale_kernel");
}

void to_half(const float* params, uint32_t n, __half* out, cudaStream_t s) {
    if (n == 0) return;
    to_half_kernel<<<blocks_for(n), k_block, 0, s>>>(params, n, out);
    NPT_CUDA_CHECK_LAUNCH("to_half_kernel");
}

}  // namespace npt::nerf::cuda
