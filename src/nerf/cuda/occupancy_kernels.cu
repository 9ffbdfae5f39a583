#include "nerf/cuda/occupancy_kernels.h"

#include "core/cuda/device_buffer.h"
#include "core/rng.h"
#include "nerf/occupancy_view.h"

namespace npt::nerf::cuda {

namespace {

constexpr int k_block = 256;

__device__ __forceinline__ uint32_t uniform_index(Pcg32& rng, uint32_t n) {
    return uint32_t((uint64_t(rng.next_u32()) * n) >> 32);
}

__global__ void plan_kernel(OccupancyDevice g, uint64_t seed, bool warmup, uint32_t first, uint32_t n,
                            uint32_t* cells, Vec3* positions) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const uint32_t k = first + i;
    Pcg32 rng(seed, k);
    uint32_t cell;
    if (warmup) {
        cell = k;
    } else if (k < g.cells / 4) {
        cell = uniform_index(rng, g.cells);
    } else {
        const uint32_t oc = *g.occupied_count;
        cell = oc ? g.occupied_list[uniform_index(rng, oc)] : uniform_index(rng, g.cells);
    }
    const uint32_t r = uint32_t(g.resolution), per_cascade = r * r * r;
    const int c = int(cell / per_cascade);
    const uint32_t local = cell % per_cascade;
    const float xyz[3] = {float(local % r), float((local / r) % r), float(local / (r * r))};
    const OccupancyGridView view{nullptr, g.cascades, g.resolution};
    const float size = view.cascade_size(c);
    Vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = 0.5f + ((xyz[a] + rng.next_float()) / float(r) - 0.5f) * size;
    // x + u can round up to x + 1 for large x; the cell centre keeps the position inside its cell.
    if (view.cell_index(p, c) != int64_t(cell))
        for (int a = 0; a < 3; ++a) p[a] = 0.5f + ((xyz[a] + 0.5f) / float(r) - 0.5f) * size;
    cells[i] = cell;
    positions[i] = p;
}

__global__ void splat_kernel(float* estimate, const uint32_t* cells, const float* sigma, uint32_t n,
                             float min_step) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const float e = sigma[i] * min_step;
    // Non-negative floats order as their bit patterns; a NaN from the network is dropped (as fmax on the CPU).
    if (e > 0.0f) atomicMax(reinterpret_cast<int*>(estimate + cells[i]), __float_as_int(e));
}

__global__ void decay_kernel(OccupancyDevice g, float decay) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    float d = 0.0f;
    if (i < g.cells) {
        d = fmaxf(g.density[i] * decay, g.estimate[i]);
        g.density[i] = d;
        g.estimate[i] = 0.0f;
    }
    double s = d;
#pragma unroll
    for (int off = 16; off > 0; off >>= 1) s += __shfl_down_sync(0xffffffffu, s, off);
    __shared__ double warp_sums[k_block / 32];
    if ((threadIdx.x & 31) == 0) warp_sums[threadIdx.x >> 5] = s;
    __syncthreads();
    if (threadIdx.x == 0) {
        double b = 0.0;
        for (int w = 0; w < k_block / 32; ++w) b += warp_sums[w];
        if (b != 0.0) atomicAdd(g.density_sum, b);
    }
}

