#include "nerf/cuda/render_kernels.h"

#include <algorithm>

#include "core/cuda/device_buffer.h"
#include "core/cuda/warp_lists.cuh"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/hash_grid_kernels.h"
#include "nerf/cuda/march_slots.cuh"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 128;

__device__ __forceinline__ void write_pixel(const RenderFrame& f, uint32_t pixel, Rgb color, float tau) {
    const float t = expf(-tau);
    const Rgb c = color + f.background * t;
    f.image[pixel] = make_float4(c.x, c.y, c.z, 1.0f - t);
}

__global__ void __launch_bounds__(k_block) init_kernel(RenderFrame f, RayCamera cam, uint32_t* alive,
                                                        uint32_t* alive_count) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const uint32_t n = uint32_t(f.width) * uint32_t(f.height);
    bool live = false;
    if (i < n) {
        const int x = int(i % uint32_t(f.width)), y = int(i / uint32_t(f.width));
        RenderRay r;
        r.ray = pixel_ray(cam, float(x) + 0.5f, float(y) + 0.5f);
        // A fixed mid-step offset, as render_view: an image must not change from one render to the next.
        live = march_start(f.march, f.grid, r.ray, 0.5f, &r.cursor) &&
               march_clip(f.march, r.ray, f.box_min, f.box_max, &r.cursor) && !r.cursor.done(f.march);
        f.rays[i] = r;
        f.dirs[i] = r.ray.d;
        if (!live) write_pixel(f, i, Rgb(0.0f), 0.0f);
    }
    gpu::warp_append(live, i, alive, alive_count);
}

__global__ void __launch_bounds__(k_block) march_kernel(RenderFrame f, const uint32_t* alive, uint32_t n, int k,
                                                         RenderSlots slots) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    const bool live = a < n;
    const uint32_t pixel = live ? alive[a] : 0u;
    MarchCursor c;
    Ray ray{};
    if (live) {
        c = f.rays[pixel].cursor;  // in registers while marching
        ray = f.rays[pixel].ray;
    }
    march_into_slots(live, a, pixel, f.march, f.grid, ray, c, k, slots, f.object);
    if (live) f.rays[pixel].cursor = c;
}

__global__ void __launch_bounds__(k_block) field_fp32_kernel(NerfFieldView field, RenderSlots slots,
                                                              const Vec3* dirs, float* sigma, Rgb* rgb) {
    const uint32_t m = *slots.count;
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < m; i += gridDim.x * blockDim.x)
        field.query(slots.pos[i], dirs[slots.pixel[i]], &sigma[i], &rgb[i]);
}

__global__ void __launch_bounds__(k_block) composite_kernel(RenderFrame f, const uint32_t* alive, uint32_t n,
                                                             int k, RenderSlots slots, const float* sigma,
                                                             const Rgb* rgb, uint32_t* next,
                                                             uint32_t* next_count) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    bool go_on = false;
    uint32_t pixel = 0;
    if (a < n) {
        pixel = alive[a];
        RenderRay& r = f.rays[pixel];
        float tau = r.tau;
        Rgb color = r.color;
        bool done = false;
        const size_t base = slots.first[a];
        const int used = slots.used[a];
        // render_view.cpp's arithmetic, sample by sample.
        for (int j = 0; j < used; ++j) {
            const float t_before = expf(-tau);
            const float od = sigma[base + j] * slots.dt[base + j];
            color += rgb[base + j] * (t_before * -expm1f(-od));
            tau += od;
            if (expf(-tau) < f.min_transmittance) {
                done = true;
                break;
            }
        }
        if (!done && r.cursor.done(f.march)) done = true;
        if (done) {
            write_pixel(f, pixel, color, tau);
        } else {
            r.tau = tau;
            r.color = color;
            go_on = true;
        }
    }
    gpu::warp_append(go_on, pixel, next, next_count);
}

unsigned blocks_for(uint32_t n) { return (n + k_block - 1) / k_block; }

}  // namespace

void render_init(const RenderFrame& f, const RayCamera& camera, uint32_t* alive, uint32_t* alive_count,
                 cudaStream_t s) {
    const uint32_t n = uint32_t(f.width) * uint32_t(f.height);
    init_kernel<<<blocks_for(n), k_block, 0, s>>>(f, camera, alive, alive_count);
    NPT_CUDA_CHECK_LAUNCH("render init_kernel");
}

void render_march(const RenderFrame& f, const uint32_t* alive, uint32_t n, int k, RenderSlots slots,
                  cudaStream_t s) {
    if (n == 0) return;
    march_kernel<<<blocks_for(n), k_block, 0, s>>>(f, alive, n, k, slots);
    NPT_CUDA_CHECK_LAUNCH("render march_kernel");
}

void render_field_fp32(const NerfFieldView& field, const RenderSlots& slots, const Vec3* dirs, uint32_t capacity,
                       float* sigma, Rgb* rgb, cudaStream_t s) {
    if (capacity == 0) return;
    field_fp32_kernel<<<std::min(blocks_for(capacity), 132u * 16u), k_block, 0, s>>>(field, slots, dirs, sigma, rgb);
    NPT_CUDA_CHECK_LAUNCH("render field_fp32_kernel");
}

void render_field_fp16(const NerfLayout& layout, const float* params, const __half* mlp_half,
                       const RenderSlots& slots, const Vec3* dirs, uint32_t capacity, __half* encoded, float* sigma,
                       Rgb* rgb, cudaStream_t s) {
    HashGridArgs h;
    h.layout = layout;
    h.positions = slots.pos;
    h.count = slots.count;
    h.capacity = capacity;
    hash_encode(h, params + layout.grid_offset, encoded, s);
    MlpInferenceArgs a;
    a.weights = mlp_half;
    a.encoded = encoded;
    a.sample_ray = slots.pixel;
    a.ray_dir = dirs;
    a.count = slots.count;
    a.capacity = capacity;
    a.sigma = sigma;
    a.rgb = rgb;
    mlp_inference(a, false, s);
}

void render_density_fp16(const NerfLayout& layout, const float* params, const __half* mlp_half,
                         const RenderSlots& slots, uint32_t capacity, __half* encoded, float* sigma, cudaStream_t s) {
    HashGridArgs h;
    h.layout = layout;
    h.positions = slots.pos;
    h.count = slots.count;
    h.capacity = capacity;
    hash_encode(h, params + layout.grid_offset, encoded, s);
    MlpInferenceArgs a;
    a.weights = mlp_half;
    a.encoded = encoded;
    a.count = slots.count;
    a.capacity = capacity;
    a.sigma = sigma;
    mlp_inference(a, true, s);
}

void render_composite(const RenderFrame& f, const uint32_t* alive, uint32_t n, int k, RenderSlots slots,
                      const float* sigma, const Rgb* rgb, uint32_t* next, uint32_t* next_count, cudaStream_t s) {
    if (n == 0) return;
    composite_kernel<<<blocks_for(n), k_block, 0, s>>>(f, alive, n, k, slots, sigma, rgb, next, next_count);
    NPT_CUDA_CHECK_LAUNCH("render composite_kernel");
}

}  // namespace npt::nerf::cuda
