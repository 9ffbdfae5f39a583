// Emissive triangles: uniform-by-area sampling with the area-to-solid-angle conversion, the front-face rule,
// and the (optionally textured) emitted radiance.
#pragma once

#include "core/sampling.h"
#include "core/texture.h"
#include "lights/light_types.h"

namespace npt::lights {

// Emitted radiance of triangle l at barycentrics (b1, b2) towards the unit direction wo (away from the
// surface). Single-sided triangles emit only on the side their winding normal points to.
NPT_HD NPT_INLINE Rgb triangle_emission_at(Span<const TextureView> textures, const Light& l, Vec2 bary,
                                           Vec3 wo) {
    float c = dot(l.normal, wo);
    if (!(c > 0.0f) && !(l.two_sided && c < 0.0f)) return Rgb(0.0f);
    Rgb e = l.emission;
    if (l.texture >= 0 && size_t(l.texture) < textures.size && textures[size_t(l.texture)].valid()) {
        Vec2 uv = l.uv0 * (1.0f - bary.x - bary.y) + l.uv1 * bary.x + l.uv2 * bary.y;
        e *= textures[size_t(l.texture)].sample(uv).rgb();
    }
    return e;
}

// Solid-angle density (without selection) of sampling point light_p on l from ref_p; 0 where sampling would
// never produce it (back face of a single-sided triangle, grazing, degenerate).
NPT_HD NPT_INLINE float triangle_solid_angle_pdf(const Light& l, Vec3 ref_p, Vec3 light_p) {
    if (!(l.area > 0.0f)) return 0.0f;
    Vec3 to_light = light_p - ref_p;
    float d2 = length_squared(to_light);
    if (!(d2 > 0.0f)) return 0.0f;
    float cos_light = -dot(l.normal, to_light) / sqrtf(d2);
    if (l.two_sided) cos_light = fabsf(cos_light);
    if (!(cos_light > 0.0f)) return 0.0f;
    return d2 / (cos_light * l.area);
}

// Samples a point uniformly by area; s->pdf is solid-angle, without selection. False for back-facing,
// grazing or degenerate configurations.
NPT_HD NPT_INLINE bool sample_triangle(Span<const TextureView> textures, const Light& l, Vec3 ref_p, Vec2 u,
                                       LightSample* s) {
    if (!(l.area > 0.0f)) return false;
    Vec2 b = sample_uniform_triangle(u);
    Vec3 p = l.p0 * (1.0f - b.x - b.y) + l.p1 * b.x + l.p2 * b.y;
    float pdf = triangle_solid_angle_pdf(l, ref_p, p);
    if (!(pdf > 0.0f) || isinf(pdf)) return false;
    Vec3 to_light = p - ref_p;
    float d = length(to_light);
    Vec3 wi = to_light / d;
    Rgb radiance = triangle_emission_at(textures, l, b, -wi);
    if (is_black(radiance)) return false;
    s->radiance = radiance;
    s->wi = wi;
    s->distance = d;
    s->pdf = pdf;
    s->is_delta = false;
    return true;
}

}  // namespace npt::lights
