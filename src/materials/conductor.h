// Rough (GGX) and smooth conductor reflection with Schlick Fresnel and Kulla-Conty multiple-scattering
// compensation. GgxReflection is the shared specular reflection lobe: the conductor uses one Schlick Fresnel,
// the principled material a metallic-weighted mix of the metal and the dielectric specular layer.
#pragma once

#include "core/sampling.h"
#include "materials/bsdf_types.h"
#include "materials/fresnel.h"
#include "materials/ggx.h"

namespace npt::materials {

// F(c) = w_metal Schlick(f0_metal, c) + w_diel s_diel Schlick(f0_diel, c). s_diel (KHR_materials_specular)
// scales only the dielectric layer's Fresnel, w_* are the metallic mix weights.
struct GgxReflection {
    float alpha = 1.0f;
    Rgb f0_metal{1.0f};
    float w_metal = 1.0f;
    Rgb f0_diel{0.04f};
    float s_diel = 1.0f;
    float w_diel = 0.0f;
};

NPT_HD NPT_INLINE GgxReflection make_conductor(float alpha, Rgb f0) {
    return {alpha, f0, 1.0f, Rgb(0.0f), 0.0f, 0.0f};
}

NPT_HD NPT_INLINE Rgb ggx_reflection_fresnel(const GgxReflection& g, float cos_h) {
    return fresnel_schlick(g.f0_metal, cos_h) * g.w_metal +
           fresnel_schlick(g.f0_diel, cos_h) * (g.w_diel * g.s_diel);
}

// Tint of the multiple-scattering lobe: each part of the mix bounces between its own microfacets.
NPT_HD NPT_INLINE Rgb ggx_reflection_ms_tint(const GgxReflection& g) {
    Rgb t(0.0f);
    if (g.w_metal > 0.0f) t += ggx_ms_fresnel(fresnel_schlick_average(g.f0_metal), g.alpha) * g.w_metal;
    if (g.w_diel > 0.0f)
        t += ggx_ms_fresnel(fresnel_schlick_average(g.f0_diel) * g.s_diel, g.alpha) * g.w_diel;
    return t;
}

// Probability of sampling the (cosine-distributed) multiple-scattering lobe instead of the visible normals:
// the fraction of the lobe's albedo at wo that the compensation carries.
NPT_HD NPT_INLINE float ggx_reflection_ms_prob(const GgxReflection& g, float mu_o) {
    if (ggx_is_smooth(g.alpha)) return 0.0f;
    float e = ggx_albedo(g.alpha, mu_o);
    float ms = (1.0f - e) * luminance(ggx_reflection_ms_tint(g));
    float ss = e * luminance(ggx_reflection_fresnel(g, mu_o));
    return ms + ss > 0.0f ? ms / (ms + ss) : 0.0f;
}

// Non-delta part of the lobe (single + multiple scattering); 0 when the lobe is smooth.
NPT_HD NPT_INLINE Rgb ggx_reflection_eval(const GgxReflection& g, Vec3 wo, Vec3 wi) {
    if (wo.z <= 0.0f || wi.z <= 0.0f || ggx_is_smooth(g.alpha)) return Rgb(0.0f);
    Vec3 wm = wo + wi;
    if (length_squared(wm) == 0.0f) return Rgb(0.0f);
    wm = normalize(wm);
    Rgb f_ss = ggx_reflection_fresnel(g, dot(wo, wm)) *
               (ggx_d(g.alpha, wm) * ggx_g2(g.alpha, wo, wi) / (4.0f * wo.z * wi.z));
    return f_ss + ggx_reflection_ms_tint(g) * ggx_ms_lobe(g.alpha, wo.z, wi.z);
}

// Solid-angle pdf of wi from visible-normal sampling alone: D_wo(wm) / (4 |wo.wm|).
NPT_HD NPT_INLINE float ggx_reflection_vndf_pdf(float alpha, Vec3 wo, Vec3 wi) {
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    Vec3 wm = wo + wi;
    if (length_squared(wm) == 0.0f) return 0.0f;
    wm = normalize(wm);
    float d = dot(wo, wm);
    if (d <= 0.0f) return 0.0f;
    return ggx_pdf_visible(alpha, wo, wm) / (4.0f * d);
}

// Mixture pdf of the two strategies of the lobe, p_ms being ggx_reflection_ms_prob at wo.
NPT_HD NPT_INLINE float ggx_reflection_pdf(const GgxReflection& g, Vec3 wo, Vec3 wi) {
    if (wo.z <= 0.0f || wi.z <= 0.0f || ggx_is_smooth(g.alpha)) return 0.0f;
    float p_ms = ggx_reflection_ms_prob(g, wo.z);
    return (1.0f - p_ms) * ggx_reflection_vndf_pdf(g.alpha, wo, wi) + p_ms * cosine_hemisphere_pdf(wi.z);
}

// Direction only: the caller evaluates f and pdf (of its full mixture) at it. u_lobe in [0,1) picks the
// strategy.
NPT_HD NPT_INLINE bool ggx_reflection_sample_dir(const GgxReflection& g, Vec3 wo, float u_lobe, Vec2 u,
                                                 Vec3* wi) {
    if (u_lobe < ggx_reflection_ms_prob(g, wo.z)) {
        *wi = sample_cosine_hemisphere(u);
    } else {
        Vec3 wm = ggx_sample_visible(g.alpha, wo, u);
        *wi = reflect(wo, wm);
    }
    return wi->z > 0.0f;
}

NPT_HD NPT_INLINE bool ggx_reflection_sample(const GgxReflection& g, Vec3 wo, float u_lobe, Vec2 u,
                                             BsdfSample* s) {
    if (wo.z <= 0.0f) return false;
    if (ggx_is_smooth(g.alpha)) {
        // Mirror: f = F / cos so that f cos / pdf = F; the only lobe, so its pmf is 1.
        Vec3 wi(-wo.x, -wo.y, wo.z);
        *s = {wi, ggx_reflection_fresnel(g, wo.z) / wo.z, 1.0f, true};
        return true;
    }
    Vec3 wi;
    if (!ggx_reflection_sample_dir(g, wo, u_lobe, u, &wi)) return false;
    float pdf = ggx_reflection_pdf(g, wo, wi);
    if (pdf <= 0.0f) return false;
    *s = {wi, ggx_reflection_eval(g, wo, wi), pdf, false};
    return true;
}

}  // namespace npt::materials
