// The relight fit's smoothness prior between a query point and its partner a small random distance away: the
// squared differences of their albedo (3 channels), roughness and unit normal, from the intrinsic network's raw
// outputs (intrinsic_field.h). Each surface point's light estimate is noisy (K directions); without the prior
// the fine grid levels keep that noise as speckle in the albedo.
#pragma once

#include <algorithm>
#include <cmath>

#include "nerf/relight/intrinsic_field.h"

namespace npt::nerf {

// Returns the unweighted term for raw outputs a and b (k_intrinsic_outputs each) and ADDS `weight` times its
// gradient with respect to them to d_a and d_b.
inline double smoothness_term(const float* a, const float* b, float* d_a, float* d_b, float weight) {
    auto sigmoid_slope = [](float s) { return s * (1.0f - s); };  // of the sigmoid, from its value
    const IntrinsicSample sa = intrinsic_from_outputs(a), sb = intrinsic_from_outputs(b);
    double term = 0;
    for (int c = 0; c < 3; ++c) {
        const float diff = sa.albedo[c] - sb.albedo[c];
        term += double(diff) * diff;
        d_a[c] += 2.0f * weight * diff * sigmoid_slope(sa.albedo[c]);
        d_b[c] -= 2.0f * weight * diff * sigmoid_slope(sb.albedo[c]);
    }
    const float scale = 1.0f - k_min_roughness;
    const float dr = sa.roughness - sb.roughness;
    term += double(dr) * dr;
    d_a[3] += 2.0f * weight * dr * scale * sigmoid_slope((sa.roughness - k_min_roughness) / scale);
    d_b[3] -= 2.0f * weight * dr * scale * sigmoid_slope((sb.roughness - k_min_roughness) / scale);
    const Vec3 ra(a[4], a[5], a[6]), rb(b[4], b[5], b[6]);
    const float la = std::max(length(ra), 1e-6f), lb = std::max(length(rb), 1e-6f);
    const Vec3 na = ra / la, nb = rb / lb, dn = na - nb;
    term += dot(dn, dn);
    const Vec3 g = dn * (2.0f * weight);  // d/dna; -g for nb; then through the normalisation
    const Vec3 ga = (g - na * dot(na, g)) / la, gb = (nb * dot(nb, g) - g) / lb;
    d_a[4] += ga.x;
    d_a[5] += ga.y;
    d_a[6] += ga.z;
    d_b[4] += gb.x;
    d_b[5] += gb.y;
    d_b[6] += gb.z;
    return term;
}

}  // namespace npt::nerf
