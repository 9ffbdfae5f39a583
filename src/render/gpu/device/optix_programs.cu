// The OptiX device programs of the path tracer: the ray-generation program runs trace_path (the CPU's
// integrator, render/path_integrator.h) with a Tracer that answers through optixTrace; closest-hit and miss
// programs only report what was hit. Compiled by nvcc to OptiX-IR and embedded in the binary (CMake).
#include <optix.h>

#include "core/sobol_sampler.h"
#include "render/camera.h"
#include "render/gpu/optix_launch.h"
#include "render/path_integrator.h"

using namespace npt;

extern "C" {
__constant__ gpu::LaunchParams params;
}

namespace {

constexpr float k_far = 1e16f;  // OptiX wants a finite tmax

// The integrator's Tracer on OptiX. Host stubs keep trace_path's __host__ __device__ template compiling.
struct OptixTracer {
    NPT_HD bool intersect(const Ray& ray, float tmax, render::Hit* hit) const {
#if defined(__CUDA_ARCH__)
        unsigned int t = 0, mesh = 0, prim = 0, u = 0, v = 0, found = 0;
        optixTrace(params.handle, make_float3(ray.o.x, ray.o.y, ray.o.z), make_float3(ray.d.x, ray.d.y, ray.d.z),
                   0.0f, fminf(tmax, k_far), 0.0f, OptixVisibilityMask(255), OPTIX_RAY_FLAG_DISABLE_ANYHIT,
                   gpu::k_ray_radiance, gpu::k_ray_types, gpu::k_ray_radiance, t, mesh, prim, u, v, found);
        if (!found) return false;
        hit->t = __uint_as_float(t);
        hit->mesh = mesh;
        hit->prim = prim;
        hit->u = __uint_as_float(u);
        hit->v = __uint_as_float(v);
        return true;
#else
        (void)ray, (void)tmax, (void)hit;
        return false;
#endif
    }

    NPT_HD bool occluded(const Ray& ray, float tmax) const {
#if defined(__CUDA_ARCH__)
        unsigned int visible = 0;
        optixTrace(params.handle, make_float3(ray.o.x, ray.o.y, ray.o.z), make_float3(ray.d.x, ray.d.y, ray.d.z),
                   0.0f, fminf(tmax, k_far), 0.0f, OptixVisibilityMask(255),
                   OPTIX_RAY_FLAG_DISABLE_ANYHIT | OPTIX_RAY_FLAG_TERMINATE_ON_FIRST_HIT |
                       OPTIX_RAY_FLAG_DISABLE_CLOSESTHIT,
                   gpu::k_ray_shadow, gpu::k_ray_types, gpu::k_ray_shadow, visible);
        return visible == 0;
#else
        (void)ray, (void)tmax;
        return false;
#endif
    }
};

}  // namespace

extern "C" __global__ void __raygen__render() {
    const uint3 idx = optixGetLaunchIndex();
    const int x = int(idx.x), y = int(idx.y);
    const uint32_t slot = idx.z;
    const OptixTracer tracer;
    Rgb sum(0.0f);
    const uint32_t end = params.sample_begin + params.sample_count;
    for (uint32_t s = params.sample_begin + slot; s < end; s += params.slots) {
        // The CPU's sampler for (pixel, sample): the same random numbers, decision by decision.
        SobolSampler sampler(params.seed, uint32_t(x), uint32_t(y), s);
        const Ray ray = render::generate_camera_ray(params.scene.camera, x, y, sampler.next_2d());
        const Rgb l = render::trace_path(params.scene, tracer, ray, sampler, params.path);
        if (is_finite(l))
            sum += l;
        else
            atomicAdd(params.dropped, 1ull);
    }
    const size_t pixel = size_t(y) * size_t(params.width) + size_t(x);
    float4& a = params.accum[size_t(slot) * size_t(params.width) * size_t(params.height) + pixel];
    a = make_float4(a.x + sum.x, a.y + sum.y, a.z + sum.z, 0.0f);

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
            n = Vec3(dot(si.shading.n, cam.right), dot(si.shading.n, cam.up), -dot(si.shading.n, cam.forward));
        }
        params.albedo[pixel] = make_float4(albedo.x, albedo.y, albedo.z, 0.0f);
        params.normal[pixel] = make_float4(n.x, n.y, n.z, 0.0f);
    }
}