__global__ void threshold_kernel(OccupancyDevice g, float threshold) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const float mean = float(*g.density_sum / double(g.cells));
    const float cut = fminf(threshold, mean);
    // No estimate yet anywhere: nothing is known to be empty, so nothing is skipped (as the CPU grid).
    bool occ = false;
    if (i < g.cells) {
        occ = mean == 0.0f || g.density[i] > cut;
        g.occupied[i] = occ ? 1 : 0;
    }
    const unsigned mask = __ballot_sync(0xffffffffu, occ);
    // A warp covers 32 consecutive cells starting at a multiple of 32: one word of the bit field.
    if ((threadIdx.x & 31) == 0 && i < g.cells) g.occupied_bits[i >> 5] = mask;
    if (occ && g.occupied_box) {
        const uint32_t r = uint32_t(g.resolution), cells = r * r * r;
        const int c = int(i / cells);
        const uint32_t local = i % cells;
        const float size = float(1 << c), lo = 0.5f - 0.5f * size, w = size / float(r);
        const uint32_t xyz[3] = {local % r, (local / r) % r, local / (r * r)};
        for (int a = 0; a < 3; ++a) {
            atomicMin(g.occupied_box + a, float_key(lo + float(xyz[a]) * w));
            atomicMax(g.occupied_box + 3 + a, float_key(lo + float(xyz[a] + 1) * w));
        }
    }
    if (occ && g.coarse_bits) {
        const uint32_t r = uint32_t(g.resolution), cells = r * r * r, k = OccupancyGridView::k_coarse;
        const uint32_t c = i / cells, local = i % cells, rc = r / k;
        const uint32_t x = (local % r) / k, y = ((local / r) % r) / k, z = (local / (r * r)) / k;
        const uint32_t ci = c * rc * rc * rc + x + y * rc + z * rc * rc;
        atomicOr(g.coarse_bits + (ci >> 5), 1u << (ci & 31));
    }
    if (!occ) return;  // the shuffle below is among the lanes in mask only
    const int lane = threadIdx.x & 31;
    const int leader = __ffs(mask) - 1;
    uint32_t base = 0;
    if (lane == leader) base = atomicAdd(g.occupied_count, uint32_t(__popc(mask)));
    base = __shfl_sync(mask, base, leader);
    g.occupied_list[base + __popc(mask & ((1u << lane) - 1u))] = i;
}

unsigned blocks_for(uint32_t n) { return (n + k_block - 1) / k_block; }

}  // namespace

size_t coarse_words(int cascades, int resolution) {
    const size_t rc = size_t(resolution / OccupancyGridView::k_coarse);
    return (size_t(cascades) * rc * rc * rc + 31) / 32;
}

bool coarse_cells_fit(int resolution) { return resolution % (2 * OccupancyGridView::k_coarse) == 0; }

void occupancy_plan(const OccupancyDevice& g, uint64_t seed, bool warmup, uint32_t first, uint32_t n,
                    uint32_t* cells, Vec3* positions, cudaStream_t s) {
    if (n == 0) return;
    plan_kernel<<<blocks_for(n), k_block, 0, s>>>(g, seed, warmup, first, n, cells, positions);
    NPT_CUDA_CHECK_LAUNCH("occupancy plan_kernel");
}

void occupancy_splat(const OccupancyDevice& g, const uint32_t* cells, const float* sigma, uint32_t n,
                     float min_step, cudaStream_t s) {
    if (n == 0) return;
    splat_kernel<<<blocks_for(n), k_block, 0, s>>>(g.estimate, cells, sigma, n, min_step);
    NPT_CUDA_CHECK_LAUNCH("occupancy splat_kernel");
}

void occupancy_apply(const OccupancyDevice& g, float decay, float threshold, cudaStream_t s) {
    gpu::cuda_check(cudaMemsetAsync(g.density_sum, 0, sizeof(double), s), "cudaMemsetAsync");
    gpu::cuda_check(cudaMemsetAsync(g.occupied_count, 0, sizeof(uint32_t), s), "cudaMemsetAsync");
    if (g.coarse_bits)
        gpu::cuda_check(cudaMemsetAsync(g.coarse_bits, 0, coarse_words(g.cascades, g.resolution) * 4, s),
                        "cudaMemsetAsync");
    if (g.occupied_box) {
        // min keys start at the largest key, max keys at the smallest (an empty grid keeps an empty box).
        gpu::cuda_check(cudaMemsetAsync(g.occupied_box, 0xff, 3 * sizeof(uint32_t), s), "cudaMemsetAsync");
        gpu::cuda_check(cudaMemsetAsync(g.occupied_box + 3, 0, 3 * sizeof(uint32_t), s), "cudaMemsetAsync");
    }
    decay_kernel<<<blocks_for(g.cells), k_block, 0, s>>>(g, decay);
    NPT_CUDA_CHECK_LAUNCH("occupancy decay_kernel");
    threshold_kernel<<<blocks_for(g.cells), k_block, 0, s>>>(g, threshold);
    NPT_CUDA_CHECK_LAUNCH("occupancy threshold_kernel");
}

}  // namespace npt::nerf::cuda
