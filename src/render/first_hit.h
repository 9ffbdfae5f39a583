// What a camera ray meets first, for the film's outputs beside the colour (render/film.h): the transparency of
// `--transparent` (how much of the ray escapes to the environment unscattered) and the albedo, normal and
// distance of its first scattering event (`--aov`). One plain record per camera sample, written at the path's
// first vertex by the integrator (path_scatter) on every backend; a scattering event of another kind (a relit
// volume's) fills it through record_first_event too.
#pragma once

#include <math.h>

#include "core/vec.h"

namespace npt::render {

struct FirstHit {
    // The camera ray left the scene with no scattering event: its transmittance through the volumes on the way
    // (0 when it hit something or a volume ended it). The film's alpha is 1 - its average.
    float escaped = 0.0f;
    // A first scattering event was found: how much of the sample reaches it (the volumes' transmittance in
    // front of it), which weighs the AOVs below in the pixel's average; 0: no event.
    float weight = 0.0f;
    Rgb albedo{0.0f};   // the BSDF's base colour (Lambert albedo, a metal's F0), linear
    Vec3 normal{0.0f};  // world-space shading normal; facing the camera except on transmissive surfaces
    float distance = 0.0f;  // along the camera ray (camera rays have unit directions)
};

NPT_HD NPT_INLINE void record_first_event(FirstHit* first, float weight, Rgb albedo, Vec3 normal, float distance) {
    first->weight = weight;
    first->albedo = albedo;
    first->normal = normal;
    first->distance = distance;
}

// A pixel's sums of its samples' records: the escaped transmittance, then the AOVs weighted by FirstHit::weight
// (the GPU keeps them in float4 planes: (albedo, weight), (normal, distance)).
struct FirstHitSums {
    float escaped = 0.0f;
    float weight = 0.0f;
    Rgb albedo{0.0f};
    Vec3 normal{0.0f};
    float distance = 0.0f;
};

NPT_HD NPT_INLINE void add_first_hit(FirstHitSums& s, const FirstHit& f) {
    s.escaped += f.escaped;
    s.weight += f.weight;
    s.albedo += f.albedo * f.weight;
    s.normal += f.normal * f.weight;
    s.distance += f.distance * f.weight;
}

// Depth where no sample of a pixel found a scattering event: the ray went to infinity (render/film.h).
constexpr float k_depth_none = INFINITY;

// The AOVs of a pixel: the average over the part of its samples that found an event (a pixel half covered by a
// red sphere is red, not dark red); 0 (albedo, normal) and k_depth_none where none did. The normal is the
// average of unit normals, not renormalised (shorter at edges and on rough bumps, as a renderer's normal pass).
struct FirstHitAovs {
    Rgb albedo{0.0f};
    Vec3 normal{0.0f};
    float depth = k_depth_none;
};
NPT_HD NPT_INLINE FirstHitAovs resolve_first_hit(float weight, Rgb albedo_sum, Vec3 normal_sum, float distance_sum) {
    FirstHitAovs a;
    if (weight > 0.0f) {
        const float inv = 1.0f / weight;
        a.albedo = albedo_sum * inv;
        a.normal = normal_sum * inv;
        a.depth = distance_sum * inv;
    }
    return a;
}

// The camera ray's path is one colour through volumes alone, so any channel of its throughput is the
// transmittance; the mean guards against rounding.
NPT_HD NPT_INLINE float camera_transmittance(Rgb throughput) {
    return (throughput.x + throughput.y + throughput.z) * (1.0f / 3.0f);
}

}  // namespace npt::render
