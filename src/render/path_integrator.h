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
#include "media/relit_event.h"
#include "media/volume_integrator.h"
#include "nerf/relight/intrinsic_field.h"
#include "render/first_hit.h"
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
    // Film > Transparent: what a camera ray sees of the environment directly is left out (the film's alpha,
    // FirstHit::escaped, says how much of it there was); light the environment sends via surfaces stays.
    bool transparent_background = false;
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

// What a path carries from one vertex to the next.
struct PathState {
    Rgb radiance{0.0f}, throughput{1.0f};
    Vec3 prev_p{0.0f};          // the last scattering point (MIS of emitters found by the BSDF sample)
    float prev_bsdf_pdf = 0.0f;
    int depth = 0;              // scattering events so far
    bool specular_bounce = true;  // the camera ray counts as specular: no MIS on what it sees
};

// A light sample that no surface blocks: it adds `contribution` times the volumes' transmittance along `ray`
// up to `tmax` (marched with lattice offset `xi`). The CPU resolves it at once; the GPU's wavefront renderer
// may batch the transmittance of many paths first (render/gpu).
struct ShadowRequest {
    Ray ray;
    float tmax = 0.0f;
    float xi = 0.0f;
    Rgb contribution{0.0f};
    bool pending = false;
};

// The volumes' emission and attenuation on the segment in front of the next surface. False: the path is
// opaque from here on and ends.
NPT_HD NPT_INLINE bool path_add_volume(PathState& st, const media::VolumeResult& vol) {
    st.radiance += st.throughput * vol.radiance;
    st.throughput *= vol.transmittance;
    return vol.transmittance != 0.0f;
}

