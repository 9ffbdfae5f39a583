#include "nerf/cuda/hash_grid_kernels.h"

#include <algorithm>

#include "core/cuda/device_buffer.h"
#include "nerf/hash_encoding.h"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 128;
constexpr int k_dims = 32;  // encoded features per sample
// Launches for at most this many rows take a thread per sample and level (hash_encode_by_level_kernel).
constexpr uint32_t k_by_level_below = 1u << 16;

__device__ __forceinline__ uint32_t count_of(const HashGridArgs& a) {
    const uint32_t n = a.count ? *a.count : a.n_host;
    return n < a.capacity ? n : a.capacity;
}

template <int F>
struct Features {
    float v[F];
};

template <int F>
__device__ __forceinline__ Features<F> load_features(const float* p) {
    Features<F> f;
    if constexpr (F == 2) {
        const float2 x = *reinterpret_cast<const float2*>(p);
        f.v[0] = x.x, f.v[1] = x.y;
    } else if constexpr (F == 4) {
        const float4 x = *reinterpret_cast<const float4*>(p);
        f.v[0] = x.x, f.v[1] = x.y, f.v[2] = x.z, f.v[3] = x.w;
    } else {
#pragma unroll
        for (int k = 0; k < F; ++k) f.v[k] = p[k];
    }
    return f;
}

template <int F>
__device__ __forceinline__ void add_features(float* p, const float* v) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    // Hopper adds 2 or 4 floats with one vector atomic.
    if constexpr (F == 2) {
        atomicAdd(reinterpret_cast<float2*>(p), make_float2(v[0], v[1]));
    } else if constexpr (F == 4) {
        atomicAdd(reinterpret_cast<float4*>(p), make_float4(v[0], v[1], v[2], v[3]));
    } else {
#pragma unroll
        for (int k = 0; k < F; ++k) atomicAdd(p + k, v[k]);
    }
#else
#pragma unroll
    for (int k = 0; k < F; ++k) atomicAdd(p + k, v[k]);
#endif
}

// Level l's F features at grid position p (the trilinear sum of its 8 corners), rounded to fp16.
template <int F>
__device__ __forceinline__ void encode_level(const HashGridConfig& cfg, const HashLevel& level, int l, const Vec3& p,
                                             const float* grid, __half* h) {
    HashCorner corners[8];
    hash_level_corners(cfg, level, l, p, corners);
    Features<F> f[8];
#pragma unroll
    for (int c = 0; c < 8; ++c) f[c] = load_features<F>(grid + size_t(corners[c].index) * F);
#pragma unroll
    for (int k = 0; k < F; ++k) {
        float acc = 0.0f;
#pragma unroll
        for (int c = 0; c < 8; ++c) acc += corners[c].weight * f[c].v[k];
        h[k] = __float2half_rn(acc);
    }
}

// A thread per sample, its levels one after another.
template <int F>
__global__ void __launch_bounds__(k_block) hash_encode_kernel(HashGridArgs a, HashLevels levels,
                                                              const float* grid, __half* out) {
    const uint32_t n = count_of(a);
    constexpr int n_levels = k_dims / F;
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
        const Vec3 p = a.layout.grid_position(a.positions[i]);
        __align__(16) __half2 enc[k_dims / 2];
#pragma unroll
        for (int l = 0; l < n_levels; ++l)
            encode_level<F>(a.layout.grid, levels.level[l], l, p, grid, reinterpret_cast<__half*>(enc) + l * F);
        uint4* dst = reinterpret_cast<uint4*>(out + size_t(i) * k_dims);
        const uint4* src = reinterpret_cast<const uint4*>(enc);
#pragma unroll
        for (int q = 0; q < k_dims / 8; ++q) dst[q] = src[q];
    }
}

