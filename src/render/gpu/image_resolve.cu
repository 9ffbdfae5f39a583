#include "render/gpu/image_resolve.h"

#include "core/cuda/device_buffer.h"

namespace npt::gpu {

namespace {
constexpr int k_block = 256;

__global__ void __launch_bounds__(k_block) resolve_kernel(const float4* planes, uint32_t slots, size_t pixels,
                                                           float scale, float* rgb) {
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= pixels) return;
    float r = 0.0f, g = 0.0f, b = 0.0f;
    for (uint32_t z = 0; z < slots; ++z) {  // in plane order, as the CPU added them before
        const float4 s = planes[size_t(z) * pixels + i];
        r += s.x, g += s.y, b += s.z;
    }
    rgb[3 * i + 0] = r * scale;
    rgb[3 * i + 1] = g * scale;
    rgb[3 * i + 2] = b * scale;
}
}  // namespace

void resolve_image(const float4* planes, uint32_t slots, size_t pixels, float scale, float* rgb, cudaStream_t s) {
    if (pixels == 0) return;
    resolve_kernel<<<unsigned((pixels + k_block - 1) / k_block), k_block, 0, s>>>(planes, slots, pixels, scale, rgb);
    NPT_CUDA_CHECK_LAUNCH("resolve_kernel");
}

}  // namespace npt::gpu
