// Warps from the unit square to directions and points, with their densities; the MIS heuristic.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt {

NPT_HD NPT_INLINE Vec2 sample_concentric_disk(Vec2 u) {
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    if (ox == 0.0f && oy == 0.0f) return {0.0f, 0.0f};
    float r, theta;
    if (fabsf(ox) > fabsf(oy)) {
        r = ox;
        theta = 0.25f * k_pi * (oy / ox);
    } else {
        r = oy;
        theta = 0.5f * k_pi - 0.25f * k_pi * (ox / oy);
    }
    return {r * cosf(theta), r * sinf(theta)};
}

// Cosine-weighted hemisphere about +z; pdf = cos(theta) / pi.
NPT_HD NPT_INLINE Vec3 sample_cosine_hemisphere(Vec2 u) {
    Vec2 d = sample_concentric_disk(u);
    float z = safe_sqrt(1.0f - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}
NPT_HD NPT_INLINE float cosine_hemisphere_pdf(float cos_theta) { return fmaxf(cos_theta, 0.0f) * k_inv_pi; }

NPT_HD NPT_INLINE Vec3 sample_uniform_sphere(Vec2 u) {
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z);
    float phi = 2.0f * k_pi * u.y;
    return {r * cosf(phi), r * sinf(phi), z};
}
NPT_HD NPT_INLINE float uniform_sphere_pdf() { return k_inv_4pi; }

// Uniform cone about +z with half-angle acos(cos_max); pdf = 1 / (2 pi (1 - cos_max)).
NPT_HD NPT_INLINE Vec3 sample_uniform_cone(Vec2 u, float cos_max) {
    float cos_t = (1.0f - u.x) + u.x * cos_max;
    float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
    float phi = 2.0f * k_pi * u.y;
    return {cosf(phi) * sin_t, sinf(phi) * sin_t, cos_t};
}

// Barycentrics (b1, b2) uniform over a triangle (Heitz 2019 low-distortion map); b0 = 1 - b1 - b2.
NPT_HD NPT_INLINE Vec2 sample_uniform_triangle(Vec2 u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0f;
        b0 = u.x - b1;
    }
    return {b0, b1};
}

// Power heuristic with beta = 2 (Veach 1997) for one sample from each of two strategies.
NPT_HD NPT_INLINE float power_heuristic(float pdf_a, float pdf_b) {
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    if (a == 0.0f) return 0.0f;
    if (isinf(a)) return 1.0f;
    return a / (a + b);
}

}  // namespace npt
