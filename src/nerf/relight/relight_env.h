// The capture environment's equirectangular map (relight_model.h: CaptureEnvironment) in model-space
// directions: u = atan2(d.y, d.x) / 2pi + 0.5 across, v = acos(d.z) / pi down. Bilinear lookups with their four
// texel weights, so the relight trainer can push a gradient into the texels it read.
#pragma once

#include <math.h>
#include <stdint.h>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct EnvTaps {
    int index[4];
    float weight[4];
};

// Direction d's continuous texel coordinates: texel (i, j)'s centre at (i, j); x across (u), y down (v).
NPT_HD NPT_INLINE void env_texel_coords(int width, int height, Vec3 d, float* x, float* y) {
    constexpr float k_pi = 3.14159265358979f;
    const float u = atan2f(d.y, d.x) * (0.5f / k_pi) + 0.5f;
    const float v = acosf(fminf(1.0f, fmaxf(-1.0f, d.z))) * (1.0f / k_pi);
    *x = u * float(width) - 0.5f;
    *y = v * float(height) - 0.5f;
}

// The bilinear lookup between column x0 and x0 + 1 (wrapping around) and row y0 and y0 + 1 (clamped at the
// poles), at fractions ax, ay.
NPT_HD NPT_INLINE EnvTaps env_bilinear_taps(int width, int height, int x0, int y0, float ax, float ay) {
    const int x1 = ((x0 + 1) % width + width) % width;
    x0 = (x0 % width + width) % width;
    const int y1 = y0 + 1 < 0 ? 0 : (y0 + 1 >= height ? height - 1 : y0 + 1);
    y0 = y0 < 0 ? 0 : (y0 >= height ? height - 1 : y0);
    EnvTaps t;
    t.index[0] = y0 * width + x0;
    t.index[1] = y0 * width + x1;
    t.index[2] = y1 * width + x0;
    t.index[3] = y1 * width + x1;
    t.weight[0] = (1.0f - ax) * (1.0f - ay);
    t.weight[1] = ax * (1.0f - ay);
    t.weight[2] = (1.0f - ax) * ay;
    t.weight[3] = ax * ay;
    return t;
}

// Texel centres sit at ((i + 0.5) / W, (j + 0.5) / H); u wraps around, v clamps at the poles.
NPT_HD NPT_INLINE EnvTaps env_taps(int width, int height, Vec3 d) {
    float x, y;
    env_texel_coords(width, height, d, &x, &y);
    const float fx = floorf(x), fy = floorf(y);
    return env_bilinear_taps(width, height, int(fx), int(fy), x - fx, y - fy);
}

// env_taps' lookup kept in 8 bytes (the relight fit keeps one per light direction of millions of points): the
// first texel's column and row (+ 1: the row above the first is -1 near the pole) and the bilinear fractions
// in 16 bits. For maps of at most 65535 x 65534 texels.
struct PackedEnvTaps {
    uint16_t x0, y0_plus_1, ax, ay;
};

NPT_HD NPT_INLINE PackedEnvTaps pack_env_taps(int width, int height, Vec3 d) {
    float x, y;
    env_texel_coords(width, height, d, &x, &y);
    const float fx = floorf(x), fy = floorf(y);
    const int y0 = int(fy) < -1 ? -1 : (int(fy) >= height ? height - 1 : int(fy));
    PackedEnvTaps p;
    p.x0 = uint16_t((int(fx) % width + width) % width);
    p.y0_plus_1 = uint16_t(y0 + 1);
    p.ax = uint16_t(fminf(65535.0f, (x - fx) * 65535.0f + 0.5f));
    p.ay = uint16_t(fminf(65535.0f, (y - fy) * 65535.0f + 0.5f));
    return p;
}

NPT_HD NPT_INLINE EnvTaps unpack_env_taps(int width, int height, PackedEnvTaps p) {
    return env_bilinear_taps(width, height, p.x0, int(p.y0_plus_1) - 1, float(p.ax) * (1.0f / 65535.0f),
                             float(p.ay) * (1.0f / 65535.0f));
}

// The direction through texel (i, j)'s centre.
NPT_HD NPT_INLINE Vec3 env_texel_direction(int width, int height, int i, int j) {
    constexpr float k_pi = 3.14159265358979f;
    const float phi = ((float(i) + 0.5f) / float(width) - 0.5f) * 2.0f * k_pi;
    const float theta = (float(j) + 0.5f) / float(height) * k_pi;
    return Vec3(sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta));
}

// The solid angle of a texel in row j.
NPT_HD NPT_INLINE float env_texel_solid_angle(int width, int height, int j) {
    constexpr float k_pi = 3.14159265358979f;
    const float t0 = float(j) / float(height) * k_pi, t1 = float(j + 1) / float(height) * k_pi;
    return (cosf(t0) - cosf(t1)) * 2.0f * k_pi / float(width);
}

}  // namespace npt::nerf
