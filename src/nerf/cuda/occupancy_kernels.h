// The occupancy grid's update on the GPU (occupancy_grid.cpp is the CPU reference): choose cells and a random
// point in each (every cell during warm-up; later a random quarter plus as many random occupied cells), take
// the network's density there (the trainer runs the hash grid and the density MLP on the points), keep
// max(old * decay, sigma * min_step) per cell, and mark cells above min(threshold, mean) occupied. Unlike the
// CPU, warm-up estimates every cell of every cascade at each update (instant-ngp's rule): cheap on a GPU.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/vec.h"

namespace npt::nerf::cuda {

struct OccupancyDevice {
    float* density = nullptr;         // cascades * R^3
    uint8_t* occupied = nullptr;
    uint32_t* occupied_bits = nullptr;  // the same flags, one bit per cell (what the marches read)
    uint32_t* coarse_bits = nullptr;    // OccupancyGridView::coarse_bits, or null when the resolution has no
                                        // whole coarse cells
    float* estimate = nullptr;        // scratch: the largest new estimate per cell, 0 = none
    uint32_t* occupied_list = nullptr;  // indices of occupied cells after the last update
    uint32_t* occupied_count = nullptr;
    double* density_sum = nullptr;
    // The box around every occupied cell (model space), as order-preserving integer keys of its floats:
    // min x, y, z, then max x, y, z (float_key / float_of_key).
    uint32_t* occupied_box = nullptr;
    int cascades = 1;
    int resolution = 128;
    uint32_t cells = 0;
};

// Floats as unsigned integers of the same order (for atomicMin/Max on floats of either sign), and back.
inline __host__ __device__ uint32_t float_key(float f) {
    uint32_t u;
    memcpy(&u, &f, 4);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline __host__ __device__ float float_of_key(uint32_t k) {
    const uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    float f;
    memcpy(&f, &u, 4);
    return f;
}

// Words of the coarse bit field, and whether a resolution has whole coarse cells (OccupancyGridView).
size_t coarse_words(int cascades, int resolution);
bool coarse_cells_fit(int resolution);

// Points for samples [first, first + n) of an update: cell i (warm-up: the cells in order; otherwise uniform
// for the first cells/4 samples, then random occupied cells).
void occupancy_plan(const OccupancyDevice& g, uint64_t seed, bool warmup, uint32_t first, uint32_t n,
                    uint32_t* cells, Vec3* positions, cudaStream_t s);
// estimate[cell[i]] = max(estimate, sigma[i] * min_step).
void occupancy_splat(const OccupancyDevice& g, const uint32_t* cells, const float* sigma, uint32_t n,
                     float min_step, cudaStream_t s);
// density = max(density * decay, estimate); estimate = 0; then occupied flags, the list and its count.
void occupancy_apply(const OccupancyDevice& g, float decay, float threshold, cudaStream_t s);

}  // namespace npt::nerf::cuda