// Everything a path does at the end of `ray` after the volumes in front of it: the environment when nothing
// was hit, emission, next-event estimation (one light sample, weighted against the BSDF strategy; an unblocked
// one becomes *shadow), the BSDF sample and Russian roulette. True: the path goes on along *next.
// At the camera ray's vertex (depth 0) it also fills *first, when given, for the film (render/first_hit.h).
// Not inlined on the GPU: the per-thread OptiX program's path loop around a call measured faster on cornell than
// with the body inlined (296 -> 299 M samples/s at 96 registers, 300 -> 305 at 128; docs/benchmarks.md).
template <class Tracer, class Sampler>
NPT_HD NPT_DEVICE_NOINLINE bool path_scatter(const SceneView& sv, const Tracer& tracer, PathState& st, const Ray& ray, bool found,
                         const Hit& hit, Sampler& sampler, const PathSettings& ps, ShadowRequest* shadow,
                         Ray* next, FirstHit* first = nullptr) {
    shadow->pending = false;
    if (!found) {
        const lights::LightSetView& ls = sv.lights;
        const bool camera_ray = st.depth == 0;
        if (camera_ray && first) first->escaped = camera_transmittance(st.throughput);
        if (ls.environment_light >= 0 && !(camera_ray && ps.transparent_background)) {
            Rgb le = lights::environment_radiance(ls.environment, ray.d);
            float w = 1.0f;
            if (!st.specular_bounce && ps.strategy == LightStrategy::LightOnly)
                w = 0.0f;
            else if (!st.specular_bounce && ps.strategy == LightStrategy::Mis)
                w = power_heuristic(st.prev_bsdf_pdf, lights::environment_light_pdf(ls, ray.d));
            st.radiance += st.throughput * le * w;
        }
        return false;
    }

    SurfaceInteraction si = make_surface_interaction(sv, hit, ray);
    if (st.depth == 0 && first)
        record_first_event(first, camera_transmittance(st.throughput), si.bsdf.base_color, si.shading.n, hit.t);
    Vec3 wo_world = -ray.d;
    if (!is_black(si.emission)) {
        float w = 1.0f;
        if (!st.specular_bounce && ps.strategy == LightStrategy::LightOnly) {
            // An emitter that could not have been light-sampled (zero pdf) is only found this way.
            w = lights::triangle_light_pdf(sv.lights, hit.mesh, hit.prim, st.prev_p, si.p) > 0.0f ? 0.0f : 1.0f;
        } else if (!st.specular_bounce && ps.strategy == LightStrategy::Mis) {
            float light_pdf = lights::triangle_light_pdf(sv.lights, hit.mesh, hit.prim, st.prev_p, si.p);
            w = power_heuristic(st.prev_bsdf_pdf, light_pdf);
        }
        st.radiance += st.throughput * si.emission * w;
    }
    if (st.depth >= ps.max_depth) return false;

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
                Ray sray = spawn_ray(si, ls.wi);
                float tmax = INFINITY;
                if (!isinf(ls.distance)) {
                    // Aim from the offset origin at the sampled point itself. A ray parallel to wi from the
                    // offset origin meets an emitter seen at a grazing angle (cosine c) up to offset / c
                    // before ls.distance, beyond the margin below: the emitter shadowed itself wherever it
                    // was seen within ~2.5 degrees of its plane.
                    Vec3 to = si.p + ls.wi * ls.distance - sray.o;
                    float d = length(to);
                    if (d > 0.0f) sray.d = to / d;
                    tmax = d * (1.0f - 1e-4f);
                }
                // Shadow rays see the volumes' transmittance (no emission: the volume does not scatter).
                if (!tracer.occluded(sray, tmax)) {
                    float w = ls.is_delta || ps.strategy == LightStrategy::LightOnly
                                  ? 1.0f
                                  : power_heuristic(ls.pdf, materials::bsdf_pdf(bsdf, wo, wi));
                    shadow->ray = sray;
                    shadow->tmax = tmax;
                    shadow->xi = sv.volumes.size > 0 ? sampler.next_1d() : 0.0f;
                    shadow->contribution = st.throughput * f * ls.radiance * (w / ls.pdf);
                    shadow->pending = true;
                }
            }
        }
    }

    // Continue the path by sampling the BSDF.
    materials::BsdfSample bs;
    float u_lobe = sampler.next_1d();
    Vec2 u_dir = sampler.next_2d();
    if (!materials::bsdf_sample(bsdf, wo, u_lobe, u_dir, &bs) || bs.pdf <= 0.0f) return false;
    Vec3 wi_world = si.shading.to_world(bs.wi);
    if (!geometry_agrees(si, wo_world, wi_world)) return false;
    st.throughput *= bs.f * (fabsf(bs.wi.z) / bs.pdf);
    if (is_black(st.throughput) || !is_finite(st.throughput)) return false;
    st.specular_bounce = bs.is_delta;
    st.prev_bsdf_pdf = bs.pdf;
    st.prev_p = si.p;
    *next = spawn_ray(si, wi_world);

    if (st.depth + 1 >= ps.rr_start_depth) {
        // Roulette only once the throughput has fallen below 1/8: killing brighter paths costs more
        // variance than the time it saves (bench/render_bench on cornell, efficiency 1 / (relMSE x
        // seconds): 379 with survival = max(throughput) as in pbrt, 629 with 4x, 715 with 8x, 685 with
        // 16x, 558 with no roulette).
        float survive = fminf(1.0f, 8.0f * max_component(st.throughput));
        if (sampler.next_1d() >= survive) return false;
        st.throughput *= 1.0f / survive;
    }
    ++st.depth;
    return true;
}

