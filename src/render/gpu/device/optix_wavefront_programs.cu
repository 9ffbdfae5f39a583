// The wavefront form's ray-generation program (wavefront.h): one launch takes each path one vertex further
// and stops it wherever a NeRF segment is needed; the NeRF pass (nerf_segments.h) evaluates those between
// launches. Its own module (its own OptiX-IR and register limit, optix_pipeline.cpp), so that the per-thread
// program of optix_programs.cu is compiled the same whatever this one holds.
#include "core/sobol_sampler.h"
#include "render/camera.h"
#include "render/gpu/device/optix_tracer.cuh"

using namespace npt;

namespace {

// Traces the path's ray and finds the volumes on [0, hit): inline, or queued for the NeRF pass. trace_path's
// random numbers in its order: the lattice offset, then, where any volume is relit, the free flight's target.
// A query left for the pass is stored at once (PathStore::queries); returns its slot, or k_no_query. A relit
// free flight (queued, or inline with an event) is marked in p.relit_flight; an inline event is stored at once
// (PathStore::events), a queued flight's by the pass.
__device__ uint32_t begin_segment(gpu::WavefrontPath& p, uint32_t id, SobolSampler& sampler,
                                  const OptixTracer& tracer) {
    p.found = tracer.intersect(p.ray, INFINITY, &p.hit);
    p.vol = media::VolumeResult{};
    p.relit_flight = false;
    p.phase = gpu::PathPhase::Scatter;
    const Span<const media::VolumeView> volumes = params.scene.volumes;
    if (volumes.size == 0) return gpu::k_no_query;
    const float xi = sampler.next_1d();
    media::FreeFlight flight;
    if (media::any_relit(volumes)) flight.target = media::free_flight_target(sampler.next_1d());
    gpu::NerfQuery q;
    const gpu::SegmentRoute route = gpu::volume_segment(volumes, params.wave.nerf_slot, p.ray, 0.0f,
                                                        p.found ? p.hit.t : INFINITY, xi, false, &q, &p.vol,
                                                        &flight);
    if (route == gpu::SegmentRoute::Inline) {
        if (flight.event) {
            params.wave.paths.events[id] = gpu::FlightEvent{flight.p_model, flight.t, int32_t(flight.volume)};
            p.relit_flight = true;
        }
        return gpu::k_no_query;
    }
    params.wave.paths.queries[2 * size_t(id)] = q;
    p.relit_flight = route == gpu::SegmentRoute::Flight;
    return q.slot;
}

// The event a free flight found (the intrinsic fields queried here, by this thread). A call, not inlined: the
// intrinsic network's evaluation then does not weigh on the registers of the launch's main body, which most
// vertices (surfaces) take without it.
__device__ __noinline__ media::RelitEvent relit_event(const Ray& ray, const media::FreeFlight& flight) {
    return media::relit_event_at(params.scene.volumes, ray, flight);
}

// The free flight of the path's last segment (begin_segment): its event, if it had one.
__device__ media::FreeFlight flight_of(const gpu::WavefrontPath& p, uint32_t id) {
    media::FreeFlight flight;
    if (!p.relit_flight) return flight;
    const gpu::FlightEvent e = params.wave.paths.events[id];
    if (e.volume < 0) return flight;
    flight.event = true;
    flight.t = e.t;
    flight.p_model = e.p_model;
    flight.volume = e.volume;
    return flight;
}

__device__ void write_path(gpu::WavefrontPath& p) {
    const Rgb l = p.st.radiance;
    if (is_finite(l)) {
        float4& a = params.accum[size_t(p.slot) * size_t(params.width) * size_t(params.height) + p.pixel];
        a = make_float4(a.x + l.x, a.y + l.y, a.z + l.z, a.w);  // w: the film's, film_add_first_hits
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
        const uint32_t queued = begin_segment(p, i, sampler, tracer);
        p.sampler = sampler;
        gpu::store_path(w.paths, i, p);
        w.queue[i] = gpu::queue_word(true, queued, gpu::k_no_query);
        return;
    }
    const uint32_t id = w.active[i];
    gpu::WavefrontPath p = gpu::load_path(w.paths, id);
    SobolSampler sampler = p.sampler;
    uint32_t queued[2] = {gpu::k_no_query, gpu::k_no_query};  // the slots of the queries left for the pass
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
        // The camera ray's vertex: its first hit goes straight to the film (no room in the path's state).
        const bool record_first = p.st.depth == 0 && film_records_first_hit();
        render::FirstHit first;
        const media::FreeFlight flight = flight_of(p, id);
        bool more;
        if (flight.event) {
            // The path scatters in a relit NeRF at distance flight.t; at the camera vertex that is the film's
            // first hit (albedo, the facing normal, the distance).
            const media::RelitEvent ev = relit_event(p.ray, flight);
            if (record_first)
                render::record_first_event(&first, render::camera_transmittance(p.st.throughput), ev.sample.albedo,
                                           ev.frame.n, flight.t);
            more = render::relit_scatter(params.scene, tracer, p.st, ev, -p.ray.d, sampler, params.path, &shadow,
                                         &next);
        } else {
            more = render::path_scatter(params.scene, tracer, p.st, p.ray, p.found, p.hit, sampler, params.path,
                                        &shadow, &next, record_first ? &first : nullptr);
        }
        if (record_first) {
            render::FirstHitSums sums;
            render::add_first_hit(sums, first);
            film_add_first_hits(p.slot, p.pixel, sums);
        }
        if (shadow.pending) {
            p.shadow_t = 1.0f;
            p.shadow_contribution = shadow.contribution;
            media::VolumeResult in_place;
            gpu::NerfQuery q;
            if (params.scene.volumes.size == 0) {
                p.st.radiance += shadow.contribution;
            } else if (gpu::volume_segment(params.scene.volumes, w.nerf_slot, shadow.ray, 0.0f, shadow.tmax,
                                           shadow.xi, true, &q, &in_place) != gpu::SegmentRoute::Inline) {
                p.shadow_pending = true;  // its transmittance comes from the NeRF pass
                w.paths.queries[2 * size_t(id) + 1] = q;
                queued[1] = q.slot;
            } else {
                p.st.radiance += shadow.contribution * in_place.transmittance;
            }
        }
        if (more) {
            p.ray = next;
            queued[0] = begin_segment(p, id, sampler, tracer);
        } else if (p.shadow_pending) {
            p.phase = gpu::PathPhase::Finish;
        } else {
            write_path(p);
        }
    }
    p.sampler = sampler;
    if (p.phase != gpu::PathPhase::Done)
        gpu::store_path(w.paths, id, p);  // a finished path is not read again
    w.queue[id] = gpu::queue_word(p.phase != gpu::PathPhase::Done, queued[0], queued[1]);
}
