// The per-ray stages of a GPU training step: pick random pixels of random training images and march their
// rays through the occupancy grid into a sample buffer (each ray reserves its samples with one atomic add);
// then, once the field has been evaluated, composite every ray, take the Huber loss and its gradient with
// respect to each sample's density and colour (composite.h, the CPU trainer's code), and compact the samples
// that contributed (those before the ray's early stop) for the training pass. The random numbers are the CPU
// trainer's (train_pixel.h). With the surface-smoothness loss a thread composites a group of three rays.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "core/vec.h"
#include "nerf/occupancy_view.h"
#include "nerf/pixel_ray.h"
#include "nerf/ray_march.h"
#include "nerf/train_pixel.h"

namespace npt::nerf::cuda {

constexpr uint32_t k_ray_dropped = 0xffffffffu;  // count of a ray whose samples did not fit

struct DeviceImages {
    const uint32_t* rgba = nullptr;     // 8-bit RGBA packed little-endian, image after image
    const RayCamera* cameras = nullptr;
    uint32_t count = 0;
    int width = 0, height = 0;
    SubjectFocus focus;  // rects on the device (or null)
};

// Filled by the kernels of one step; read back once per step.
struct StepCounters {
    uint32_t marched = 0;    // samples reserved (may exceed the capacity: those rays were dropped)
    uint32_t rays_kept = 0;  // rays whose samples fit
    uint32_t compacted = 0;  // samples before their ray's stop: the training batch
    uint32_t nonfinite = 0;  // set by Adam when a gradient is not finite
    double loss = 0;         // sum over kept rays of the Huber loss (summed over channels)
    double squared_error = 0;
    double smoothness = 0;   // sum over groups of the surface-smoothness loss
};

struct RayBuffers {
    uint32_t* first = nullptr;  // first sample
    uint32_t* count = nullptr;  // samples, or k_ray_dropped
    Rgb* target = nullptr;
    Rgb* background = nullptr;
    Vec3* dir = nullptr;        // unit, model space
};

struct SampleBuffers {
    Vec3* pos = nullptr;
    float* dt = nullptr;
    uint32_t* ray = nullptr;
    uint32_t capacity = 0;
};

struct CompactBuffers {
    Vec3* pos = nullptr;
    uint32_t* ray = nullptr;
    float* d_sigma = nullptr;
    Rgb* d_rgb = nullptr;
    uint32_t capacity = 0;
};

// Samples a ray keeps in its own scratch slots while it is marched once; longer rays count the rest and
// march that part again after reserving.
constexpr int k_march_scratch = 32;

struct MarchRaysArgs {
    DeviceImages images;
    MarchParams march;
    OccupancyGridView grid;
    uint64_t step_seed = 0;
    bool random_background = true;
    float group_spacing = 0.0f;  // > 0: rays in groups for the smoothness loss (train_pixel.h)
    uint32_t n_rays = 0;
    RayBuffers rays;
    SampleBuffers samples;
    float4* scratch = nullptr;  // k_march_scratch per ray: position and dt
    const uint32_t* occupied_box = nullptr;  // float keys of the box around the occupied cells (or null)
    StepCounters* counters = nullptr;
};
void march_training_rays(const MarchRaysArgs& a, cudaStream_t s);

struct CompositeLossArgs {
    uint32_t n_rays = 0;
    RayBuffers rays;
    SampleBuffers samples;
    const float* sigma = nullptr;  // per marched sample, from the inference pass
    const Rgb* rgb = nullptr;
    float min_transmittance = 1e-4f;
    float huber_delta = 1.0f;
    float smoothness_weight = 0.0f;  // > 0: the surface-smoothness loss (surface_smoothness.h), rays in groups
    float smoothness_scale = 0.2f;
    CompactBuffers compact;
    StepCounters* counters = nullptr;
};
void composite_loss(const CompositeLossArgs& a, cudaStream_t s);

}  // namespace npt::nerf::cuda
