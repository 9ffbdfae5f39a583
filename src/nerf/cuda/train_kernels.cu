#include "nerf/cuda/train_kernels.h"

#include "core/cuda/device_buffer.h"
#include "core/rng.h"
#include "nerf/composite.h"
#include "nerf/loss.h"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 128;

__global__ void __launch_bounds__(k_block) march_training_rays_kernel(MarchRaysArgs a) {
    const uint32_t r = blockIdx.x * blockDim.x + threadIdx.x;
    if (r >= a.n_rays) return;
    // The CPU trainer's draws, in its order: image, pixel position, background, jitter.
    Pcg32 rng(a.step_seed, r);
    const DeviceImages& im = a.images;
    const uint32_t img = rng.next_u32() % im.count;
    const float px = rng.next_float() * float(im.width);
    const float py = rng.next_float() * float(im.height);
    const int ix = min(int(px), im.width - 1), iy = min(int(py), im.height - 1);
    const uint32_t pix = im.rgba[size_t(img) * im.width * im.height + size_t(iy) * im.width + ix];
    Rgb bg(1.0f);
    if (a.random_background) {
        const float b0 = rng.next_float();
        const float b1 = rng.next_float();
        bg = Rgb(b0, b1, rng.next_float());
    }
    const float alpha = float(pix >> 24) / 255.0f;
    const Rgb rgb(float(pix & 0xff) / 255.0f, float((pix >> 8) & 0xff) / 255.0f,
                  float((pix >> 16) & 0xff) / 255.0f);
    const Ray ray = pixel_ray(im.cameras[img], px, py);
    const float jitter = rng.next_float();

    // One march into the ray's scratch slots; a ray with more samples counts the rest, reserves, and marches
    // that part again (marching twice is cheap; a scratch per ray for up to 1024 samples is not).
    float4* mine = a.scratch + size_t(r) * k_march_scratch;
    MarchCursor c;
    int in_scratch = 0, n = 0;
    if (march_start(a.march, a.grid, ray, jitter, &c)) {
        march_continue(a.march, a.grid, ray, c, [&](const MarchSample& s) {
            mine[in_scratch++] = make_float4(s.position.x, s.position.y, s.position.z, s.dt);
            return in_scratch < k_march_scratch;
        });
        n = in_scratch;
        if (!c.done(a.march)) {
            MarchCursor rest = c;
            march_continue(a.march, a.grid, ray, rest, [&](const MarchSample&) {
                ++n;
                return true;
            });
        }
    }
    const uint32_t base = atomicAdd(&a.counters->marched, uint32_t(n));
    const bool kept = uint64_t(base) + uint64_t(n) <= a.samples.capacity;
    if (kept) {
        atomicAdd(&a.counters->rays_kept, 1u);
        for (int j = 0; j < in_scratch; ++j) {
            const float4 v = mine[j];
            a.samples.pos[base + j] = Vec3(v.x, v.y, v.z);
            a.samples.dt[base + j] = v.w;
            a.samples.ray[base + j] = r;
        }
        uint32_t j = base + uint32_t(in_scratch);
        if (n > in_scratch)
            march_continue(a.march, a.grid, ray, c, [&](const MarchSample& s) {
                a.samples.pos[j] = s.position;
                a.samples.dt[j] = s.dt;
                a.samples.ray[j] = r;
                ++j;
                return true;
            });
    }
    a.rays.first[r] = base;
    a.rays.count[r] = kept ? uint32_t(n) : k_ray_dropped;
    a.rays.target[r] = rgb * alpha + bg * (1.0f - alpha);
    a.rays.background[r] = bg;
    a.rays.dir[r] = ray.d;
}

__device__ __forceinline__ double warp_sum(double v) {
#pragma unroll
    for (int off = 16; off > 0; off >>= 1) v += __shfl_down_sync(0xffffffffu, v, off);
    return v;
}

__global__ void __launch_bounds__(k_block) composite_loss_kernel(CompositeLossArgs a) {
    const uint32_t r = blockIdx.x * blockDim.x + threadIdx.x;
    double loss = 0.0, se = 0.0;
    if (r < a.n_rays && a.rays.count[r] != k_ray_dropped) {
        const uint32_t first = a.rays.first[r];
        const int n = int(a.rays.count[r]);
        const Rgb bg = a.rays.background[r];
        const Rgb target = a.rays.target[r];
        const float* dt = a.samples.dt + first;
        const CompositeResult fwd =
            composite_forward(a.sigma + first, a.rgb + first, dt, n, a.min_transmittance, bg);
        Rgb grad;
        for (int k = 0; k < 3; ++k) {
            const float diff = fwd.color[k] - target[k];
            loss += huber_loss(diff, a.huber_delta, &grad[k]);
            se += double(diff) * diff;
        }
        const uint32_t used = uint32_t(fwd.used);
        if (used > 0) {
            const uint32_t c = atomicAdd(&a.counters->compacted, used);
            if (uint64_t(c) + used <= a.compact.capacity) {
                // The gradient of this ray's loss (not yet divided by the number of rays: the MLP kernel does).
                composite_backward(a.sigma + first, a.rgb + first, dt, int(used), fwd, bg, grad,
                                   a.compact.d_sigma + c, a.compact.d_rgb + c);
                for (uint32_t j = 0; j < used; ++j) {
                    a.compact.pos[c + j] = a.samples.pos[first + j];
                    a.compact.ray[c + j] = r;
                }
            }
        }
    }
    loss = warp_sum(loss);
    se = warp_sum(se);
    if ((threadIdx.x & 31) == 0 && (loss != 0.0 || se != 0.0)) {
        atomicAdd(&a.counters->loss, loss);
        atomicAdd(&a.counters->squared_error, se);
    }
}

int blocks_for(uint32_t n) { return int((n + k_block - 1) / k_block); }

}  // namespace

void march_training_rays(const MarchRaysArgs& a, cudaStream_t s) {
    if (a.n_rays == 0) return;
    march_training_rays_kernel<<<blocks_for(a.n_rays), k_block, 0, s>>>(a);
    NPT_CUDA_CHECK_LAUNCH("march_training_rays_kernel");
}

void composite_loss(const CompositeLossArgs& a, cudaStream_t s) {
    if (a.n_rays == 0) return;
    composite_loss_kernel<<<blocks_for(a.n_rays), k_block, 0, s>>>(a);
    NPT_CUDA_CHECK_LAUNCH("composite_loss_kernel");
}

}  // namespace npt::nerf::cuda
