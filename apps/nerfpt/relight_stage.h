// `nerfpt train --relightable`: the relight stage after the NeRF's own training (nerf/relight/): surface points
// from the training images, then the intrinsic fields, the capture environment and the exposures, with progress
// lines; the result goes into the model's relight section.
#pragma once

#include <cstdint>

#include "nerf/backend/nerf_backend.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/relight_samples.h"

namespace npt::cli {

class InterruptGuard;

struct RelightStageOptions {
    uint64_t steps = 1500;  // optimiser steps of the stage
    int points = 16384;
    int directions = 16;
    nerf::NormalEstimator normals = nerf::NormalEstimator::depth_stencil;
    int batch = 1024;              // points per optimiser step
    float normal_smoothing = 0.02f;  // nerf::RelightSampleSettings::normal_smoothing
    bool quiet = false;
    nerf::Backend backend = nerf::Backend::cpu;  // where the NeRF is evaluated while gathering surface points
};

// Returns false when interrupted (the model keeps whatever relight section it had before).
bool run_relight_stage(nerf::NerfModel& model, const nerf::Dataset& data, const RelightStageOptions& options,
                       InterruptGuard& interrupts);

}  // namespace npt::cli
