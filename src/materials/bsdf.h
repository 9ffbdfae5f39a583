// The one entry point the integrators (CPU and GPU) use for materials: make_bsdf from glTF parameters, then
// eval / pdf / sample with a switch on the kind (no virtual calls, so the same code runs in CUDA/OptiX).
// Directions are in the local shading frame (z = normal), both pointing away from the surface.
#pragma once

#include "materials/bsdf_types.h"
#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/lambert.h"
#include "materials/principled.h"

namespace npt::materials {

// Picks the cheapest kind that represents the glTF parameters exactly.
NPT_HD NPT_INLINE Bsdf make_bsdf(Rgb base_color, float metallic, float roughness, float specular,
                                 Rgb specular_color, float transmission, float ior) {
    Bsdf b;
    b.base_color = base_color;
    b.metallic = metallic;
    b.roughness = roughness;
    b.specular = specular;
    b.specular_color = specular_color;
    b.transmission = transmission;
    b.ior = ior;
    if (transmission == 0.0f && metallic == 0.0f && specular == 0.0f)
        b.kind = BsdfKind::Lambert;
    else if (metallic >= 1.0f && transmission == 0.0f)
        b.kind = BsdfKind::Conductor;
    else if (metallic == 0.0f && transmission >= 1.0f && specular > 0.0f)
        b.kind = BsdfKind::Dielectric;
    else
        b.kind = BsdfKind::Principled;
    return b;
}

NPT_HD NPT_INLINE DielectricLobe make_dielectric(const Bsdf& b) {
    return {ggx_alpha_from_roughness(b.roughness), b.ior, b.specular, b.specular_color, b.base_color};
}

NPT_HD NPT_INLINE Rgb bsdf_eval(const Bsdf& b, Vec3 wo, Vec3 wi) {
    switch (b.kind) {
        case BsdfKind::Lambert:
            return lambert_eval(b.base_color, wo, wi);
        case BsdfKind::Conductor:
            return ggx_reflection_eval(make_conductor(ggx_alpha_from_roughness(b.roughness), b.base_color),
                                       wo, wi);
        case BsdfKind::Dielectric:
            return dielectric_eval(make_dielectric(b), wo, wi);
        case BsdfKind::Principled:
            return principled_eval(make_principled(b), wo, wi);
    }
    return Rgb(0.0f);
}

NPT_HD NPT_INLINE float bsdf_pdf(const Bsdf& b, Vec3 wo, Vec3 wi) {
    switch (b.kind) {
        case BsdfKind::Lambert:
            return lambert_pdf(wo, wi);
        case BsdfKind::Conductor:
            return ggx_reflection_pdf(make_conductor(ggx_alpha_from_roughness(b.roughness), b.base_color), wo,
                                      wi);
        case BsdfKind::Dielectric:
            return dielectric_pdf(make_dielectric(b), wo, wi);
        case BsdfKind::Principled:
            return principled_pdf(make_principled(b), wo, wi);
    }
    return 0.0f;
}

// false: no sample (absorbed, or a direction that carries no energy); *s is then unspecified.
NPT_HD NPT_INLINE bool bsdf_sample(const Bsdf& b, Vec3 wo, float u_lobe, Vec2 u, BsdfSample* s) {
    switch (b.kind) {
        case BsdfKind::Lambert:
            return lambert_sample(b.base_color, wo, u, s);
        case BsdfKind::Conductor:
            return ggx_reflection_sample(make_conductor(ggx_alpha_from_roughness(b.roughness), b.base_color),
                                         wo, u_lobe, u, s);
        case BsdfKind::Dielectric:
            return dielectric_sample(make_dielectric(b), wo, u_lobe, u, s);
        case BsdfKind::Principled:
            return principled_sample(make_principled(b), wo, u_lobe, u, s);
    }
    return false;
}

NPT_HD NPT_INLINE bool bsdf_is_delta(const Bsdf& b) {
    float alpha = ggx_alpha_from_roughness(b.roughness);
    switch (b.kind) {
        case BsdfKind::Lambert:
            return false;
        case BsdfKind::Conductor:
        case BsdfKind::Dielectric:
            return ggx_is_smooth(alpha);
        case BsdfKind::Principled:
            return principled_is_delta(make_principled(b));
    }
    return false;
}

NPT_HD NPT_INLINE bool bsdf_has_transmission(const Bsdf& b) {
    return b.kind == BsdfKind::Dielectric || (b.kind == BsdfKind::Principled && b.transmission > 0.0f);
}

}  // namespace npt::materials
