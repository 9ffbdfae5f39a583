// The OptiX device programs of the path tracer: the ray-generation program runs trace_path (the CPU's
// integrator, render/path_integrator.h) with a Tracer that answers through optixTrace; closest-hit and miss
// programs only report what was hit. Compiled by nvcc to OptiX-IR and embedded in the binary (CMake); the
// wavefront form's program is in optix_wavefront_programs.cu.
#include "core/sobol_sampler.h"
#include "render/camera.h"
#include "render/gpu/device/optix_tracer.cuh"

using namespace npt;

extern "C" __global__ void __raygen__render() {
    const uint3 idx = optixGetLaunchIndex();
    const int x = int(idx.x), y = int(idx.y);
    const uint32_t slot = idx.z;
    const OptixTracer tracer;
    Rgb sum(0.0f);
    render::FirstHitSums first_sums;
    const bool record_first = film_records_first_hit();
    const uint32_t end = params.sample_begin + params.sample_count;
    for (uint32_t s = params.sample_begin + slot; s < end; s += params.slots) {
        // The CPU's sampler for (pixel, sample): the same random numbers, decision by decision.
        SobolSampler sampler(params.seed, uint32_t(x), uint32_t(y), s);
        const Ray ray = render::generate_camera_ray(params.scene.camera, x, y, sampler.next_2d());
        render::FirstHit first;
        const Rgb l = render::trace_path(params.scene, tracer, ray, sampler, params.path,
                                         record_first ? &first : nullptr);
        render::add_first_hit(first_sums, first);  // a dropped sample's coverage still counts, as on the CPU
        if (is_finite(l))
            sum += l;
        else
            atomicAdd(params.dropped, 1ull);
    }
    const size_t pixel = size_t(y) * size_t(params.width) + size_t(x);
    float4& a = params.accum[size_t(slot) * size_t(params.width) * size_t(params.height) + pixel];
    a = make_float4(a.x + sum.x, a.y + sum.y, a.z + sum.z, a.w);
    if (record_first) film_add_first_hits(slot, pixel, first_sums);

    if (params.albedo && params.sample_begin == 0 && slot == 0) {
        // Guides for the denoiser: what the pixel's centre sees first.
        const render::CameraView& cam = params.scene.camera;
        const Ray ray = render::generate_camera_ray(cam, x, y, Vec2(0.5f, 0.5f));
        render::Hit hit;
        Rgb albedo(0.0f);
        Vec3 n(0.0f);
        if (tracer.intersect(ray, INFINITY, &hit)) {
            const render::SurfaceInteraction si = render::make_surface_interaction(params.scene, hit, ray);
            albedo = Rgb(clampf(si.bsdf.base_color.x, 0.0f, 1.0f), clampf(si.bsdf.base_color.y, 0.0f, 1.0f),
                         clampf(si.bsdf.base_color.z, 0.0f, 1.0f));
            n = Vec3(dot(si.shading.n, cam.right), dot(si.shading.n, cam.up),
                     -dot(si.shading.n, cam.forward));
        }
        params.albedo[pixel] = make_float4(albedo.x, albedo.y, albedo.z, 0.0f);
        params.normal[pixel] = make_float4(n.x, n.y, n.z, 0.0f);
    }
}

extern "C" __global__ void __closesthit__radiance() {
    const float2 b = optixGetTriangleBarycentrics();
    optixSetPayload_0(__float_as_uint(optixGetRayTmax()));
    // The mesh: the hit group's record names it (one build input per mesh, optix_accel.h).
    optixSetPayload_1(reinterpret_cast<const gpu::HitRecordData*>(optixGetSbtDataPointer())->mesh);
    optixSetPayload_2(optixGetPrimitiveIndex());
    optixSetPayload_3(__float_as_uint(b.x));  // OptiX's (b1, b2) weigh vertices 1 and 2, as Embree's (u, v)
    optixSetPayload_4(__float_as_uint(b.y));
    optixSetPayload_5(1u);
}

extern "C" __global__ void __miss__radiance() { optixSetPayload_5(0u); }

extern "C" __global__ void __miss__shadow() { optixSetPayload_0(1u); }
