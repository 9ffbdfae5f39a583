// The sRGB transfer curve, NPT_HD: image files, and NeRF colours (networks predict the stored sRGB-encoded
// values) decoded to linear radiance in the renderer on either device.
#pragma once

#include <math.h>

#include "core/platform.h"

namespace npt {

NPT_HD NPT_INLINE float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : powf((v + 0.055f) / 1.055f, 2.4f);
}

NPT_HD NPT_INLINE float linear_to_srgb(float v) {
    return v <= 0.0031308f ? v * 12.92f : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace npt
