// Runs the shared NPT_HD math (BSDFs, light sampling, camera rays) on the GPU for a batch of inputs, so a
// test can compare it with the same functions on the CPU. Plain C++ interface: callers need no CUDA headers.
#pragma once

#include <vector>

#include "core/vec.h"
#include "lights/light.h"
#include "materials/bsdf_types.h"
#include "media/volume_integrator.h"
#include "render/scene_view.h"

namespace npt::gpu {

// True when a CUDA device can be used here.
bool device_available();

struct BsdfCase {
    materials::Bsdf bsdf;
    Vec3 wo, wi;
    float u_lobe;
    Vec2 u;
};
struct BsdfResult {
    Rgb f;
    float pdf;
    bool sampled;
    materials::BsdfSample sample;
};
std::vector<BsdfResult> run_bsdf_cases(const std::vector<BsdfCase>& cases);

struct CameraCase {
    int i, j;
    Vec2 u;
};
std::vector<Ray> run_camera_cases(const render::CameraView& camera, const std::vector<CameraCase>& cases);

struct LightCase {
    Vec3 ref_p;
    float u_select;
    Vec2 u;
};
struct LightResult {
    bool sampled;
    lights::LightSample sample;
};
// The first `dimensions` 2D values of SobolSampler(seed, px, py, sample) for each case, in order.
struct SamplerCase {
    uint32_t px, py, sample;
};
std::vector<Vec2> run_sampler_cases(uint64_t seed, int dimensions, const std::vector<SamplerCase>& cases);

struct VolumeCase {
    Ray ray;
    float t_end;
    float xi;
    bool shadow;
};
// `volumes` point at host memory; grids and majorants (NeRF volumes: parameters and occupancy) are copied to
// the device for the run.
std::vector<media::VolumeResult> run_volume_cases(const std::vector<media::VolumeView>& volumes,
                                                  const std::vector<VolumeCase>& cases);

// `lights` points at host memory; its arrays are copied to the device for the run.
std::vector<LightResult> run_light_cases(const lights::LightSetView& lights,
                                         const std::vector<LightCase>& cases);

}  // namespace npt::gpu
