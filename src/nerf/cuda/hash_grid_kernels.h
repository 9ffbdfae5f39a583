// The multiresolution hash encoding on the GPU: forward (fp32 table, fp16 features out, the layout the fused
// MLP reads) and backward (fp32 atomics into the table's gradient). One thread per sample walks every level
// with the shared NPT_HD corner function (hash_encoding.h), so the corners are exactly the CPU's.
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>

#include "core/vec.h"
#include "nerf/nerf_field.h"

namespace npt::nerf::cuda {

struct HashGridArgs {
    NerfLayout layout;                 // grid config and the aabb mapping (grid_position)
    const Vec3* positions = nullptr;   // model space
    const uint32_t* count = nullptr;   // device: n; when null, n_host is used
    uint32_t n_host = 0;
    uint32_t capacity = 0;
};

// Requires layout.grid.output_dims() == 32 and features_per_level in {1, 2, 4, 8}.
void hash_encode(const HashGridArgs& a, const float* grid_params, __half* encoded /*[n][32]*/, cudaStream_t s);
void hash_backward(const HashGridArgs& a, const float* d_encoded /*[n][32]*/, float* d_grid_params,
                   cudaStream_t s);

}  // namespace npt::nerf::cuda
