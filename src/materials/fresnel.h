// Fresnel reflectance (exact dielectric and Schlick) and refraction, shared by every BSDF in this folder.
// Conventions: eta is the relative index n_inside / n_outside; a negative cosine means the incident direction
// lies inside, so the relative index inverts.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::materials {

// Unpolarised Fresnel reflectance of a smooth dielectric interface; 1 under total internal reflection.
NPT_HD NPT_INLINE float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clampf(cos_i, -1.0f, 1.0f);
    if (cos_i < 0.0f) {
        eta = 1.0f / eta;
        cos_i = -cos_i;
    }
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f;
    float cos_t = safe_sqrt(1.0f - sin2_t);
    float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_par * r_par + r_perp * r_perp);
}

NPT_HD NPT_INLINE float schlick_weight(float cos_t) {
    float m = clampf(1.0f - cos_t, 0.0f, 1.0f);
    float m2 = m * m;
    return m2 * m2 * m;
}

NPT_HD NPT_INLINE Rgb fresnel_schlick(Rgb f0, float cos_t) {
    return lerp(schlick_weight(cos_t), f0, Rgb(1.0f));
}

// Hemispherical average 2 * integral F(mu) mu dmu of Schlick's approximation: 2 * B(2, 6) = 1/21.
NPT_HD NPT_INLINE Rgb fresnel_schlick_average(Rgb f0) { return f0 + (Rgb(1.0f) - f0) * (1.0f / 21.0f); }

// Normal-incidence reflectance of a dielectric with relative index eta.
NPT_HD NPT_INLINE float f0_from_ior(float eta) { return sqr((eta - 1.0f) / (eta + 1.0f)); }

// Refracts wi about n (both on the same side); eta = n_t / n_i relative to the side n points to. Returns
// false under total internal reflection. *etap receives the effective relative index used.
NPT_HD NPT_INLINE bool refract(Vec3 wi, Vec3 n, float eta, float* etap, Vec3* wt) {
    float cos_i = dot(n, wi);
    if (cos_i < 0.0f) {
        eta = 1.0f / eta;
        cos_i = -cos_i;
        n = -n;
    }
    float sin2_t = fmaxf(0.0f, 1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return false;
    float cos_t = safe_sqrt(1.0f - sin2_t);
    *wt = -wi / eta + n * (cos_i / eta - cos_t);
    if (etap) *etap = eta;
    return true;
}

}  // namespace npt::materials