// A thread per sample and level (blockIdx.y the level), for rounds of few samples: each level is a chain of
// dependent loads, and a sample's levels then run side by side instead of one after another (a round of a
// handful of samples took about 17 us in the kernel above on the H200, most of it that chain's latency).
template <int F>
__global__ void __launch_bounds__(k_block) hash_encode_by_level_kernel(HashGridArgs a, HashLevels levels,
                                                                       const float* grid, __half* out) {
    const uint32_t n = count_of(a);
    const int l = int(blockIdx.y);
    const HashLevel level = levels.level[l];
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
        __align__(16) __half h[F < 4 ? 4 : F];
        encode_level<F>(a.layout.grid, level, l, a.layout.grid_position(a.positions[i]), grid, h);
        __half* dst = out + size_t(i) * k_dims + size_t(l) * F;
        if constexpr (F == 8) {
            *reinterpret_cast<uint4*>(dst) = *reinterpret_cast<const uint4*>(h);
        } else if constexpr (F == 4) {
            *reinterpret_cast<uint2*>(dst) = *reinterpret_cast<const uint2*>(h);
        } else {
#pragma unroll
            for (int k = 0; k < F; ++k) dst[k] = h[k];
        }
    }
}

// Sums v over runs of consecutive lanes with the same idx (a segmented scan over the warp); returns true in
// the first lane of each run, which then holds its run's sum. Every lane of the warp must call it.
template <int F>
__device__ __forceinline__ bool warp_run_sum(uint32_t idx, float (&v)[F]) {
    const int lane = threadIdx.x & 31;
    const uint32_t prev = __shfl_up_sync(0xffffffffu, idx, 1);
    const bool head = lane == 0 || prev != idx;
    int seg = head ? lane : 0;  // the first lane of this lane's run: an inclusive max-scan of the heads
#pragma unroll
    for (int off = 1; off < 32; off <<= 1) {
        const int o = __shfl_up_sync(0xffffffffu, seg, off);
        if (lane >= off) seg = max(seg, o);
    }
#pragma unroll
    for (int off = 1; off < 32; off <<= 1) {
        const int s = __shfl_down_sync(0xffffffffu, seg, off);
        float o[F];
#pragma unroll
        for (int k = 0; k < F; ++k) o[k] = __shfl_down_sync(0xffffffffu, v[k], off);
        if (lane + off < 32 && s == seg)
#pragma unroll
            for (int k = 0; k < F; ++k) v[k] += o[k];
    }
    return head;
}

// One thread per sample. On coarse levels (bit set in `merge_levels`) consecutive samples of a ray share their
// cell's corners, and thousands of atomics on the same few entries serialise: there each warp first sums the
// runs of lanes that hit the same entry and adds each run once.
template <int F>
__global__ void __launch_bounds__(k_block) hash_backward_kernel(HashGridArgs a, HashLevels levels,
                                                                const float* d_enc, float* d_grid,
                                                                uint32_t merge_levels) {
    const uint32_t n = count_of(a);
    const uint32_t stride = gridDim.x * blockDim.x;
    // Whole warps iterate together (the merged levels shuffle across the warp); lanes past n carry zeros.
    const uint32_t n_warps = (n + 31) / 32 * 32;
    const HashGridConfig& cfg = a.layout.grid;
    constexpr int n_levels = k_dims / F;
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n_warps; i += stride) {
        const bool valid = i < n;
        const Vec3 p = valid ? a.layout.grid_position(a.positions[i]) : Vec3(0.0f);
        float d[k_dims];
        if (valid) {
            const float4* src = reinterpret_cast<const float4*>(d_enc + size_t(i) * k_dims);
#pragma unroll
            for (int q = 0; q < k_dims / 4; ++q) {
                const float4 v = src[q];
                d[4 * q] = v.x, d[4 * q + 1] = v.y, d[4 * q + 2] = v.z, d[4 * q + 3] = v.w;
            }
        } else {
#pragma unroll
            for (int q = 0; q < k_dims; ++q) d[q] = 0.0f;
        }
#pragma unroll
        for (int l = 0; l < n_levels; ++l) {
            bool any = false;
#pragma unroll
            for (int k = 0; k < F; ++k) any |= d[l * F + k] != 0.0f;
            const bool merge = (merge_levels >> l) & 1u;
            // Samples past a ray's stop and dead ReLUs give exact zeros: no atomics for them.
            if (merge ? !__any_sync(0xffffffffu, any) : !any) continue;
            HashCorner corners[8];
            hash_level_corners(cfg, levels.level[l], l, p, corners);
#pragma unroll
            for (int c = 0; c < 8; ++c) {
                float v[F];
#pragma unroll
                for (int k = 0; k < F; ++k) v[k] = corners[c].weight * d[l * F + k];
                if (merge) {
                    if (!warp_run_sum<F>(corners[c].index, v)) continue;
                    bool nonzero = false;
#pragma unroll
                    for (int k = 0; k < F; ++k) nonzero |= v[k] != 0.0f;
                    if (!nonzero) continue;
                }
                add_features<F>(d_grid + size_t(corners[c].index) * F, v);
            }
        }
    }
}

