// The surface-smoothness loss of NeRF training (loss.surface_smoothness), shared by the CPU and GPU trainers.
// A hash-grid NeRF carves its colour edges into its density (the relight stage's normals come from that
// surface: issue 24). The loss takes groups of three rays through pixels on one image line (train_pixel.h),
// each ray's expected termination point P = sum w_i p_i / sum w_i, and penalises the bend of the three points:
// with u = (P_0 - P_2) / |P_0 - P_2|,
//   b = (I - u u^T) (P_0 - 2 P_1 + P_2) / |P_0 - P_2|,  loss = weight * |b|^2 / (1 + |b|^2 / scale^2).
// Only the part across the line counts: three rays through collinear pixels meet a plane in three collinear
// points, unevenly spaced when the plane is seen at an angle, so the loss is zero on any plane. It is small
// on a surface curved at a scale much larger than the pixels' spacing, and redescending (its gradient falls to
// zero) for bends much larger than `scale`: at depth edges and creases the loss lets go. The loss is skipped
// where a ray's opacity is below k_min_smoothness_alpha (a silhouette: P is not on a surface).
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/composite.h"

namespace npt::nerf {

constexpr float k_min_smoothness_alpha = 0.5f;

// Over a ray's samples before its stop: sum w_i p_i, sum w_i = 1 - T_end (the forward's weights), and the
// optical depth they add up to (kept for the backward pass, which walks back from T_end).
struct SurfacePoint {
    Vec3 weighted_sum{0.0f, 0.0f, 0.0f};
    float alpha = 0.0f;
    float optical_depth = 0.0f;
    NPT_HD Vec3 point() const { return weighted_sum * (1.0f / alpha); }
};

NPT_HD inline SurfacePoint surface_point(const float* sigma, const Vec3* pos, const float* dt, int used) {
    SurfacePoint s;
    float tau = 0.0f;
    for (int i = 0; i < used; ++i) {
        const float depth = sigma[i] * dt[i];
        s.weighted_sum += pos[i] * (expf(-tau) * composite_alpha(depth));
        tau += depth;
    }
    s.alpha = -expm1f(-tau);
    s.optical_depth = tau;
    return s;
}

struct SmoothnessTerm {
    float loss = 0.0f;
    Vec3 d_point[3];  // dLoss / dP_k
    bool active = false;
};

NPT_HD inline SmoothnessTerm smoothness_term(const SurfacePoint* s, float weight, float scale) {
    SmoothnessTerm t;
    for (int k = 0; k < 3; ++k) {
        t.d_point[k] = Vec3(0.0f);
        if (!(s[k].alpha >= k_min_smoothness_alpha)) return t;
    }
    const Vec3 p0 = s[0].point(), p1 = s[1].point(), p2 = s[2].point();
    const float span = length(p0 - p2);
    if (!(span > 1e-7f)) return t;
    const Vec3 u = (p0 - p2) * (1.0f / span);
    const Vec3 second = p0 - p1 * 2.0f + p2;
    const float along = dot(second, u);
    const Vec3 b = (second - u * along) * (1.0f / span);
    const float b2 = dot(b, b);
    const float r = 1.0f / (1.0f + b2 / (scale * scale));
    t.loss = weight * b2 * r;
    // Through s = P_0 - 2 P_1 + P_2 and d = P_0 - P_2 (b = s / |d| - d (d.s) / |d|^3; g = dLoss/db is
    // perpendicular to d): dLoss/ds = g / |d|, dLoss/dd = -(u (g.b) + g (u.s) / |d|) / |d|.
    const Vec3 g = b * (2.0f * weight * r * r);
    const Vec3 d_second = g * (1.0f / span);
    const Vec3 d_span = (u * dot(g, b) + g * (along / span)) * (-1.0f / span);
    t.d_point[0] = d_second + d_span;
    t.d_point[1] = d_second * -2.0f;
    t.d_point[2] = d_second - d_span;
    t.active = isfinite(t.loss);
    return t;
}

// Adds d(d_point . P)/d sigma_i to d_sigma[i] for i < used, with P = s.point():
//   dP/d sigma_i = dt_i [(T_{i+1} p_i - S_i) / A - P T_end / A],  S_i = sum_{i<j<used} w_j p_j,  A = s.alpha,
// (the colour's derivative, composite.h, with the positions as colour and no background, and the derivative
// of the normalisation, dA/d sigma_i = dt_i T_end).
NPT_HD inline void surface_point_backward_add(const float* sigma, const Vec3* pos, const float* dt, int used,
                                              const SurfacePoint& s, Vec3 d_point, float* d_sigma) {
    if (!(s.alpha > 0.0f)) return;
    float tau = s.optical_depth;
    const float t_end = expf(-tau);
    const float inv_a = 1.0f / s.alpha;
    const float g_point_t_end = dot(d_point, s.point()) * t_end;
    Vec3 behind(0.0f);  // S_i
    float t_after = t_end;
    for (int i = used - 1; i >= 0; --i) {
        const float depth = sigma[i] * dt[i];
        tau = fmaxf(tau - depth, 0.0f);
        const float t_before = expf(-tau);
        d_sigma[i] += dt[i] * inv_a * (dot(d_point, pos[i] * t_after - behind) - g_point_t_end);
        behind += pos[i] * (t_before * composite_alpha(depth));
        t_after = t_before;
    }
}

}  // namespace npt::nerf
