#include "nerf/cuda/train_kernels.h"

#include "core/cuda/device_buffer.h"
#include "core/rng.h"
#include "nerf/composite.h"
#include "nerf/cuda/occupancy_kernels.h"
#include "nerf/loss.h"
#include "nerf/surface_smoothness.h"
#include "nerf/train_pixel.h"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 128;

// Ray r of the step: the CPU trainer's draws, in its order: image, pixel position, background, jitter.
struct TrainRay {
    Ray ray;
    Rgb target, background;
    float jitter;
};
__device__ __forceinline__ TrainRay setup_ray(const MarchRaysArgs& a, uint32_t r) {
    const DeviceImages& im = a.images;
    const TrainPixel draw =
        draw_train_pixel(a.step_seed, r, im.count, im.width, im.height, a.random_background, a.group_spacing,
                         im.focus);
    const int ix = min(int(draw.px), im.width - 1), iy = min(int(draw.py), im.height - 1);
    const uint32_t pix = im.rgba[size_t(draw.image) * im.width * im.height + size_t(iy) * im.width + ix];
    TrainRay t;
    t.background = draw.background;
    const float alpha = float(pix >> 24) / 255.0f;
    const Rgb rgb(float(pix & 0xff) / 255.0f, float((pix >> 8) & 0xff) / 255.0f,
                  float((pix >> 16) & 0xff) / 255.0f);
    t.target = rgb * alpha + t.background * (1.0f - alpha);
    t.ray = pixel_ray(im.cameras[draw.image], draw.px, draw.py);
    t.jitter = draw.jitter;
    return t;
}

__device__ __forceinline__ void write_ray(const MarchRaysArgs& a, uint32_t r, const TrainRay& t, uint32_t base,
                                          uint32_t n, bool kept) {
    a.rays.first[r] = base;
    a.rays.count[r] = kept ? n : k_ray_dropped;
    a.rays.target[r] = t.target;
    a.rays.background[r] = t.background;
    a.rays.dir[r] = t.ray.d;
}

__global__ void __launch_bounds__(k_block) march_training_rays_kernel(MarchRaysArgs a) {
    const uint32_t r = blockIdx.x * blockDim.x + threadIdx.x;
    if (r >= a.n_rays) return;
    const TrainRay tr = setup_ray(a, r);
    const Ray& ray = tr.ray;
    const float jitter = tr.jitter;

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
    write_ray(a, r, tr, base, uint32_t(n), kept);
}

// With a uniform step lattice (cone_angle 0: every scene inside the unit cube) the samples of a ray are the
// lattice points t0 + k dt in occupied cells, so k_segments threads can march one ray together, each a
// quarter of its lattice: 4x the threads of a step's ~30k rays, which alone leave the GPU latency-bound.
// Positions are t0 + k dt as march_continue computes them, so the samples are those of a single march.
constexpr int k_segments = 4;

template <typename Visit>
__device__ __forceinline__ int march_lattice(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray,
                                             float t0, float dt, float t_far, uint32_t k_begin, uint32_t k_end,
                                             Visit&& visit) {
    const Vec3 inv_d(ray.d.x != 0.0f ? 1.0f / ray.d.x : 0.0f, ray.d.y != 0.0f ? 1.0f / ray.d.y : 0.0f,
                     ray.d.z != 0.0f ? 1.0f / ray.d.z : 0.0f);
    const float inv_dt = 1.0f / dt;
    int n = 0;
    for (uint32_t k = k_begin; k < k_end;) {
        const float t = t0 + float(k) * dt;
        if (!(t < t_far)) break;
        const Vec3 p = ray.at(t);
        const int cas = march_cascade(grid, p, dt);
        if (grid.is_occupied(p, cas)) {
            visit(MarchSample{p, t, dt}, n);
            ++n;
            ++k;
            continue;
        }
        const float cell = grid.cascade_size(cas) / float(grid.resolution);
        const float eps = fmaxf(1e-6f * cell, 1e-6f * t);
        const float skip_cell = grid.coarse_occupied(p, cas) ? cell : cell * float(OccupancyGridView::k_coarse);
        const float target = t + march_distance_to_cell_exit(p, ray.d, inv_d, skip_cell) + eps;
        // The same lattice arithmetic as march_continue: the samples are the CPU march's.
        const float kn = march_lattice_next(t0, inv_dt, k, target);
        k = kn < float(k_end) ? uint32_t(kn) : k_end;
    }
    return n;
}

