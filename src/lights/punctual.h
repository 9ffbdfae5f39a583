// Point, spot and directional lights (glTF KHR_lights_punctual): delta lights, sampled deterministically.
// Spot falloff follows the spec's recommended smooth attenuation between the inner and outer cone.
#pragma once

#include "lights/light_types.h"

namespace npt::lights {

// glTF's recommended spot attenuation: clamp(cos * scale + offset, 0, 1)^2, with scale = 1 / max(0.001,
// cos_inner - cos_outer) and offset = -cos_outer * scale. The 0.001 keeps inner == outer from dividing by 0.
NPT_HD NPT_INLINE float spot_attenuation(float cos_theta, float cos_inner, float cos_outer) {
    float scale = 1.0f / fmaxf(0.001f, cos_inner - cos_outer);
    float offset = -cos_outer * scale;
    return sqr(clampf(cos_theta * scale + offset, 0.0f, 1.0f));
}

// Fills s (pdf left to the caller, which knows the selection probability); false when no light arrives.
NPT_HD NPT_INLINE bool sample_point_or_spot(const Light& l, Vec3 ref_p, LightSample* s) {
    Vec3 to_light = l.position - ref_p;
    float d2 = length_squared(to_light);
    if (!(d2 > 0.0f)) return false;
    float d = sqrtf(d2);
    Vec3 wi = to_light / d;
    Rgb radiance = l.intensity / d2;
    if (l.kind == LightKind::Spot)
        radiance *= spot_attenuation(dot(l.direction, -wi), l.cos_inner, l.cos_outer);
    if (is_black(radiance)) return false;
    s->radiance = radiance;
    s->wi = wi;
    s->distance = d;
    s->is_delta = true;
    return true;
}

NPT_HD NPT_INLINE bool sample_directional(const Light& l, LightSample* s) {
    if (is_black(l.intensity)) return false;
    s->radiance = l.intensity;
    s->wi = -l.direction;
    s->distance = INFINITY;
    s->is_delta = true;
    return true;
}

}  // namespace npt::lights
