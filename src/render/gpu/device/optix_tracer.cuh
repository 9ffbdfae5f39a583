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

}  // namespace
}  // namespace npt
