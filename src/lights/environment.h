// Light from infinity: a constant colour or an equirectangular map (+Y up) times a strength, rotated about
// +Y. Radiance lookup and importance sampling (piecewise-constant over texels, Jacobian 2 pi^2 sin(theta)).
#pragma once

#include "core/distribution_2d.h"
#include "core/platform.h"
#include "core/sampling.h"
#include "core/texture.h"
#include "core/vec.h"

namespace npt::lights {

struct EnvironmentView {
    Rgb color{0.0f};      // used when `texture` is not valid
    TextureView texture;  // equirectangular, linear RGBA
    float strength = 1.0f;
    // The map is turned by rotation_y about +Y: a feature at map direction d appears at world direction
    // R_y(rotation_y) d. Stored as cos/sin so the per-sample code does no trigonometry for it.
    float cos_rot = 1.0f;
    float sin_rot = 0.0f;
    Distribution2DView distribution;  // over (u, v) of the map; invalid for a constant colour
};

// Right-handed rotation about +Y by the angle whose cosine and sine are c and s.
NPT_HD NPT_INLINE Vec3 rotate_y(Vec3 d, float c, float s) {
    return {c * d.x + s * d.z, d.y, -s * d.x + c * d.z};
}

// Map direction (unrotated, unit) -> equirect uv: u = 0.5 + atan2(x, -z) / 2pi, v = acos(y) / pi (v = 0 is
// up).
NPT_HD NPT_INLINE Vec2 equirect_uv(Vec3 d) {
    float u = 0.5f + atan2f(d.x, -d.z) * k_inv_2pi;
    float v = acosf(clampf(d.y, -1.0f, 1.0f)) * k_inv_pi;
    // atan2 of (-0, -1) gives -pi, i.e. u = 0; fold u = 1 (from +pi) onto 0 so the result stays in [0,1).
    if (u >= 1.0f) u -= 1.0f;
    if (u < 0.0f) u += 1.0f;
    return {u, v};
}

// Inverse of equirect_uv.
NPT_HD NPT_INLINE Vec3 equirect_direction(Vec2 uv, float* sin_theta) {
    float phi = 2.0f * k_pi * (uv.x - 0.5f);
    float theta = k_pi * uv.y;
    float st = sinf(theta);
    *sin_theta = st;
    return {st * sinf(phi), cosf(theta), -st * cosf(phi)};
}

NPT_HD NPT_INLINE Vec3 environment_to_map(const EnvironmentView& env, Vec3 world_dir) {
    return rotate_y(world_dir, env.cos_rot, -env.sin_rot);
}
NPT_HD NPT_INLINE Vec3 environment_to_world(const EnvironmentView& env, Vec3 map_dir) {
    return rotate_y(map_dir, env.cos_rot, env.sin_rot);
}

// Radiance arriving from direction `dir` (unit, pointing away from the scene).
NPT_HD NPT_INLINE Rgb environment_radiance(const EnvironmentView& env, Vec3 dir) {
    if (!env.texture.valid()) return env.color * env.strength;
    Vec2 uv = equirect_uv(environment_to_map(env, dir));
    return env.texture.sample(uv).rgb() * env.strength;
}

// Solid-angle density of environment_sample, without the light-selection probability.
NPT_HD NPT_INLINE float environment_pdf(const EnvironmentView& env, Vec3 dir) {
    if (!env.distribution.valid()) return env.texture.valid() ? 0.0f : uniform_sphere_pdf();
    Vec3 d = environment_to_map(env, dir);
    float sin_theta = safe_sqrt(1.0f - d.y * d.y);
    if (sin_theta <= 0.0f) return 0.0f;
    return env.distribution.pdf(equirect_uv(d)) / (2.0f * k_pi * k_pi * sin_theta);
}

// Picks a direction towards the environment; returns false when nothing can be sampled. pdf is solid-angle,
// without the light-selection probability.
NPT_HD NPT_INLINE bool environment_sample(const EnvironmentView& env, Vec2 u, Vec3* wi, Rgb* radiance,
                                          float* pdf) {
    if (!env.texture.valid()) {
        *wi = sample_uniform_sphere(u);
        *pdf = uniform_sphere_pdf();
        *radiance = env.color * env.strength;
        return !is_black(*radiance);
    }
    float pdf_uv;
    Vec2 uv = env.distribution.sample(u, &pdf_uv);
    float sin_theta;
    Vec3 d = equirect_direction(uv, &sin_theta);
    if (pdf_uv <= 0.0f || sin_theta <= 0.0f) return false;
    *wi = environment_to_world(env, d);
    *pdf = pdf_uv / (2.0f * k_pi * k_pi * sin_theta);
    *radiance = environment_radiance(env, *wi);
    return true;
}

}  // namespace npt::lights
