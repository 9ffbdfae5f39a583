// The depth-spread loss of NeRF training (loss.depth_spread), shared by the CPU and GPU trainers. A ray's
// weights spread in depth about its surface; the relight stage's fields are read where a ray's scattering
// events fall, so each point of that shell is fitted to what the training rays through it see, and a
// thick shell blurs the fitted albedo by its thickness times the angle between the views (issue 24,
// docs/benchmarks.md "the density shell"). The loss is the variance of the ray's termination depth,
//   V = sum_i w_i (t_i - m)^2 / A,  m = sum_i w_i t_i / A,  A = sum_i w_i = 1 - T_end,
// in units of the pixel's footprint at depth m (footprint = distance * inv_focal): v = V / footprint^2, and
//   loss = weight * v / (1 + v / scale^2),
// which lets go (its gradient falls to zero) of spreads much larger than `scale` pixels: a young model's
// fog, depth edges within the pixel, semi-transparent parts. Without that a weight that thins a surface's
// shell empties the whole scene early in training (measured: 12 dB at step 500 against 27.6 dB).
// Skipped where A < k_min_smoothness_alpha (a silhouette: no surface on the ray), as the smoothness loss is.
// The footprint is held fixed in the gradient (it moves with m, whose own gradient through V is zero).
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/composite.h"
#include "nerf/surface_smoothness.h"

namespace npt::nerf {

struct DepthSpreadTerm {
    float loss = 0.0f;
    float d_variance = 0.0f;  // dLoss / dV
    Vec3 mean{0.0f, 0.0f, 0.0f};
    float variance = 0.0f;
    bool active = false;
};

// `origin`: the camera centre, `dir`: the unit ray direction, in the space of `pos`; `inv_focal`: 1 / focal
// length in pixels.
NPT_HD inline DepthSpreadTerm depth_spread_term(const float* sigma, const Vec3* pos, const float* dt,
                                                int used, const SurfacePoint& s, Vec3 origin, Vec3 dir,
                                                float inv_focal, float weight, float scale) {
    DepthSpreadTerm t;
    if (!(s.alpha >= k_min_smoothness_alpha) || used <= 0) return t;
    t.mean = s.point();
    const float footprint = length(t.mean - origin) * inv_focal;
    if (!(footprint > 0.0f)) return t;
    float tau = 0.0f, sum = 0.0f;
    for (int i = 0; i < used; ++i) {
        const float depth = sigma[i] * dt[i];
        const float u = dot(pos[i] - t.mean, dir);
        sum += u * u * (expf(-tau) * composite_alpha(depth));
        tau += depth;
    }
    t.variance = sum / s.alpha;
    const float inv_area = 1.0f / (footprint * footprint);
    const float v = t.variance * inv_area, r = 1.0f / (1.0f + v / (scale * scale));
    t.loss = weight * v * r;
    t.d_variance = weight * r * r * inv_area;  // d/dv of v / (1 + v / c^2) is 1 / (1 + v / c^2)^2
    t.active = isfinite(t.loss);
    return t;
}

// Adds d_variance * dV/d sigma_i to d_sigma[i] for i < used, with q_i = ((p_i - m) . dir)^2:
//   dV/d sigma_i = dt_i [(T_{i+1} q_i - S_i) / A - V T_end / A],  S_i = sum_{i<j<used} w_j q_j
// (surface_point_backward_add's derivative with the scalar q_i as the value; m held fixed is exact, since
// dV/dm = -2 sum_i w_i (t_i - m) / A = 0).
NPT_HD inline void depth_spread_backward_add(const float* sigma, const Vec3* pos, const float* dt, int used,
                                             const SurfacePoint& s, Vec3 dir, const DepthSpreadTerm& t,
                                             float scale, float* d_sigma) {
    if (!t.active || !(s.alpha > 0.0f)) return;
    float tau = s.optical_depth;
    const float t_end = expf(-tau);
    const float g = t.d_variance * scale / s.alpha;
    const float variance_t_end = t.variance * t_end;
    float behind = 0.0f;  // S_i
    float t_after = t_end;
    for (int i = used - 1; i >= 0; --i) {
        const float depth = sigma[i] * dt[i];
        tau = fmaxf(tau - depth, 0.0f);
        const float t_before = expf(-tau);
        const float u = dot(pos[i] - t.mean, dir);
        const float q = u * u;
        d_sigma[i] += dt[i] * g * (q * t_after - behind - variance_t_end);
        behind += q * (t_before * composite_alpha(depth));
        t_after = t_before;
    }
}

}  // namespace npt::nerf
