// Volume-rendering a ray from its samples (emission-absorption, as NeRF): weight_i = T_i (1 - exp(-sigma_i
// dt_i)), colour = sum weight_i c_i + T_end * background, with the transmittance kept in log space and the
// ray stopped once T < min_transmittance. The backward pass gives the exact gradient of that colour with
// respect to every sigma_i and c_i (samples past the stop get zero). NPT_HD, shared by training, rendering
// and GPU.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct CompositeResult {
    Rgb color;            // including T_end * background
    float transmittance;  // T_end
    int used = 0;         // samples composited before the stop; later ones have no effect
};

// 1 - exp(-x) without the cancellation of the direct form when x is small (thin samples are the common case).
NPT_HD NPT_INLINE float composite_alpha(float optical_depth) { return -expm1f(-optical_depth); }

// The stop is tested before each sample, so the sample that takes T below min_transmittance is still
// composited and `used` counts it; the optical depth tau is summed and T = exp(-tau) taken from it, so T is
// never the product of many roundings.
NPT_HD inline CompositeResult composite_forward(const float* sigma, const Rgb* rgb, const float* dt, int n,
                                                float min_transmittance, Rgb background) {
    CompositeResult r;
    r.color = Rgb(0.0f);
    float tau = 0.0f;
    float t = 1.0f;
    int i = 0;
    for (; i < n && !(t < min_transmittance); ++i) {
        const float depth = sigma[i] * dt[i];
        r.color += rgb[i] * (t * composite_alpha(depth));
        tau += depth;
        t = expf(-tau);
    }
    r.used = i;
    r.transmittance = t;
    r.color += background * t;
    return r;
}

// d_color: dLoss/d(result.color). Writes d_sigma[i] and d_rgb[i] for i < n (zero for i >= fwd.used).
//
// d colour / d sigma_i = dt_i (T_{i+1} c_i - S_i) with S_i = sum_{i<j<used} w_j c_j + T_end bg, the light
// that reaches the eye from behind sample i. S_i is summed in a reverse pass rather than taken as the total
// colour minus the running prefix (instant-ngp): every term is non-negative for non-negative colours, so the
// reverse sum has a relative error of O(n eps) for every i, while the subtraction has an absolute error of
// O(n eps |colour|), which swamps S_i for the late samples of an opaque ray, where S_i is tiny. The forward's
// optical depths are kept in d_sigma (it is overwritten later in the same pass) so that the backward uses
// bit-for-bit the T_i of the forward without a second buffer.
NPT_HD inline void composite_backward(const float* sigma, const Rgb* rgb, const float* dt, int n,
                                      const CompositeResult& fwd, Rgb background, Rgb d_color, float* d_sigma,
                                      Rgb* d_rgb) {
    const int used = fwd.used < 0 ? 0 : (fwd.used > n ? n : fwd.used);
    float tau = 0.0f;
    for (int i = 0; i < used; ++i) {
        d_sigma[i] = tau;  // optical depth in front of sample i
        tau += sigma[i] * dt[i];
    }
    for (int i = used; i < n; ++i) {
        d_sigma[i] = 0.0f;
        d_rgb[i] = Rgb(0.0f);
    }
    Rgb behind = background * expf(-tau);  // S_i, starting from the last used sample
    float t_after = expf(-tau);            // T_{i+1}
    for (int i = used - 1; i >= 0; --i) {
        const float t_before = expf(-d_sigma[i]);
        const float w = t_before * composite_alpha(sigma[i] * dt[i]);
        d_rgb[i] = d_color * w;
        d_sigma[i] = dt[i] * dot(d_color, rgb[i] * t_after - behind);
        behind += rgb[i] * w;
        t_after = t_before;
    }
}

}  // namespace npt::nerf
