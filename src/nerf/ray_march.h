// Ray marching through the occupancy grid (instant-ngp's scheme): steps of dt = clamp(t * cone_angle,
// sqrt(3)/max_steps, max_step) along a model-space ray, inside the model's aabb, skipping unoccupied cells
// to the next cell boundary of their cascade. NPT_HD: used by training, rendering and the GPU.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/occupancy_view.h"

namespace npt::nerf {

struct MarchParams {
    Vec3 aabb_min{0, 0, 0};  // model-space box the field lives in: 0.5 -+ aabb_scale / 2
    Vec3 aabb_max{1, 1, 1};
    float min_step = 1.7320508f / 1024.0f;
    float max_step = 1.7320508f * 128.0f / 128.0f;  // sqrt(3) * 2^(cascades-1) / resolution
    float cone_angle = 0.0f;
    int max_samples = 1024;
};

struct MarchSample {
    Vec3 position;  // model space
    float t;        // distance along the (unit-direction) ray
    float dt;       // the step this sample stands for
};

NPT_HD NPT_INLINE float march_step(const MarchParams& mp, float t) {
    return clampf(t * mp.cone_angle, mp.min_step, mp.max_step);
}

// Entry and exit distances of the ray in the aabb, clipped to t >= 0; false when it misses.
NPT_HD inline bool march_bounds(const MarchParams& mp, const Ray& ray, float* t_near, float* t_far);

// Writes up to mp.max_samples samples of `ray` (unit direction, model space) into out and returns how many.
// jitter in [0,1) offsets the first sample by jitter * step so that training sees every depth. Samples lie in
// occupied cells only; their dt is the step taken at them.
NPT_HD inline int march_ray(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray, float jitter,
                     MarchSample* out);

}  // namespace npt::nerf

