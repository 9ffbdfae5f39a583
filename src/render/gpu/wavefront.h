// The wavefront form of the OptiX path tracer, for scenes with NeRF models (the design's "wavefront split"):
// instead of each thread evaluating the network sample by sample inside the ray-generation program
// (divergent, no tensor cores), a path stops wherever it needs a NeRF segment, leaves a NerfQuery in its
// state, and a CUDA pass (nerf_segments.h) marches all waiting segments together and evaluates their samples
// with the tensor-core MLP of `nerfpt view`. The path then goes on from where it stopped, with the same
// random numbers in the same order as render/path_integrator.h's trace_path, which it is built from
// (path_scatter). A relit NeRF (media/relit_free_flight.h) is a segment too: the pass samples the radiance ray's
// free flight through it (the event, if any, goes back to the path as a FlightEvent, which the next launch shades
// with relit_scatter) and a shadow ray's transmittance. Shared by the OptiX programs, the CUDA pass and the host
// loop (optix_wavefront.cpp).
#pragma once

#include <cstdint>

#include "core/sobol_sampler.h"
#include "core/vec.h"
#include "media/volume_integrator.h"
#include "render/path_integrator.h"

namespace npt::gpu {

constexpr uint32_t k_no_query = 0xffffffffu;

// A NeRF segment a path waits for: the model-space ray from the segment's start (unit direction), where the
// segment ends along it (model units) and the step lattice's offset. `slot`: which of the pass's NeRFs
// (NerfSegmentPass), k_no_query when nothing waits. A radiance ray's segment through a relit NeRF is a free flight
// (march_relit): its target optical depth, and the map of a model-space distance s along `ray` to the world ray's
// t = t_world + s * world_per_model, as march_relit computes the event's t.
struct NerfQuery {
    Ray ray;
    float t_max = 0.0f;
    float xi = 0.0f;
    uint32_t slot = k_no_query;
    float target = INFINITY;
    float t_world = 0.0f;
    float world_per_model = 0.0f;
};

// A radiance ray's free flight through a relit NeRF as the next launch reads it (PathStore::events): the event's
// model-space sample position, its world distance along the ray and its volume (index into the scene's volumes;
// -1: no event, the flight went through). Written by the NeRF pass for a queued segment, by the launch itself
// for a segment it integrated inline.
struct FlightEvent {
    Vec3 p_model{0.0f};
    float t = 0.0f;
    int32_t volume = -1;
};

// What the NeRF pass's gather reads of a path after a launch, one word per path: whether the path goes on and
// each query's slot (the whole path state, about 250 bytes a path, read for these cost the gather 60-150 us a
// launch at 1080p on the H200). Slots at most k_max_queue_slot - 1: the pass takes no more NeRFs than that.
constexpr uint32_t k_max_queue_slot = 0x7fffu;
NPT_HD NPT_INLINE uint32_t queue_word(bool going_on, uint32_t slot0, uint32_t slot1) {
    const uint32_t s0 = slot0 == k_no_query ? k_max_queue_slot : slot0;
    const uint32_t s1 = slot1 == k_no_query ? k_max_queue_slot : slot1;
    return (going_on ? 0x80000000u : 0u) | (s1 << 15) | s0;
}
NPT_HD NPT_INLINE bool queue_going_on(uint32_t word) { return (word >> 31) != 0; }
NPT_HD NPT_INLINE uint32_t queue_slot(uint32_t word, int kind) {
    const uint32_t s = (word >> (15 * kind)) & k_max_queue_slot;
    return s == k_max_queue_slot ? k_no_query : s;
}

enum class PathPhase : uint8_t {
    Scatter,  // the segment in front of `hit` is known (or queued): path_scatter next
    Finish,   // ended, but a shadow ray's transmittance is still queued
    Done,     // written to the image
};

// What a path carries from one launch to the next. `vol` first and 16 bytes: the NeRF pass writes it as one
// word of the path's planes (path_store.h); its queries are kept apart (PathStore::queries), written only
// when queued.
struct WavefrontPath {
    media::VolumeResult vol;  // the volumes on [0, hit) of `ray`: set inline or by the NeRF pass
    render::PathState st;
    SobolSampler sampler;
    Ray ray;  // the ray that found `hit`
    render::Hit hit;
    Rgb shadow_contribution{0.0f};
    float shadow_t = 1.0f;  // the shadow ray's transmittance: set inline or by the NeRF pass
    uint32_t pixel = 0;     // y * width + x
    uint32_t slot = 0;      // the sample slot (accumulation plane) it adds to
    bool found = false;
    bool shadow_pending = false;
    PathPhase phase = PathPhase::Done;
    bool relit_flight = false;  // the volumes on [0, hit) held a relit free flight: its event in PathStore::events
};

// The world distance of a queued free flight's event at model point p (FreeFlight::add's ta + s.t *
// world_per_model, with the query's t_world and world_per_model). The NeRF pass packs a sample's position, not
// its t: t is recovered from the position along the segment's model ray, and on a uniform lattice (cone angle 0)
// put back on the lattice point t0 + k dt that the march computed it as (the position's rounding is far below
// half a step), so that it is the march's own t. `lattice_t0`: the march's first lattice point (MarchCursor::t0).
NPT_HD NPT_INLINE float flight_event_t(const nerf::MarchParams& mp, const Ray& model_ray, float lattice_t0,
                                       float t_world, float world_per_model, Vec3 p) {
    float t = dot(p - model_ray.o, model_ray.d);
    if (mp.cone_angle == 0.0f) {
        const float dt = nerf::march_step(mp, lattice_t0);
        t = lattice_t0 + rintf((t - lattice_t0) / dt) * dt;
    }
    return t_world + t * world_per_model;
}

// Where volume_segment left a segment.
enum class SegmentRoute : uint8_t {
    Inline,  // integrated in place (or no volume there)
    Queued,  // left for the NeRF pass: the emissive integral, or a shadow ray's transmittance
    Flight,  // left for the NeRF pass: a radiance ray's free flight through a relit NeRF
};

// The volumes of `volumes` on [t_begin, t_end] of `ray`: when exactly one volume lies there and it is a NeRF
// the pass evaluates, the segment is left in *q for the pass; otherwise it is integrated here into *vol (and
// *flight), exactly as trace_path does. `shadow`: attenuation only, volumes that cast shadows only. `flight`
// (radiance rays, as integrate_volumes takes it): a relit NeRF's segment becomes a free flight with its target
// (SegmentRoute::Flight; *vol stays "nothing", as integrate_volumes leaves it for a relit volume alone), or,
// integrated here, may end at an event in *flight.
NPT_HD NPT_INLINE SegmentRoute volume_segment(Span<const media::VolumeView> volumes, const uint32_t* nerf_slot,
                                              const Ray& ray, float t_begin, float t_end, float xi, bool shadow,
                                              NerfQuery* q, media::VolumeResult* vol,
                                              media::FreeFlight* flight = nullptr) {
    int count = 0;
    size_t only = 0;
    float t0 = 0.0f, t1 = 0.0f;
    for (size_t i = 0; i < volumes.size && count < 2; ++i) {
        const media::VolumeView& v = volumes[i];
        if (shadow && !v.casts_shadows) continue;
        const Vec3 lo = v.world_to_local.apply(ray.o), ld = v.world_to_local.apply_vector(ray.d);
        float a, b;
        if (!media::intersect_box(lo, ld, v.local_min, v.local_max, t_begin, t_end, &a, &b)) continue;
        ++count;
        only = i;
        t0 = a;
        t1 = b;
    }
    q->slot = k_no_query;
    q->target = INFINITY;
    *vol = media::VolumeResult{};
    if (count == 0) return SegmentRoute::Inline;
    const media::VolumeView& v = volumes[only];
    // A relit NeRF on a radiance ray without a flight is absorption only (march_relit_nerf): left inline.
    const bool relit_radiance = !shadow && v.kind == media::VolumeKind::Nerf && v.nerf.relit;
    if (count == 1 && v.kind == media::VolumeKind::Nerf && nerf_slot[only] != k_no_query &&
        (!relit_radiance || flight)) {
        // march_nerf's (and march_relit's) segment (volume_integrator.h), handed over instead of marched here.
        if (!media::nerf_model_segment(v, ray, t0, t1, &q->ray, &q->t_max)) return SegmentRoute::Inline;
        q->xi = xi;
        q->slot = nerf_slot[only];
        if (!relit_radiance) return SegmentRoute::Queued;
        q->target = flight->target;
        q->t_world = t0;
        q->world_per_model = (t1 - t0) / q->t_max;  // march_relit's world_per_model
        return SegmentRoute::Flight;
    }
    *vol = media::integrate_volumes(volumes, ray, t_begin, t_end, xi, shadow, shadow ? nullptr : flight);
    return SegmentRoute::Inline;
}

}  // namespace npt::gpu
