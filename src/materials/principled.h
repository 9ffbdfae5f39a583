// glTF 2.0 metallic-roughness (spec appendix B) with KHR_materials_specular, _transmission and _ior, as a
// layered mix: metal GGX + dielectric specular GGX over a diffuse / transmissive base, with
// multiple-scattering compensation on the GGX part. Sampling picks one of three strategies by an albedo
// estimate at wo.
#pragma once

#include "materials/conductor.h"
#include "materials/dielectric.h"
#include "materials/lambert.h"

namespace npt::materials {

struct Principled {
    GgxReflection spec;  // metal and dielectric specular layer share one GGX distribution
    Rgb base{1.0f};
    Rgb f0_diel{0.04f};  // glTF: min(((ior-1)/(ior+1))^2 * specular_color, 1)
    float specular = 1.0f;
    float w_diffuse = 0.0f;  // (1 - metallic) (1 - transmission)
    float w_trans = 0.0f;    // (1 - metallic) transmission
    DielectricLobe inside;   // the interface as seen from inside the body (wo.z < 0)
    float burley_roughness = -1.0f;  // >= 0: Burley's diffuse at this roughness (Bsdf::burley_diffuse)
};

NPT_HD NPT_INLINE Principled make_principled(const Bsdf& b) {
    Principled p;
    float alpha = ggx_alpha_from_roughness(b.roughness);
    float m = clampf(b.metallic, 0.0f, 1.0f), t = clampf(b.transmission, 0.0f, 1.0f);
    p.base = b.base_color;
    p.f0_diel = vmin(b.specular_color * f0_from_ior(b.ior), Rgb(1.0f));
    p.specular = b.specular;
    p.spec = {alpha, b.base_color, m, p.f0_diel, b.specular, 1.0f - m};
    p.w_diffuse = (1.0f - m) * (1.0f - t);
    p.w_trans = (1.0f - m) * t;
    p.inside = {alpha, b.ior, b.specular, b.specular_color, b.base_color};
    if (b.burley_diffuse) p.burley_roughness = clampf(b.roughness, 0.0f, 1.0f);
    return p;
}

// What the specular layer leaves to the base at cosine c: 1 - specular * Schlick(F0, c) (glTF fresnel_mix).
NPT_HD NPT_INLINE Rgb principled_layer_transmittance(const Principled& p, float c) {
    return Rgb(1.0f) - fresnel_schlick(p.f0_diel, c) * p.specular;
}

// Burley's diffuse factor (Disney 2012) as Cycles writes it: Lambert's 1 darkened at grazing angles, plus a
// retro-reflection that brightens them on rough surfaces; 2 cos^2(theta_d) = 1 + wo . wi.
NPT_HD NPT_INLINE float burley_diffuse_factor(float roughness, Vec3 wo, Vec3 wi) {
    const float mo = 1.0f - clampf(wo.z, 0.0f, 1.0f), mi = 1.0f - clampf(wi.z, 0.0f, 1.0f);
    const float fo = sqr(sqr(mo)) * mo, fi = sqr(sqr(mi)) * mi;  // Schlick's (1 - cos)^5
    const float rr = roughness * (1.0f + dot(wo, wi));
    return (1.0f - 0.5f * fo) * (1.0f - 0.5f * fi) + rr * (fo + fi + fo * fi * (rr - 1.0f));
}

// The diffuse base. Layered (the default): below the specular layer, in the reciprocal Kulla-Conty layering
// form base/pi (1 - sF(mu_o)) (1 - sF(mu_i)) / (1 - sF_avg), whose albedo is exactly base (1 - sF(mu_o)).
// Burley (Bsdf::burley_diffuse): base/pi times burley_diffuse_factor, beside the specular layer.
NPT_HD NPT_INLINE Rgb principled_diffuse(const Principled& p, Vec3 wo, Vec3 wi) {
    if (p.burley_roughness >= 0.0f)
        return p.base * (k_inv_pi * p.w_diffuse * burley_diffuse_factor(p.burley_roughness, wo, wi));
    Rgb avg = Rgb(1.0f) - fresnel_schlick_average(p.f0_diel) * p.specular;
    Rgb num = principled_layer_transmittance(p, wo.z) * principled_layer_transmittance(p, wi.z);
    return p.base * k_inv_pi * p.w_diffuse * Rgb(num.x / avg.x, num.y / avg.y, num.z / avg.z);
}

// Transmission through the specular layer into the body (wo outside, wi inside), Walter et al. 2007.
NPT_HD NPT_INLINE Rgb principled_btdf(const Principled& p, Vec3 wo, Vec3 wi, float* pdf) {
    *pdf = 0.0f;
    Vec3 wm;
    float etap;
    if (ggx_is_smooth(p.spec.alpha) || !dielectric_half_vector(p.inside.eta, wo, wi, &wm, &etap) ||
        etap == 1.0f)
        return Rgb(0.0f);
    float alpha = p.spec.alpha;
    float denom = sqr(dot(wi, wm) + dot(wo, wm) / etap);
    *pdf = ggx_pdf_visible(alpha, wo, wm) * absdot(wi, wm) / denom;
    float ft = ggx_d(alpha, wm) * ggx_g2(alpha, wo, wi) *
               fabsf(dot(wi, wm) * dot(wo, wm) / (denom * wi.z * wo.z)) / sqr(etap);
    return principled_layer_transmittance(p, dot(wo, wm)) * p.base * (p.w_trans * ft);
}

struct PrincipledLobeProbs {
    float spec, cosine, trans;
};

// Albedo estimates at wo of the GGX reflection (single scattering), the cosine-sampled parts (multiple
// scattering and diffuse) and the transmission, normalised.
NPT_HD NPT_INLINE PrincipledLobeProbs principled_probs(const Principled& p, float mu_o) {
    float e = ggx_is_smooth(p.spec.alpha) ? 1.0f : ggx_albedo(p.spec.alpha, mu_o);
    float base = p.burley_roughness >= 0.0f ? luminance(p.base)  // Burley's albedo is about base's
                                            : luminance(p.base * principled_layer_transmittance(p, mu_o));
    float w_spec = e * luminance(ggx_reflection_fresnel(p.spec, mu_o));
    float w_cos = (1.0f - e) * luminance(ggx_reflection_ms_tint(p.spec)) + p.w_diffuse * base;
    float w_trans = p.w_trans * base;
    float sum = w_spec + w_cos + w_trans;
    if (!(sum > 0.0f)) return {0.0f, 0.0f, 0.0f};
    return {w_spec / sum, w_cos / sum, w_trans / sum};
}

// From inside the body (wo.z < 0, only reachable through transmission) diffuse and metal play no part: the
// path meets only the dielectric interface, with the exact Fresnel term (Schlick has no total internal
// reflection).
NPT_HD NPT_INLINE Rgb principled_eval(const Principled& p, Vec3 wo, Vec3 wi) {
    if (wo.z < 0.0f) return p.w_trans > 0.0f ? dielectric_eval(p.inside, wo, wi) : Rgb(0.0f);
    if (wo.z == 0.0f) return Rgb(0.0f);
    if (wi.z > 0.0f) return ggx_reflection_eval(p.spec, wo, wi) + principled_diffuse(p, wo, wi);
    if (p.w_trans <= 0.0f) return Rgb(0.0f);
    float pdf;
    return principled_btdf(p, wo, wi, &pdf);
}

NPT_HD NPT_INLINE float principled_pdf(const Principled& p, Vec3 wo, Vec3 wi) {
    if (wo.z < 0.0f) return p.w_trans > 0.0f ? dielectric_pdf(p.inside, wo, wi) : 0.0f;
    if (wo.z == 0.0f) return 0.0f;
    PrincipledLobeProbs pr = principled_probs(p, wo.z);
    if (wi.z > 0.0f) {
        float pdf = pr.cosine * cosine_hemisphere_pdf(wi.z);
        if (!ggx_is_smooth(p.spec.alpha)) pdf += pr.spec * ggx_reflection_vndf_pdf(p.spec.alpha, wo, wi);
        return pdf;
    }
    if (pr.trans <= 0.0f) return 0.0f;
    float pdf;
    principled_btdf(p, wo, wi, &pdf);
    return pr.trans * pdf;
}

NPT_HD NPT_INLINE bool principled_sample(const Principled& p, Vec3 wo, float u_lobe, Vec2 u, BsdfSample* s) {
    if (wo.z < 0.0f) return p.w_trans > 0.0f && dielectric_sample(p.inside, wo, u_lobe, u, s);
    if (wo.z == 0.0f) return false;
    PrincipledLobeProbs pr = principled_probs(p, wo.z);
    bool smooth = ggx_is_smooth(p.spec.alpha);
    Vec3 wi;
    if (u_lobe < pr.spec) {
        if (smooth) {
            wi = Vec3(-wo.x, -wo.y, wo.z);
            *s = {wi, ggx_reflection_fresnel(p.spec, wo.z) / wo.z, pr.spec, true};
            return true;
        }
        wi = reflect(wo, ggx_sample_visible(p.spec.alpha, wo, u));
        if (wi.z <= 0.0f) return false;
    } else if (u_lobe < pr.spec + pr.cosine) {
        wi = sample_cosine_hemisphere(u);
        if (wi.z <= 0.0f) return false;
    } else {
        if (pr.trans <= 0.0f) return false;
        float etap;
        if (smooth) {
            if (!refract(wo, Vec3(0.0f, 0.0f, 1.0f), p.inside.eta, &etap, &wi) || wi.z >= 0.0f) return false;
            Rgb t = principled_layer_transmittance(p, wo.z) * p.base * p.w_trans;
            *s = {wi, t / (fabsf(wi.z) * sqr(etap)), pr.trans, true};
            return true;
        }
        Vec3 wm = ggx_sample_visible(p.spec.alpha, wo, u);
        if (!refract(wo, wm, p.inside.eta, &etap, &wi) || wi.z >= 0.0f) return false;
    }
    float pdf = principled_pdf(p, wo, wi);
    if (pdf <= 0.0f) return false;
    *s = {wi, principled_eval(p, wo, wi), pdf, false};
    return true;
}

NPT_HD NPT_INLINE bool principled_is_delta(const Principled& p) {
    return ggx_is_smooth(p.spec.alpha) && p.w_diffuse <= 0.0f;
}

}  // namespace npt::materials
