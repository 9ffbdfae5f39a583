// What each module of the OptiX programs shares: its copy of the launch parameters (OptiX sets the variable
// named `params` of every module of the pipeline) and the integrator's Tracer on optixTrace. Included once
// per module (device/*.cu): each is compiled to its own OptiX-IR.
#pragma once

#include <optix.h>

#include "render/gpu/optix_launch.h"
#include "render/path_integrator.h"

extern "C" {
__constant__ npt::gpu::LaunchParams params;
}

namespace npt {
namespace {

constexpr float k_far = 1e16f;  // OptiX wants a finite tmax

// The integrator's Tracer on OptiX. Host stubs keep trace_path's __host__ __device__ template compiling.
struct OptixTracer {
    NPT_HD bool intersect(const Ray& ray, float tmax, render::Hit* hit) const {
#if defined(__CUDA_ARCH__)
        unsigned int t = 0, mesh = 0, prim = 0, u = 0, v = 0, found = 0;
        optixTrace(params.handle, make_float3(ray.o.x, ray.o.y, ray.o.z),
                   make_float3(ray.d.x, ray.d.y, ray.d.z), 0.0f, fminf(tmax, k_far), 0.0f,
                   OptixVisibilityMask(255), OPTIX_RAY_FLAG_DISABLE_ANYHIT, gpu::k_ray_radiance,
                   gpu::k_ray_types, gpu::k_ray_radiance, t, mesh, prim, u, v, found);
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
        optixTrace(params.handle, make_float3(ray.o.x, ray.o.y, ray.o.z),
                   make_float3(ray.d.x, ray.d.y, ray.d.z), 0.0f, fminf(tmax, k_far), 0.0f,
                   OptixVisibilityMask(255),
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

// The camera ray's first hit is recorded only where the film needs it (alpha or AOVs).
__device__ NPT_INLINE bool film_records_first_hit() {
    return params.path.transparent_background || params.first_hit != nullptr;
}

// Adds a pixel's first-hit sums to slot `slot` of the film: the escaped transmittance to accum's w, the AOVs to
// their planes. Each (slot, pixel) belongs to one thread at a time, so plain read-modify-writes suffice.
__device__ NPT_INLINE void film_add_first_hits(uint32_t slot, size_t pixel, const render::FirstHitSums& s) {
    const size_t pixels = size_t(params.width) * size_t(params.height);
    params.accum[size_t(slot) * pixels + pixel].w += s.escaped;
    if (!params.first_hit) return;
    float4& a = params.first_hit[2 * size_t(slot) * pixels + pixel];
    float4& n = params.first_hit[(2 * size_t(slot) + 1) * pixels + pixel];
    a = make_float4(a.x + s.albedo.x, a.y + s.albedo.y, a.z + s.albedo.z, a.w + s.weight);
    n = make_float4(n.x + s.normal.x, n.y + s.normal.y, n.z + s.normal.z, n.w + s.distance);
}

}  // namespace
}  // namespace npt
