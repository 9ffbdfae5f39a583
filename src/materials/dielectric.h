// Smooth and rough (GGX, Walter et al. 2007) dielectric interface: reflection plus refraction with the exact
// Fresnel term, sampled through visible normals (Heitz 2018). Transmission transports radiance (1/eta^2) and
// is tinted by glTF's base colour at every crossing; KHR_materials_specular scales the reflectance.
#pragma once

#include "materials/bsdf_types.h"
#include "materials/fresnel.h"
#include "materials/ggx.h"

namespace npt::materials {

struct DielectricLobe {
    float alpha = 0.0f;
    float eta = 1.5f;          // n_inside / n_outside; z of the local frame is the outside (front) normal
    float specular = 1.0f;     // KHR_materials_specular: reflectance scale ...
    Rgb specular_color{1.0f};  // ... and tint, applied to the exact Fresnel (clamped to 1)
    Rgb tint{1.0f};            // multiplies transmitted radiance
};

// Per-channel reflectance at a (micro)surface with cosine cos_o toward wo. Total internal reflection stays
// total whatever the specular parameters: no light may leak out of that case.
NPT_HD NPT_INLINE Rgb dielectric_reflectance(const DielectricLobe& d, float cos_o) {
    float fr = fresnel_dielectric(cos_o, d.eta);
    if (fr >= 1.0f) return Rgb(1.0f);
    return vmin(d.specular_color * fr, Rgb(1.0f)) * d.specular;
}

NPT_HD NPT_INLINE float mean3(Rgb c) { return (c.x + c.y + c.z) * (1.0f / 3.0f); }

// Generalised half vector of (wo, wi) for reflection or refraction, oriented to +z; false for degenerate or
// back-facing configurations, which carry no energy.
NPT_HD NPT_INLINE bool dielectric_half_vector(float eta, Vec3 wo, Vec3 wi, Vec3* wm, float* etap) {
    float cos_o = wo.z, cos_i = wi.z;
    if (cos_o == 0.0f || cos_i == 0.0f) return false;
    bool reflect_ = cos_o * cos_i > 0.0f;
    *etap = reflect_ ? 1.0f : (cos_o > 0.0f ? eta : 1.0f / eta);
    Vec3 m = wi * *etap + wo;
    if (length_squared(m) == 0.0f) return false;
    m = normalize(m);
    if (m.z < 0.0f) m = -m;
    if (dot(m, wi) * cos_i < 0.0f || dot(m, wo) * cos_o < 0.0f) return false;
    *wm = m;
    return true;
}

NPT_HD NPT_INLINE Rgb dielectric_eval(const DielectricLobe& d, Vec3 wo, Vec3 wi) {
    if (ggx_is_smooth(d.alpha) || d.eta == 1.0f) return Rgb(0.0f);
    Vec3 wm;
    float etap;
    if (!dielectric_half_vector(d.eta, wo, wi, &wm, &etap)) return Rgb(0.0f);
    Rgb r = dielectric_reflectance(d, dot(wo, wm));
    float dg = ggx_d(d.alpha, wm) * ggx_g2(d.alpha, wo, wi);
    if (etap == 1.0f) return r * (dg / fabsf(4.0f * wo.z * wi.z));
    float denom = sqr(dot(wi, wm) + dot(wo, wm) / etap) * wi.z * wo.z;
    float ft = dg * fabsf(dot(wi, wm) * dot(wo, wm) / denom) / sqr(etap);
    return (Rgb(1.0f) - r) * d.tint * ft;
}

NPT_HD NPT_INLINE float dielectric_pdf(const DielectricLobe& d, Vec3 wo, Vec3 wi) {
    if (ggx_is_smooth(d.alpha) || d.eta == 1.0f) return 0.0f;
    Vec3 wm;
    float etap;
    if (!dielectric_half_vector(d.eta, wo, wi, &wm, &etap)) return 0.0f;
    float pr = mean3(dielectric_reflectance(d, dot(wo, wm)));
    float pdf_m = ggx_pdf_visible(d.alpha, wo, wm);
    if (etap == 1.0f) return pr * pdf_m / (4.0f * absdot(wo, wm));
    float denom = sqr(dot(wi, wm) + dot(wo, wm) / etap);
    return (1.0f - pr) * pdf_m * absdot(wi, wm) / denom;
}

NPT_HD NPT_INLINE bool dielectric_sample(const DielectricLobe& d, Vec3 wo, float u_lobe, Vec2 u,
                                         BsdfSample* s) {
    if (wo.z == 0.0f) return false;
    if (ggx_is_smooth(d.alpha) || d.eta == 1.0f) {
        Rgb r = dielectric_reflectance(d, wo.z);
        float pr = mean3(r);
        if (u_lobe < pr) {
            Vec3 wi(-wo.x, -wo.y, wo.z);
            *s = {wi, r / fabsf(wi.z), pr, true};
            return true;
        }
        Vec3 wi;
        float etap;
        if (!refract(wo, Vec3(0.0f, 0.0f, 1.0f), d.eta, &etap, &wi) || wi.z == 0.0f) return false;
        *s = {wi, (Rgb(1.0f) - r) * d.tint / (fabsf(wi.z) * sqr(etap)), 1.0f - pr, true};
        return true;
    }
    Vec3 wm = ggx_sample_visible(d.alpha, wo, u);
    float pr = mean3(dielectric_reflectance(d, dot(wo, wm)));
    Vec3 wi;
    if (u_lobe < pr) {
        wi = reflect(wo, wm);
        if (wi.z * wo.z <= 0.0f) return false;
    } else {
        float etap;
        if (!refract(wo, wm, d.eta, &etap, &wi) || wi.z * wo.z >= 0.0f) return false;
    }
    float pdf = dielectric_pdf(d, wo, wi);
    if (pdf <= 0.0f) return false;
    *s = {wi, dielectric_eval(d, wo, wi), pdf, false};
    return true;
}

}  // namespace npt::materials