// A grid-stride loop over the samples: enough blocks to fill the GPU, never one per sample of the capacity.
int blocks_for(uint32_t n) {
    static const int limit = [] {
        int dev = 0, sms = 0;
        cudaGetDevice(&dev);
        cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev);
        return std::max(1, sms) * 16;
    }();
    return std::max(1, std::min(int((n + k_block - 1) / k_block), limit));
}

// Levels whose cells are at least 1/256 of the unit cube: several consecutive samples of a ray (steps of at
// least sqrt(3)/1024) share a cell there, so their gradients are merged per warp before the atomics.
uint32_t merge_levels_of(const HashGridConfig& cfg) {
    uint32_t mask = 0;
    for (int l = 0; l < cfg.levels && l < 32; ++l)
        if (hash_level(cfg, l).scale <= 256.0f) mask |= 1u << l;
    return mask;
}

template <int F>
void launch_encode(const HashGridArgs& a, const HashLevels& levels, const float* grid, __half* out, cudaStream_t s) {
    const int blocks = blocks_for(a.capacity);
    if (a.capacity <= k_by_level_below) {
        const dim3 per_level(unsigned(blocks), unsigned(k_dims / F));  // a row of blocks per level
        hash_encode_by_level_kernel<F><<<per_level, k_block, 0, s>>>(a, levels, grid, out);
    } else {
        hash_encode_kernel<F><<<blocks, k_block, 0, s>>>(a, levels, grid, out);
    }
}

void check_config(const NerfLayout& l) {
    const int f = l.grid.features_per_level;
    if (l.grid.output_dims() != k_dims || (f != 1 && f != 2 && f != 4 && f != 8))
        throw Error("the CUDA hash grid needs levels x features_per_level = 32 with 1, 2, 4 or 8 features per "
                    "level (got " + std::to_string(l.grid.levels) + " x " + std::to_string(f) + ")");
}

}  // namespace

void hash_encode(const HashGridArgs& a, const float* grid_params, __half* encoded, cudaStream_t s) {
    check_config(a.layout);
    if (a.capacity == 0) return;
    const HashLevels levels = hash_levels(a.layout.grid);
    switch (a.layout.grid.features_per_level) {
        case 1: launch_encode<1>(a, levels, grid_params, encoded, s); break;
        case 2: launch_encode<2>(a, levels, grid_params, encoded, s); break;
        case 4: launch_encode<4>(a, levels, grid_params, encoded, s); break;
        default: launch_encode<8>(a, levels, grid_params, encoded, s); break;
    }
    NPT_CUDA_CHECK_LAUNCH("hash_encode_kernel");
}

void hash_backward(const HashGridArgs& a, const float* d_encoded, float* d_grid_params, cudaStream_t s) {
    check_config(a.layout);
    if (a.capacity == 0) return;
    const HashLevels levels = hash_levels(a.layout.grid);
    const int blocks = blocks_for(a.capacity);
    const uint32_t merge = merge_levels_of(a.layout.grid);
    switch (a.layout.grid.features_per_level) {
        case 1: hash_backward_kernel<1><<<blocks, k_block, 0, s>>>(a, levels, d_encoded, d_grid_params, merge); break;
        case 2: hash_backward_kernel<2><<<blocks, k_block, 0, s>>>(a, levels, d_encoded, d_grid_params, merge); break;
        case 4: hash_backward_kernel<4><<<blocks, k_block, 0, s>>>(a, levels, d_encoded, d_grid_params, merge); break;
        default: hash_backward_kernel<8><<<blocks, k_block, 0, s>>>(a, levels, d_encoded, d_grid_params, merge); break;
    }
    NPT_CUDA_CHECK_LAUNCH("hash_backward_kernel");
}

}  // namespace npt::nerf::cuda