// ---- The wavefront form (wavefront.h): one launch takes each path one vertex further and stops it wherever a
// NeRF segment is needed; the NeRF pass (nerf_segments.h) evaluates those between launches.

namespace {

// Traces the path's ray and finds the volumes on [0, hit): inline, or queued for the NeRF pass.
__device__ void begin_segment(gpu::WavefrontPath& p, SobolSampler& sampler, const OptixTracer& tracer) {
    p.found = tracer.intersect(p.ray, INFINITY, &p.hit);
    p.vol = media::VolumeResult{};
    if (params.scene.volumes.size > 0)
        gpu::volume_segment(params.scene.volumes, params.wave.nerf_slot, p.ray, 0.0f, p.found ? p.hit.t : INFINITY,
                            sampler.next_1d(), false, &p.query[0], &p.vol);
    p.phase = gpu::PathPhase::Scatter;
}

__device__ void write_path(gpu::WavefrontPath& p) {
    const Rgb l = p.st.radiance;
    if (is_finite(l)) {
        float4& a = params.accum[size_t(p.slot) * size_t(params.width) * size_t(params.height) + p.pixel];
        a = make_float4(a.x + l.x, a.y + l.y, a.z + l.z, 0.0f);
    } else {
        atomicAdd(params.dropped, 1ull);
    }
    p.phase = gpu::PathPhase::Done;
}

}  // namespace

extern "C" __global__ void __raygen__wavefront() {
    const uint32_t i = optixGetLaunchIndex().x;
    const gpu::WavefrontParams& w = params.wave;
    const OptixTracer tracer;
    if (!w.active) {
        // A new wave: path i is sample sample_begin + i / pixels of pixel i % pixels.
        const uint32_t pixels = uint32_t(params.width) * uint32_t(params.height);
        gpu::WavefrontPath p;
        p.pixel = i % pixels;
        p.slot = i / pixels;
        const uint32_t x = p.pixel % uint32_t(params.width), y = p.pixel / uint32_t(params.width);
        SobolSampler sampler(params.seed, x, y, params.sample_begin + p.slot);
        p.ray = render::generate_camera_ray(params.scene.camera, int(x), int(y), sampler.next_2d());
        p.st.prev_p = p.ray.o;
        begin_segment(p, sampler, tracer);
        p.sampler = sampler;
        w.paths[i] = p;
        w.queue[i] = gpu::queue_word(true, p.query[0].slot, gpu::k_no_query);
        return;
    }
    const uint32_t id = w.active[i];
    gpu::WavefrontPath& slot = w.paths[id];
    gpu::WavefrontPath p = slot;
    SobolSampler sampler = p.sampler;
    p.query[0].slot = p.query[1].slot = gpu::k_no_query;
    if (p.shadow_pending) {
        p.st.radiance += p.shadow_contribution * p.shadow_t;
        p.shadow_pending = false;
    }
    if (p.phase == gpu::PathPhase::Finish || !render::path_add_volume(p.st, p.vol)) {
        write_path(p);
    } else {
        // trace_path's loop body after the volume ray (path_integrator.h).
        render::ShadowRequest shadow;
        Ray next;
        const bool more = render::path_scatter(params.scene, tracer, p.st, p.ray, p.found, p.hit, sampler,
                                               params.path, &shadow, &next);
        if (shadow.pending) {
            p.shadow_t = 1.0f;
            p.shadow_contribution = shadow.contribution;
            media::VolumeResult in_place;
            if (params.scene.volumes.size == 0)
                p.st.radiance += shadow.contribution;
            else if (gpu::volume_segment(params.scene.volumes, w.nerf_slot, shadow.ray, 0.0f, shadow.tmax,
                                         shadow.xi, true, &p.query[1], &in_place))
                p.shadow_pending = true;  // its transmittance comes from the NeRF pass
            else
                p.st.radiance += shadow.contribution * in_place.transmittance;
        }
        if (more) {
            p.ray = next;
            begin_segment(p, sampler, tracer);
        } else if (p.shadow_pending) {
            p.phase = gpu::PathPhase::Finish;
        } else {
            write_path(p);
        }
    }
    p.sampler = sampler;
    slot = p;
    w.queue[id] = gpu::queue_word(p.phase != gpu::PathPhase::Done, p.query[0].slot, p.query[1].slot);
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
