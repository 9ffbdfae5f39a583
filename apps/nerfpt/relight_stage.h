// `nerfpt train --relightable`: the relight stage after the NeRF's own training (nerf/relight/): surface
// points from the training images, then the intrinsic fields, the capture environment and the exposures, with
// progress lines; the result goes into the model's relight section.
#pragma once

#include <cstdint>

#include "nerf/backend/nerf_backend.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/relight_samples.h"
#include "nerf/relight/relight_trainer.h"

namespace npt::cli {

class InterruptGuard;

// The defaults of points, directions and batch per backend. Measured on dev (docs/benchmarks.md, issue 24):
// on the GPU, 16x more points at a quarter of the directions bought 2 dB of albedo, and 4x more again at half
// the directions (1 M x 8) another 0.9 dB and 1 degree of normals for 11 s more; later, with borrowing pixels
// and the prefiltered fit, 16 directions instead of 8 bought 1.0 dB of albedo for 3-5 s of gather (32: 1.6 dB
// for 18 s). The CPU's keep the gather to minutes on 2 cores.
constexpr int k_relight_points_gpu = 1048576, k_relight_points_cpu = 32768;
constexpr int k_relight_directions_gpu = 16, k_relight_directions_cpu = 16;
constexpr int k_relight_batch_gpu = 4096, k_relight_batch_cpu = 1024;
// Borrowing pixels (relight_samples.h): on the CPU 262 144 bought 2.6 dB of albedo and 2 degrees of normals
// for a third more gather time; on the GPU 2.2 M bought 0.2 dB of albedo and 0.5 degrees of normals over 1 M lit
// points, for 13 s.
constexpr int k_relight_pixels_gpu = 2097152, k_relight_pixels_cpu = 262144;
// Pooled neighbours (RelightSampleSettings::pooled_neighbours): on the CPU 8 bought 0.3 dB of albedo for 6 s
// of fitting (4: 0.3 dB). On an H100 with 16 directions, 8 bought 0.7 dB of albedo (4: 0.6 dB) for 5 s of
// fitting; train + relight 103 s, inside the 120 s budget (docs/benchmarks.md, "pooled neighbours on a GPU").
constexpr int k_relight_pool = 8;  // the same on both backends
// Footprint queries (RelightTrainSettings::footprint_queries): on the CPU, averaging the fields over a 2x2 grid of
// each training pixel's square bought 0.6 dB of albedo (fields) and 0.9 dB (render AOV), +0.2 dB relit, for 6 s
// more fitting; 3x3 no more than 2x2 (docs/benchmarks.md, "each pixel's square").
constexpr int k_relight_footprint = 4;  // the same on both backends

struct RelightStageOptions {
    uint64_t steps = 1500;  // optimiser steps of the stage
    int points = 0;         // surface points; 0: k_relight_points_* of the backend
    int batch = 0;          // points per optimiser step; 0: k_relight_batch_* of the backend
    int directions = 0;     // light directions per point; 0: k_relight_directions_* of the backend
    int event_draws = nerf::RelightSampleSettings{}.event_draws;
    nerf::NormalEstimator normals = nerf::RelightSampleSettings{}.normals;
    float normal_smoothing = nerf::RelightSampleSettings{}.normal_smoothing;
    nerf::SpecularEstimate specular = nerf::RelightTrainSettings{}.specular;
    nerf::DiffuseEstimate diffuse = nerf::RelightTrainSettings{}.diffuse;
    nerf::IntrinsicDiffuse diffuse_lobe = nerf::IntrinsicConfig{}.diffuse;  // the BSDF the model is fitted for
    float roughness_prior = nerf::RelightTrainSettings{}.roughness_prior;
    float huber_delta = nerf::RelightTrainSettings{}.huber_delta;
    float ground_share = nerf::RelightTrainSettings{}.ground_share;
    int footprint_queries = k_relight_footprint;
    float average_decay = nerf::RelightTrainSettings{}.average_decay;
    uint64_t seed = 0;          // of the stage's draws, when seed_given
    bool seed_given = false;    // else the model's training seed
    int borrowing_pixels = -1;  // -1: k_relight_pixels_* of the backend
    int pooled_neighbours = k_relight_pool;
    int table_log2 =
        nerf::IntrinsicConfig{}.grid.log2_table_size;  // hash entries per level of the intrinsic grid
    float finest_resolution =
        nerf::IntrinsicConfig{}.finest_resolution;  // of the intrinsic grid, x aabb_scale
    bool quiet = false;
    nerf::Backend backend = nerf::Backend::cpu;  // where the NeRF is evaluated while gathering surface points
};

// Returns false when interrupted (the model keeps whatever relight section it had before).
bool run_relight_stage(nerf::NerfModel& model, const nerf::Dataset& data, const RelightStageOptions& options,
                       InterruptGuard& interrupts);

}  // namespace npt::cli
