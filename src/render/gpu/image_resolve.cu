#include "render/gpu/image_resolve.h"

#include "core/cuda/device_buffer.h"
#include "render/first_hit.h"

namespace npt::gpu {

namespace {
constexpr int k_block = 256;

__global__ void __launch_bounds__(k_block) resolve_kernel(const float4* planes, uint32_t slots, size_t pixels,
                                                           float scale, int channels, float* rgb) {
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= pixels) return;
    float r = 0.0f, g = 0.0f, b = 0.0f, escaped = 0.0f;
    for (uint32_t z = 0; z < slots; ++z) {  // in plane order, as the CPU added them before
        const float4 s = planes[size_t(z) * pixels + i];
        r += s.x, g += s.y, b += s.z, escaped += s.w;
    }
    float* px = rgb + size_t(channels) * i;
    px[0] = r * scale;
    px[1] = g * scale;
    px[2] = b * scale;
    if (channels == 4) px[3] = 1.0f - escaped * scale;
}

__global__ void __launch_bounds__(k_block) resolve_first_hits_kernel(const float4* planes, uint32_t slots,
                                                                      size_t pixels, float* albedo, float* normal,
                                                                      float* depth) {
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= pixels) return;
    float weight = 0.0f, distance = 0.0f;
    Rgb albedo_sum(0.0f);
    Vec3 normal_sum(0.0f);
    for (uint32_t z = 0; z < slots; ++z) {
        const float4 a = planes[2 * size_t(z) * pixels + i], n = planes[(2 * size_t(z) + 1) * pixels + i];
        albedo_sum += Rgb(a.x, a.y, a.z);
        weight += a.w;
        normal_sum += Vec3(n.x, n.y, n.z);
        distance += n.w;
    }
    const render::FirstHitAovs v = render::resolve_first_hit(weight, albedo_sum, normal_sum, distance);
    for (int c = 0; c < 3; ++c) {
        if (albedo) albedo[3 * i + size_t(c)] = v.albedo[c];
        if (normal) normal[3 * i + size_t(c)] = v.normal[c];
    }
    if (depth) depth[i] = v.depth;
}

unsigned blocks(size_t pixels) { return unsigned((pixels + k_block - 1) / k_block); }
}  // namespace

void resolve_image(const float4* planes, uint32_t slots, size_t pixels, float scale, int channels, float* rgb,
                   cudaStream_t s) {
    if (pixels == 0) return;
    resolve_kernel<<<blocks(pixels), k_block, 0, s>>>(planes, slots, pixels, scale, channels, rgb);
    NPT_CUDA_CHECK_LAUNCH("resolve_kernel");
}

void resolve_first_hits(const float4* first_hit, uint32_t slots, size_t pixels, float* albedo, float* normal,
                        float* depth, cudaStream_t s) {
    if (pixels == 0) return;
    resolve_first_hits_kernel<<<blocks(pixels), k_block, 0, s>>>(first_hit, slots, pixels, albedo, normal, depth);
    NPT_CUDA_CHECK_LAUNCH("resolve_first_hits_kernel");
}

}  // namespace npt::gpu
