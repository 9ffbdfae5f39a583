// Unidirectional path tracing with next-event estimation and multiple importance sampling (power heuristic),
// Russian roulette and a maximum depth. Templated on the backend's Tracer (Embree on the CPU, OptiX later),
// which answers only two questions: the first hit along a ray, and whether a segment is blocked.
//   struct Tracer { bool intersect(const Ray&, float tmax, Hit*) const; bool occluded(const Ray&, float tmax)
//   const; };
#pragma once

#include "core/sobol_sampler.h"
#include "core/vec.h"
#include "lights/light.h"
#include "materials/bsdf.h"
#include "media/volume_integrator.h"
#include "render/ray_offset.h"
#include "render/surface.h"

namespace npt::render {

// How direct light is found. Mis is the renderer's default; the other two exist to check it (all three
// converge to the same image) and to debug a scene.
enum class LightStrategy : uint8_t { Mis, BsdfOnly, LightOnly };

struct PathSettings {
    LightStrategy strategy = LightStrategy::Mis;
    int max_depth = 16;      // the most scattering events on a path; emission after the last one still counts
    int rr_start_depth = 3;  // Russian roulette starts after this many bounces
};

// Spawns a ray leaving `si` in direction `wi` from the correct side of the surface.
NPT_HD NPT_INLINE Ray spawn_ray(const SurfaceInteraction& si, Vec3 wi) {
    Vec3 n = dot(wi, si.ng) > 0.0f ? si.ng : -si.ng;
    return Ray{offset_ray_origin(si.p, n), wi};
}

// True when wi and wo lie on the sides of the geometric surface that the BSDF's local frame says they do
// (reflection on one side, transmission across); guards against light leaks through shading normals.
NPT_HD NPT_INLINE bool geometry_agrees(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) {
    float go = dot(wo, si.ng), gi = dot(wi, si.ng);
    float so = dot(wo, si.shading.n), s_i = dot(wi, si.shading.n);
    return (go * gi > 0.0f) == (so * s_i > 0.0f);
}

// Radiance arriving at the ray origin along `ray`. `sampler` gives this pixel-sample's random numbers, one
// dimension per decision in a fixed order (so low-discrepancy samplers stratify each decision).
template <class Tracer, class Sampler>
NPT_HD Rgb trace_path(const SceneView& sv, const Tracer& tracer, Ray ray, Sampler& sampler,
                      const PathSettings& ps) {
    Rgb radiance(0.0f), throughput(1.0f);
    bool specular_bounce = true;  // the camera ray counts as specular: no MIS on what it sees
    float prev_bsdf_pdf = 0.0f;
    Vec3 prev_p = ray.o;

    for (int depth = 0;; ++depth) {
        Hit hit;
        bool found = tracer.intersect(ray, INFINITY, &hit);

        // The volume ray: emission and attenuation of the volumes on [0, nearest surface), so a surface
        // inside or behind a volume occludes exactly the part of it that lies behind the surface.
        if (sv.volumes.size > 0) {
            media::VolumeResult vol = media::integrate_volumes(
                sv.volumes, ray, 0.0f, found ? hit.t : INFINITY, sampler.next_1d(), false);
            radiance += throughput * vol.radiance;
            throughput *= vol.transmittance;
            if (vol.transmittance == 0.0f) break;
        }

        if (!found) {
            const lights::LightSetView& ls = sv.lights;
            if (ls.environment_light >= 0) {
                Rgb le = lights::environment_radiance(ls.environment, ray.d);
                float w = 1.0f;
                if (!specular_bounce && ps.strategy == LightStrategy::LightOnly)
                    w = 0.0f;
                else if (!specular_bounce && ps.strategy == LightStrategy::Mis)
                    w = power_heuristic(prev_bsdf_pdf, lights::environment_light_pdf(ls, ray.d));
                radiance += throughput * le * w;
            }
            break;
        }

        SurfaceInteraction si = make_surface_interaction(sv, hit, ray);
        Vec3 wo_world = -ray.d;
        if (!is_black(si.emission)) {
            float w = 1.0f;
            if (!specular_bounce && ps.strategy == LightStrategy::LightOnly) {
                // An emitter that could not have been light-sampled (zero pdf) is only found this way.
                w = lights::triangle_light_pdf(sv.lights, hit.mesh, hit.prim, prev_p, si.p) > 0.0f ? 0.0f
                                                                                                   : 1.0f;
            } else if (!specular_bounce && ps.strategy == LightStrategy::Mis) {
                float light_pdf = lights::triangle_light_pdf(sv.lights, hit.mesh, hit.prim, prev_p, si.p);
                w = power_heuristic(prev_bsdf_pdf, light_pdf);
            }
            radiance += throughput * si.emission * w;
        }
        if (depth >= ps.max_depth) break;

        const materials::Bsdf& bsdf = si.bsdf;
        Vec3 wo = si.shading.to_local(wo_world);

        // Next-event estimation: one light sample, weighted against the BSDF strategy.
        if (!materials::bsdf_is_delta(bsdf) && ps.strategy != LightStrategy::BsdfOnly) {
            lights::LightSample ls;
            float u_select = sampler.next_1d();
            Vec2 u_light = sampler.next_2d();
            if (lights::sample_light(sv.lights, si.p, u_select, u_light, &ls) && ls.pdf > 0.0f &&
                !is_black(ls.radiance)) {
                Vec3 wi = si.shading.to_local(ls.wi);
                Rgb f = materials::bsdf_eval(bsdf, wo, wi) * fabsf(wi.z);
                if (!is_black(f) && geometry_agrees(si, wo_world, ls.wi)) {
                    Ray shadow = spawn_ray(si, ls.wi);
                    float tmax = isinf(ls.distance) ? INFINITY : ls.distance * (1.0f - 1e-4f);
                    // Shadow rays see the volumes' transmittance (no emission: the volume does not scatter).
                    float shadow_t = tracer.occluded(shadow, tmax) ? 0.0f : 1.0f;
                    if (shadow_t > 0.0f && sv.volumes.size > 0)
                        shadow_t =
                            media::integrate_volumes(sv.volumes, shadow, 0.0f, tmax, sampler.next_1d(), true)
                                .transmittance;
                    if (shadow_t > 0.0f) {
                        float w = ls.is_delta || ps.strategy == LightStrategy::LightOnly
                                      ? 1.0f
                                      : power_heuristic(ls.pdf, materials::bsdf_pdf(bsdf, wo, wi));
                        radiance += throughput * f * ls.radiance * (shadow_t * w / ls.pdf);
                    }
                }
            }
        }

        // Continue the path by sampling the BSDF.
        materials::BsdfSample bs;
        float u_lobe = sampler.next_1d();
        Vec2 u_dir = sampler.next_2d();
        if (!materials::bsdf_sample(bsdf, wo, u_lobe, u_dir, &bs) || bs.pdf <= 0.0f) break;
        Vec3 wi_world = si.shading.to_world(bs.wi);
        if (!geometry_agrees(si, wo_world, wi_world)) break;
        throughput *= bs.f * (fabsf(bs.wi.z) / bs.pdf);
        if (is_black(throughput) || !is_finite(throughput)) break;
        specular_bounce = bs.is_delta;
        prev_bsdf_pdf = bs.pdf;
        prev_p = si.p;
        ray = spawn_ray(si, wi_world);

        if (depth + 1 >= ps.rr_start_depth) {
            // Roulette only once the throughput has fallen below 1/8: killing brighter paths costs more
            // variance than the time it saves (bench/render_bench on cornell, efficiency 1 / (relMSE x
            // seconds): 379 with survival = max(throughput) as in pbrt, 629 with 4x, 715 with 8x, 685 with
            // 16x, 558 with no roulette).
            float survive = fminf(1.0f, 8.0f * max_component(throughput));
            if (sampler.next_1d() >= survive) break;
            throughput *= 1.0f / survive;
        }
    }
    return radiance;
}

}  // namespace npt::render