__global__ void __launch_bounds__(k_block) march_segmented_kernel(MarchRaysArgs a) {
    const uint32_t gid = blockIdx.x * blockDim.x + threadIdx.x;
    const uint32_t r = gid / k_segments;
    const int seg = int(gid % k_segments);
    const int lane = threadIdx.x & 31;
    const int leader = lane & ~(k_segments - 1);
    const bool active = r < a.n_rays;
    TrainRay tr;
    MarchCursor c;
    bool ok = false;
    if (active) {
        tr = setup_ray(a, r);
        ok = march_start(a.march, a.grid, tr.ray, tr.jitter, &c);
        // Only the part of the lattice inside the box around the occupied cells can hold samples.
        if (ok && a.occupied_box) {
            const Vec3 lo(float_of_key(a.occupied_box[0]), float_of_key(a.occupied_box[1]),
                          float_of_key(a.occupied_box[2]));
            const Vec3 hi(float_of_key(a.occupied_box[3]), float_of_key(a.occupied_box[4]),
                          float_of_key(a.occupied_box[5]));
            ok = march_clip(a.march, tr.ray, lo, hi, &c);
        }
    }
    const float dt = ok ? march_step(a.march, c.t0) : 1.0f;
    uint32_t first = 0, lattice = 0;  // lattice indices [first, lattice) of the ray
    if (ok && c.t < c.t_far) {
        first = c.k;
        lattice = min(uint32_t(ceilf((c.t_far - c.t0) / dt)) + 1u, uint32_t(a.march.max_samples));
        if (lattice < first) lattice = first;
    }
    const uint32_t span = lattice - first;
    const uint32_t k_begin = first + span * uint32_t(seg) / k_segments,
                   k_end = first + span * uint32_t(seg + 1) / k_segments;
    int mine = 0;
    if (ok)
        mine = march_lattice(a.march, a.grid, tr.ray, c.t0, dt, c.t_far, k_begin, k_end,
                             [](const MarchSample&, int) {});
    // The ray's total and this segment's offset within it (the lanes of a ray are consecutive).
    int before = 0, total = 0;
#pragma unroll
    for (int q = 0; q < k_segments; ++q) {
        const int v = __shfl_sync(0xffffffffu, mine, leader + q);
        total += v;
        if (q < seg) before += v;
    }
    uint32_t base = 0;
    if (seg == 0 && active) base = atomicAdd(&a.counters->marched, uint32_t(total));
    base = __shfl_sync(0xffffffffu, base, leader);
    if (!active) return;
    const bool kept = uint64_t(base) + uint64_t(total) <= a.samples.capacity;
    if (kept && mine > 0) {
        const uint32_t at = base + uint32_t(before);
        march_lattice(a.march, a.grid, tr.ray, c.t0, dt, c.t_far, k_begin, k_end, [&](const MarchSample& s, int j) {
            a.samples.pos[at + j] = s.position;
            a.samples.dt[at + j] = s.dt;
            a.samples.ray[at + j] = r;
        });
    }
    if (seg == 0) {
        if (kept) atomicAdd(&a.counters->rays_kept, 1u);
        write_ray(a, r, tr, base, uint32_t(total), kept);
    }
}

__device__ __forceinline__ double warp_sum(double v) {
#pragma unroll
    for (int off = 16; off > 0; off >>= 1) v += __shfl_down_sync(0xffffffffu, v, off);
    return v;
}

// Ray r's composite and Huber loss, into *fwd and the colour gradient; false for a dropped ray.
__device__ __forceinline__ bool ray_forward(const CompositeLossArgs& a, uint32_t r, CompositeResult* fwd, Rgb* grad,
                                            double* loss, double* se) {
    if (r >= a.n_rays || a.rays.count[r] == k_ray_dropped) return false;
    const uint32_t first = a.rays.first[r];
    *fwd = composite_forward(a.sigma + first, a.rgb + first, a.samples.dt + first, int(a.rays.count[r]),
                             a.min_transmittance, a.rays.background[r]);
    const Rgb target = a.rays.target[r];
    for (int k = 0; k < 3; ++k) {
        const float diff = fwd->color[k] - target[k];
        *loss += huber_loss(diff, a.huber_delta, &(*grad)[k]);
        *se += double(diff) * diff;
    }
    return true;
}

