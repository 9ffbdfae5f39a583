// Volume-rendering a ray from its samples (emission-absorption, as NeRF): weight_i = T_i (1 - exp(-sigma_i
// dt_i)), colour = sum weight_i c_i + T_end * background, with the transmittance kept in log space and the ray
// stopped once T < min_transmittance. The backward pass gives the exact gradient of that colour with respect
// to every sigma_i and c_i (samples past the stop get zero). NPT_HD, shared by training, rendering and GPU.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct CompositeResult {
    Rgb color;            // including T_end * background
    float transmittance;  // T_end
    int used = 0;         // samples composited before the stop; later ones have no effect
};

NPT_HD inline CompositeResult composite_forward(const float* sigma, const Rgb* rgb, const float* dt, int n,
                                         float min_transmittance, Rgb background);

// d_color: dLoss/d(result.color). Writes d_sigma[i] and d_rgb[i] for i < n (zero for i >= fwd.used).
NPT_HD inline void composite_backward(const float* sigma, const Rgb* rgb, const float* dt, int n,
                               const CompositeResult& fwd, Rgb background, Rgb d_color, float* d_sigma,
                               Rgb* d_rgb);

}  // namespace npt::nerf