// path_scatter for a scattering event in a relit NeRF (media/relit_event.h): the same light sample with the
// same MIS, the same BSDF continuation, depth and roulette rules, in the same order of random numbers, but a
// point with a shading frame and no surface: it emits nothing, has no geometric normal to check directions
// against (the intrinsic BSDF only reflects, into the facing normal's hemisphere) and starts its rays from the
// event's spawn point. Shadow rays see the volumes' transmittance (this one's included: self-shadowing).
template <class Tracer, class Sampler>
NPT_HD NPT_DEVICE_NOINLINE bool relit_scatter(const SceneView& sv, const Tracer& tracer, PathState& st,
                                              const media::RelitEvent& ev, Vec3 wo_world, Sampler& sampler,
                                              const PathSettings& ps, ShadowRequest* shadow, Ray* next) {
    shadow->pending = false;
    if (st.depth >= ps.max_depth) return false;
    const materials::Bsdf bsdf = nerf::intrinsic_bsdf(ev.sample);
    const Vec3 wo = ev.frame.to_local(wo_world);

    if (!materials::bsdf_is_delta(bsdf) && ps.strategy != LightStrategy::BsdfOnly) {
        lights::LightSample ls;
        float u_select = sampler.next_1d();
        Vec2 u_light = sampler.next_2d();
        if (lights::sample_light(sv.lights, ev.origin, u_select, u_light, &ls) && ls.pdf > 0.0f &&
            !is_black(ls.radiance)) {
            Vec3 wi = ev.frame.to_local(ls.wi);
            Rgb f = materials::bsdf_eval(bsdf, wo, wi) * fabsf(wi.z);
            if (!is_black(f)) {
                Ray sray{ev.origin, ls.wi};
                float tmax = isinf(ls.distance) ? INFINITY : ls.distance * (1.0f - 1e-4f);
                if (!tracer.occluded(sray, tmax)) {
                    float w = ls.is_delta || ps.strategy == LightStrategy::LightOnly
                                  ? 1.0f
                                  : power_heuristic(ls.pdf, materials::bsdf_pdf(bsdf, wo, wi));
                    shadow->ray = sray;
                    shadow->tmax = tmax;
                    shadow->xi = sampler.next_1d();  // a relit event implies volumes
                    shadow->contribution = st.throughput * f * ls.radiance * (w / ls.pdf);
                    shadow->pending = true;
                }
            }
        }
    }

    materials::BsdfSample bs;
    float u_lobe = sampler.next_1d();
    Vec2 u_dir = sampler.next_2d();
    if (!materials::bsdf_sample(bsdf, wo, u_lobe, u_dir, &bs) || bs.pdf <= 0.0f) return false;
    st.throughput *= bs.f * (fabsf(bs.wi.z) / bs.pdf);
    if (is_black(st.throughput) || !is_finite(st.throughput)) return false;
    st.specular_bounce = bs.is_delta;
    st.prev_bsdf_pdf = bs.pdf;
    st.prev_p = ev.origin;
    *next = Ray{ev.origin, ev.frame.to_world(bs.wi)};

    if (st.depth + 1 >= ps.rr_start_depth) {  // as path_scatter
        float survive = fminf(1.0f, 8.0f * max_component(st.throughput));
        if (sampler.next_1d() >= survive) return false;
        st.throughput *= 1.0f / survive;
    }
    ++st.depth;
    return true;
}

// Radiance arriving at the ray origin along `ray`. `sampler` gives this pixel-sample's random numbers, one
// dimension per decision in a fixed order (so low-discrepancy samplers stratify each decision). `first`,
// when given, receives what the camera ray met first (render/first_hit.h); it does not change the radiance.
template <class Tracer, class Sampler>
NPT_HD Rgb trace_path(const SceneView& sv, const Tracer& tracer, Ray ray, Sampler& sampler,
                      const PathSettings& ps, FirstHit* first = nullptr) {
    PathState st;
    st.prev_p = ray.o;
    if (first) *first = FirstHit{};
    for (;;) {
        Hit hit;
        bool found = tracer.intersect(ray, INFINITY, &hit);
        // The volume ray: emission and attenuation of the volumes on [0, nearest surface), so a surface
        // inside or behind a volume occludes exactly the part of it that lies behind the surface; with relit
        // NeRFs, also the free flight through them, which may end the segment at a scattering event.
        media::FreeFlight flight;
        if (sv.volumes.size > 0) {
            const float xi = sampler.next_1d();
            if (media::any_relit(sv.volumes)) flight.target = media::free_flight_target(sampler.next_1d());
            if (!path_add_volume(st, media::integrate_volumes(sv.volumes, ray, 0.0f, found ? hit.t : INFINITY,
                                                              xi, false, &flight)))
                break;
        }
        ShadowRequest shadow;
        Ray next;
        bool more;
        if (flight.event) {
            // The path scatters in a relit NeRF at distance flight.t; at the camera vertex that is the film's
            // first hit (albedo, the facing normal, the distance).
            const media::RelitEvent ev = media::relit_event_at(sv.volumes, ray, flight);
            if (st.depth == 0 && first)
                record_first_event(first, camera_transmittance(st.throughput), ev.sample.albedo, ev.frame.n,
                                   flight.t);
            more = relit_scatter(sv, tracer, st, ev, -ray.d, sampler, ps, &shadow, &next);
        } else {
            more = path_scatter(sv, tracer, st, ray, found, hit, sampler, ps, &shadow, &next, first);
        }
        if (shadow.pending) {
            const float t = sv.volumes.size > 0 ? media::integrate_volumes(sv.volumes, shadow.ray, 0.0f, shadow.tmax,
                                                                           shadow.xi, true)
                                                      .transmittance
                                                : 1.0f;
            st.radiance += shadow.contribution * t;
        }
        if (!more) break;
        ray = next;
    }
    return st.radiance;
}

}  // namespace npt::render
