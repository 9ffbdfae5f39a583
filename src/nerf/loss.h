// The photometric loss of NeRF training, shared by the CPU and GPU trainers: instant-ngp's Huber loss per
// colour channel (alpha = delta), and its derivative with respect to the prediction.
#pragma once

#include <math.h>

#include "core/platform.h"

namespace npt::nerf {

NPT_HD NPT_INLINE float huber_loss(float diff, float delta, float* grad) {
    const float a = fabsf(diff);
    if (a < delta) {
        *grad = diff / delta;
        return 0.5f * diff * diff / delta;
    }
    *grad = diff > 0 ? 1.0f : -1.0f;
    return a - 0.5f * delta;
}

}  // namespace npt::nerf
