// What the OptiX programs read (one struct in constant memory, set per launch) and the ray types of the
// pipeline: radiance rays find the closest hit, shadow rays only whether anything lies in the way (the
// paper's separate ray types). Shared by the host (optix_renderer.cpp) and the device programs.
#pragma once

#include <optix_types.h>

#include "render/gpu/path_store.h"
#include "render/path_integrator.h"
#include "render/scene_view.h"

namespace npt::gpu {

enum RayType : unsigned { k_ray_radiance = 0, k_ray_shadow = 1, k_ray_types = 2 };

// The data of a hit-group record (after its header): which mesh the build input is, as Embree's geomID.
struct HitRecordData {
    uint32_t mesh;
};

struct LaunchParams {
    render::SceneView scene;  // device copies (device_scene.h)
    OptixTraversableHandle handle = 0;
    // slots planes of width * height running sums of radiance and (w) of FirstHit::escaped: launch index z adds
    // samples sample_begin + z, + z + slots, ... of its pixel to plane z (optix_renderer.cpp adds the planes).
    float4* accum = nullptr;
    // The AOVs' sums (render/first_hit.h), null when none is asked for: 2 * slots planes, plane 2z holding
    // (albedo sum, weight), plane 2z + 1 (normal sum, distance sum) of slot z.
    float4* first_hit = nullptr;
    uint32_t slots = 1;
    // The denoiser's guides, written by the launch with sample_begin 0, slot 0 (null: no denoising): the first
    // surface's albedo and its shading normal in camera axes (right, up, towards the camera), per pixel.
    float4* albedo = nullptr;
    float4* normal = nullptr;
    unsigned long long* dropped = nullptr;  // samples that were NaN or infinite (dropped, as on the CPU)
    int width = 0, height = 0;
    uint32_t sample_begin = 0, sample_count = 0;  // the sample indices this launch adds per pixel
    uint64_t seed = 0;
    render::PathSettings path;
    WavefrontParams wave;  // the wavefront programs' (wavefront.h); unused by __raygen__render
};

}  // namespace npt::gpu
