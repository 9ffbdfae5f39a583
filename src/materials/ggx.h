// Isotropic Trowbridge-Reitz (GGX) microfacet distribution: D, height-correlated Smith G1/G2, visible-normal
// sampling (Heitz 2018), and the tabulated single-scattering albedo that the multiple-scattering compensation
// (Kulla & Conty 2017) needs. All directions are in the local frame, z = macro normal.
#pragma once

#include "core/platform.h"
#include "core/vec.h"
#include "materials/ggx_albedo_table.h"

namespace npt::materials {

// Below this alpha a lobe is treated as a perfect mirror/refractor: the float GGX lobe is then narrower than
// the precision of its own sampling and evaluation.
constexpr float k_delta_alpha = 1e-3f;

// glTF perceptual roughness -> GGX alpha; alpha below k_delta_alpha means "smooth" (see ggx_is_smooth).
NPT_HD NPT_INLINE float ggx_alpha_from_roughness(float roughness) {
    return sqr(clampf(roughness, 0.0f, 1.0f));
}
NPT_HD NPT_INLINE bool ggx_is_smooth(float alpha) { return alpha < k_delta_alpha; }

// sin^2 is taken from the tangential components, not as 1 - cos^2: near the peak of a sharp lobe 1 - cos^2
// cancels catastrophically in float and D would lose most of its digits.
NPT_HD NPT_INLINE float ggx_d(float alpha, Vec3 wm) {
    float cos2 = wm.z * wm.z;
    if (cos2 <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float t = (wm.x * wm.x + wm.y * wm.y) + cos2 * a2;
    return a2 / (k_pi * t * t);
}

NPT_HD NPT_INLINE float ggx_lambda(float alpha, Vec3 w) {
    float cos2 = w.z * w.z;
    if (cos2 <= 0.0f) return 1e30f;
    float tan2 = (w.x * w.x + w.y * w.y) / cos2;  // not (1 - cos2) / cos2, for the same reason as in ggx_d
    return 0.5f * (-1.0f + sqrtf(1.0f + alpha * alpha * tan2));
}

NPT_HD NPT_INLINE float ggx_g1(float alpha, Vec3 w) { return 1.0f / (1.0f + ggx_lambda(alpha, w)); }

// Height-correlated masking-shadowing (Heitz 2014): the form the albedo table is computed for.
NPT_HD NPT_INLINE float ggx_g2(float alpha, Vec3 wo, Vec3 wi) {
    return 1.0f / (1.0f + ggx_lambda(alpha, wo) + ggx_lambda(alpha, wi));
}

// Density of visible normals seen from w: G1(w) max(0, w.m) D(m) / |w.z|. Solid-angle pdf over m.
NPT_HD NPT_INLINE float ggx_pdf_visible(float alpha, Vec3 w, Vec3 wm) {
    float cos_w = fabsf(w.z);
    if (cos_w == 0.0f) return 0.0f;
    return ggx_g1(alpha, w) * absdot(w, wm) * ggx_d(alpha, wm) / cos_w;
}

// Heitz 2018, "Sampling the GGX distribution of visible normals". Returns m in the upper hemisphere. For w
// below the surface (inside a dielectric) the visible facets are those whose backs face w, i.e. those visible
// from -w.
NPT_HD NPT_INLINE Vec3 ggx_sample_visible(float alpha, Vec3 w, Vec2 u) {
    if (w.z < 0.0f) w = -w;
    Vec3 wh = normalize(Vec3(alpha * w.x, alpha * w.y, w.z));
    float lensq = wh.x * wh.x + wh.y * wh.y;
    Vec3 t1 = lensq > 0.0f ? Vec3(-wh.y, wh.x, 0.0f) * (1.0f / sqrtf(lensq)) : Vec3(1.0f, 0.0f, 0.0f);
    Vec3 t2 = cross(wh, t1);
    float r = sqrtf(u.x);
    float phi = 2.0f * k_pi * u.y;
    float p1 = r * cosf(phi), p2 = r * sinf(phi);
    float s = 0.5f * (1.0f + wh.z);
    p2 = (1.0f - s) * safe_sqrt(1.0f - p1 * p1) + s * p2;
    Vec3 nh = t1 * p1 + t2 * p2 + wh * safe_sqrt(1.0f - p1 * p1 - p2 * p2);
    return normalize(Vec3(alpha * nh.x, alpha * nh.y, fmaxf(1e-6f, nh.z)));
}

// Bilinear lookup in the albedo table: rows by perceptual roughness sqrt(alpha), columns by sqrt(mu).
NPT_HD NPT_INLINE float ggx_albedo(float alpha, float mu) {
    float y = clampf(sqrtf(alpha), 0.0f, 1.0f) * float(k_ggx_table_n_rough - 1);
    float x = clampf(sqrtf(clampf(mu, 0.0f, 1.0f)), 0.0f, 1.0f) * float(k_ggx_table_n_mu - 1);
    int j = int(y) < k_ggx_table_n_rough - 2 ? int(y) : k_ggx_table_n_rough - 2;
    int i = int(x) < k_ggx_table_n_mu - 2 ? int(x) : k_ggx_table_n_mu - 2;
    float ty = y - float(j), tx = x - float(i);
    float e0 = ggx_albedo_entry(j, i) * (1.0f - tx) + ggx_albedo_entry(j, i + 1) * tx;
    float e1 = ggx_albedo_entry(j + 1, i) * (1.0f - tx) + ggx_albedo_entry(j + 1, i + 1) * tx;
    return e0 * (1.0f - ty) + e1 * ty;
}

NPT_HD NPT_INLINE float ggx_albedo_average(float alpha) {
    float y = clampf(sqrtf(alpha), 0.0f, 1.0f) * float(k_ggx_table_n_rough - 1);
    int j = int(y) < k_ggx_table_n_rough - 2 ? int(y) : k_ggx_table_n_rough - 2;
    float ty = y - float(j);
    return ggx_albedo_avg_entry(j) * (1.0f - ty) + ggx_albedo_avg_entry(j + 1) * ty;
}

// Kulla-Conty multiple-scattering lobe for Fresnel = 1, without its Fresnel tint:
// f_ms = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)). Reciprocal, and its cosine integral is exactly
// 1 - E(mu_o) of the table, so a white conductor conserves energy up to the table's interpolation error.
NPT_HD NPT_INLINE float ggx_ms_lobe(float alpha, float mu_o, float mu_i) {
    float e_avg = ggx_albedo_average(alpha);
    if (e_avg >= 1.0f - 1e-6f) return 0.0f;
    return (1.0f - ggx_albedo(alpha, mu_o)) * (1.0f - ggx_albedo(alpha, mu_i)) / (k_pi * (1.0f - e_avg));
}

// Colour of the multiple-scattering lobe for a lobe whose average Fresnel is f_avg (Kulla & Conty 2017, eq.
// 15): every bounce between microfacets is tinted again, so energy lost to single scattering returns
// saturated.
NPT_HD NPT_INLINE Rgb ggx_ms_fresnel(Rgb f_avg, float alpha) {
    float e_avg = ggx_albedo_average(alpha);
    Rgb num = f_avg * f_avg * e_avg;
    Rgb den = Rgb(1.0f) - f_avg * (1.0f - e_avg);
    return {num.x / fmaxf(den.x, 1e-6f), num.y / fmaxf(den.y, 1e-6f), num.z / fmaxf(den.z, 1e-6f)};
}

}  // namespace npt::materials