// Compacts ray r's samples before its stop with their gradient (not yet divided by the number of rays: the MLP
// kernel does); with a smoothness term, its gradient d_point through the ray's surface point is added.
__device__ __forceinline__ void ray_backward(const CompositeLossArgs& a, uint32_t r, const CompositeResult& fwd,
                                             Rgb grad, const SurfacePoint* point, Vec3 d_point) {
    const uint32_t used = uint32_t(fwd.used);
    if (used == 0) return;
    const uint32_t first = a.rays.first[r];
    const uint32_t c = atomicAdd(&a.counters->compacted, used);
    if (uint64_t(c) + used > a.compact.capacity) return;
    const float* dt = a.samples.dt + first;
    composite_backward(a.sigma + first, a.rgb + first, dt, int(used), fwd, a.rays.background[r], grad,
                       a.compact.d_sigma + c, a.compact.d_rgb + c);
    if (point)
        surface_point_backward_add(a.sigma + first, a.samples.pos + first, dt, int(used), *point, d_point,
                                   a.compact.d_sigma + c);
    for (uint32_t j = 0; j < used; ++j) {
        a.compact.pos[c + j] = a.samples.pos[first + j];
        a.compact.ray[c + j] = r;
    }
}

__device__ __forceinline__ void add_counters(const CompositeLossArgs& a, double loss, double se, double smooth) {
    loss = warp_sum(loss);
    se = warp_sum(se);
    smooth = warp_sum(smooth);
    if ((threadIdx.x & 31) == 0 && (loss != 0.0 || se != 0.0 || smooth != 0.0)) {
        atomicAdd(&a.counters->loss, loss);
        atomicAdd(&a.counters->squared_error, se);
        if (smooth != 0.0) atomicAdd(&a.counters->smoothness, smooth);
    }
}

__global__ void __launch_bounds__(k_block) composite_loss_kernel(CompositeLossArgs a) {
    const uint32_t r = blockIdx.x * blockDim.x + threadIdx.x;
    double loss = 0.0, se = 0.0;
    CompositeResult fwd;
    Rgb grad;
    if (ray_forward(a, r, &fwd, &grad, &loss, &se)) ray_backward(a, r, fwd, grad, nullptr, Vec3(0.0f));
    add_counters(a, loss, se, 0.0);
}

// With the smoothness loss: a thread per group of rays (train_pixel.h); the term where all three were kept.
__global__ void __launch_bounds__(k_block) composite_group_loss_kernel(CompositeLossArgs a) {
    const uint32_t g = blockIdx.x * blockDim.x + threadIdx.x;
    double loss = 0.0, se = 0.0, smooth = 0.0;
    CompositeResult fwd[k_smoothness_group];
    Rgb grad[k_smoothness_group];
    SurfacePoint points[k_smoothness_group];
    bool kept[k_smoothness_group];
    bool whole = true;
    for (uint32_t k = 0; k < k_smoothness_group; ++k) {
        const uint32_t r = g * k_smoothness_group + k;
        kept[k] = ray_forward(a, r, &fwd[k], &grad[k], &loss, &se);
        whole = whole && kept[k];
        if (kept[k]) {
            const uint32_t first = a.rays.first[r];
            points[k] = surface_point(a.sigma + first, a.samples.pos + first, a.samples.dt + first, fwd[k].used);
        }
    }
    SmoothnessTerm term;
    if (whole) term = smoothness_term(points, a.smoothness_weight, a.smoothness_scale);
    if (term.active) smooth = term.loss;
    for (uint32_t k = 0; k < k_smoothness_group; ++k)
        if (kept[k])
            ray_backward(a, g * k_smoothness_group + k, fwd[k], grad[k], term.active ? &points[k] : nullptr,
                         term.d_point[k]);
    add_counters(a, loss, se, smooth);
}

int blocks_for(uint32_t n) { return int((n + k_block - 1) / k_block); }

}  // namespace

void march_training_rays(const MarchRaysArgs& a, cudaStream_t s) {
    if (a.n_rays == 0) return;
    if (a.march.cone_angle == 0.0f) {
        march_segmented_kernel<<<blocks_for(a.n_rays * k_segments), k_block, 0, s>>>(a);
        NPT_CUDA_CHECK_LAUNCH("march_segmented_kernel");
        return;
    }
    march_training_rays_kernel<<<blocks_for(a.n_rays), k_block, 0, s>>>(a);
    NPT_CUDA_CHECK_LAUNCH("march_training_rays_kernel");
}

void composite_loss(const CompositeLossArgs& a, cudaStream_t s) {
    if (a.n_rays == 0) return;
    if (a.smoothness_weight > 0.0f) {
        const uint32_t groups = (a.n_rays + k_smoothness_group - 1) / k_smoothness_group;
        composite_group_loss_kernel<<<blocks_for(groups), k_block, 0, s>>>(a);
        NPT_CUDA_CHECK_LAUNCH("composite_group_loss_kernel");
        return;
    }
    composite_loss_kernel<<<blocks_for(a.n_rays), k_block, 0, s>>>(a);
    NPT_CUDA_CHECK_LAUNCH("composite_loss_kernel");
}

}  // namespace npt::nerf::cuda
