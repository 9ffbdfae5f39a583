// Everything that defines a NeRF model and how it is trained, as one plain struct that round-trips through
// JSON (`nerfpt train --config`, and the copy stored in every model file). Defaults follow instant-ngp's
// published NeRF configuration (configs/nerf/base.json plus the testbed's overrides); the CPU-specific
// choices (batch size) are marked as such.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "nerf/hash_encoding.h"

namespace npt::nerf {

// A fully connected network without biases (as tiny-cuda-nn's MLPs): `hidden_layers` layers of `width`
// neurons with ReLU, then a linear output layer; the caller applies the output activation.
struct MlpConfig {
    int hidden_layers = 1;
    int width = 64;
    int outputs = 16;
};

struct EncodingConfig {
    HashGridConfig grid;  // per_level_scale is derived, see finest_resolution
    // The finest level's resolution is finest_resolution * aabb_scale (instant-ngp: 2048 * aabb_scale);
    // grid.per_level_scale is recomputed from it when a model is created for a data set.
    float finest_resolution = 2048.0f;
    int sh_degree = 4;  // view-direction encoding; only 4 (16 coefficients) is implemented
};

struct OccupancyConfig {
    int resolution = 128;         // cells per axis per cascade
    float decay = 0.95f;          // every update multiplies the stored density by this before taking the max
    float threshold = 0.01f;      // a cell is occupied when its optical thickness over the minimum step exceeds
                                  // min(threshold, mean over the grid)
    // Both count instant-ngp steps of 2^18 samples: with training.batch_samples = 2^16 an update comes every
    // 16 * 4 = 64 of our steps, so the grid costs the same share of the work as in instant-ngp.
    int update_interval = 16;     // steps between updates
    int warmup_steps = 256;       // updates before this step sample every cell; later ones a quarter of them
};

struct MarchConfig {
    int max_steps = 1024;            // the minimum step is sqrt(3) / max_steps (instant-ngp's NERF_STEPS)
    float cone_angle = -1.0f;        // step = clamp(t * cone_angle, min, max); < 0: 1/256 when aabb_scale > 1
                                     // else 0 (instant-ngp)
    float min_transmittance = 1e-4f; // a ray stops when its transmittance falls below this
    int max_samples_per_ray = 1024;  // training samples generated per ray at most
};

struct OptimizerConfig {
    float learning_rate = 1e-2f;
    float beta1 = 0.9f;
    float beta2 = 0.99f;
    float epsilon = 1e-15f;
    float l2_reg = 1e-6f;         // added to the gradient of MLP weights only (not the hash grid)
    int decay_start = 20000;      // lr *= decay_base ^ floor((step - decay_start) / decay_interval + 1)
    int decay_interval = 10000;   //   once step >= decay_start
    float decay_base = 0.33f;
    float ema_decay = 0.95f;      // evaluation uses the bias-corrected exponential moving average of parameters
    // CPU trainer: a hash-grid parameter whose gradient is exactly zero this step (no sample reached its entry)
    // keeps its value and moments, tiny-cuda-nn's rule for non-matrix parameters; the step then touches only
    // the entries the batch reached instead of every one: 7.5% more steps on a capture and 30% on lego in the
    // same time, and better held-out PSNR on both (docs/benchmarks.md, "Sparse Adam on the CPU"). The CUDA
    // trainer updates every parameter.
    bool sparse_grid = true;
};

struct LossConfig {
    float huber_delta = 1.0f;  // instant-ngp's Huber with alpha 1: quadratic for |error| < delta
    // The surface-smoothness loss (surface_smoothness.h): its weight per group of three rays against the
    // photometric loss per ray (0: off, the rays are drawn one by one as before), the largest spacing of the
    // group's pixels, and the bend beyond which the loss lets go (depth edges, creases).
    float surface_smoothness = 0.0f;
    float smoothness_spacing = 4.0f;
    float smoothness_scale = 0.2f;
};

struct TrainingConfig {
    // Samples per step (after marching; rays are added until the batch is full). instant-ngp uses 2^18 on a
    // GPU; 2^16 keeps a CPU step under a second so progress and checkpoints stay responsive.
    int batch_samples = 1 << 16;
    int max_rays_per_batch = 1 << 14;
    // The CUDA trainer's batch: samples per step that contribute to the loss (after each ray's early stop:
    // instant-ngp's compacted batch). Rays per step adapt to reach it, up to cuda_batch_samples rays.
    int cuda_batch_samples = 1 << 18;
    uint64_t seed = 1337;
    int checkpoint_interval = 500;  // steps between checkpoints (also on Ctrl-C and at the end)
    bool random_background = true;  // train against a random colour per ray, so alpha is learned
    // A gain per training image and channel, learned beside the network (image_exposure.h): a phone video's
    // exposure and white balance drift. CPU trainer only.
    bool exposure_per_image = false;
    float exposure_learning_rate = 2e-3f;
    // With subject rectangles in the data set (nerfpt capture's object box): the share of each step's rays
    // drawn inside them, the rest over the whole image (train_pixel.h).
    float subject_rays = 0.5f;
};

struct NerfConfig {
    EncodingConfig encoding;
    MlpConfig density_mlp{1, 64, 16};  // output 0 is log-density (exp activation); all 16 feed the colour MLP
    MlpConfig color_mlp{2, 64, 3};     // input: density outputs (16) + SH of the direction (16); sigmoid
    OccupancyConfig occupancy;
    MarchConfig march;
    OptimizerConfig optimizer;
    LossConfig loss;
    TrainingConfig training;
};

// JSON with the same field names as the structs, grouped as {"encoding": {"levels": ...}, ...} (see
// docs/formats.md). Missing fields keep their defaults; unknown fields, wrong types and out-of-range values
// throw npt::Error naming `source` (a file name, for messages) and the field.
// Missing fields keep their values in `base`.
NerfConfig config_from_json(const nlohmann::json& j, const std::string& source, const NerfConfig& base = {});
nlohmann::json config_to_json(const NerfConfig& c);
NerfConfig load_config(const std::string& path, const NerfConfig& base = {});  // the file, then config_from_json

// The defaults of a model trained on a GPU: instant-ngp's current hash grid of 8 levels x 4 features (half the
// lookups of 16 x 2; on lego the same PSNR at equal training time on an H200, and more steps per second:
// docs/benchmarks.md), everything else as NerfConfig{}. A model keeps its config, so it trains and renders
// the same on either backend.
NerfConfig cuda_default_config();

// The defaults of a model trained on the CPU: a hash table of 2^17 entries per level instead of 2^19. In the
// minutes a CPU trains, the smaller table makes steps cheaper (fewer bytes for Adam and the grid's backward)
// and wins at every time measured: lego 200x200 24.96 -> 25.74 dB at 1 min, 30.05 -> 30.17 dB at 10 min; the
// beer capture 31.19 -> 31.84 dB held out after 300 s (docs/benchmarks.md, "A smaller hash grid for the CPU's
// minutes"). Everything else as NerfConfig{}.
NerfConfig cpu_default_config();

}  // namespace npt::nerf
