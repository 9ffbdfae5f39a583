// The NeRF's two MLPs (density: 32 hash features -> 64 -> 16; colour: 16 density outputs + 16 SH values -> 64
// -> 64 -> 3) on tensor cores: fully fused kernels in which each warp carries 16 samples through every layer
// in shared memory (fp16 operands, fp32 accumulation, WMMA 16x16x16). Inference writes sigma and colour; the
// training kernel runs forward and backward in one pass from given dL/dsigma and dL/drgb, accumulates the
// weight gradients of its tiles in registers (a persistent grid) and writes dL/d(encoding) for the hash grid.
// The maths is that of nerf/field_batch.cpp (the fp32 CPU reference); fp16 rounding is the only difference.
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>
#include <string>

#include "core/vec.h"
#include "nerf/nerf_field.h"

namespace npt::nerf::cuda {

constexpr int k_mlp_inputs = 32;           // hash-grid features
constexpr int k_mlp_width = 64;            // hidden layers
constexpr int k_mlp_density_outputs = 16;  // output 0 is log-density; all feed the colour MLP
constexpr int k_mlp_color_inputs = 32;     // 16 density outputs + 16 SH coefficients
constexpr int k_mlp_rows_per_tile = 128;   // samples per block iteration; buffers are sized in multiples of it
// fp16 copy of the MLP weights in the parameter order (density layers, then colour layers, each row-major
// [outputs][inputs]), the colour output layer padded from 3 to 16 rows with zeros.
constexpr int k_mlp_half_weights = 64 * 32 + 16 * 64 + 64 * 32 + 64 * 64 + 16 * 64;  // 10240

// True when the model's network has the shape these kernels are built for; otherwise `why` says what differs.
bool mlp_shape_supported(const NerfLayout& layout, std::string* why);

// Number of MLP parameters (fp32, params order) for the supported shape: 9408.
constexpr int k_mlp_param_count = 64 * 32 + 16 * 64 + 64 * 32 + 64 * 64 + 3 * 64;

struct MlpInferenceArgs {
    const __half* weights = nullptr;     // k_mlp_half_weights
    const __half* encoded = nullptr;     // [n][32], row-major
    const uint32_t* sample_ray = nullptr;  // per sample: index into ray_dir (colour only)
    const Vec3* ray_dir = nullptr;       // unit directions (model space)
    const uint32_t* count = nullptr;     // device: n; when null, n_host is used
    uint32_t n_host = 0;
    uint32_t capacity = 0;               // rows the buffers hold (n is clamped to it)
    float* sigma = nullptr;              // [n] activated density (exp)
    Rgb* rgb = nullptr;                  // [n] sigmoid colour; untouched when density_only
};
void mlp_inference(const MlpInferenceArgs& a, bool density_only, cudaStream_t stream);

struct MlpTrainArgs {
    const __half* weights = nullptr;
    const __half* encoded = nullptr;
    const uint32_t* sample_ray = nullptr;
    const Vec3* ray_dir = nullptr;
    const uint32_t* count = nullptr;      // device: n
    uint32_t capacity = 0;
    const float* d_sigma = nullptr;       // dL/dsigma per sample, L = the sum of the rays' losses
    const Rgb* d_rgb = nullptr;           // dL/drgb per sample
    const uint32_t* rays = nullptr;       // device: the number of rays; gradients are divided by it (mean loss)
    float loss_scale = 128.0f;            // gradients are multiplied by this before fp16 rounding, and divided after
    float* d_encoded = nullptr;           // [n][32] fp32 out: dL/d(encoding) of the mean loss
    float* d_weights = nullptr;           // [k_mlp_param_count] fp32: the weight gradient is ADDED here
};
void mlp_train(const MlpTrainArgs& a, cudaStream_t stream);

}  // namespace npt::nerf::cuda
