// Robust spawn points for secondary rays: move the origin off the surface by a few ulps along the geometric
// normal (Waechter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems
// 2019), so rays never re-hit their own triangle and need no scene-scale epsilon.
#pragma once

#include <cstring>

#include "core/vec.h"

namespace npt::render {

NPT_HD NPT_INLINE float int_bits_to_float(int32_t i) {
#if defined(__CUDA_ARCH__)
    return __int_as_float(i);
#else
    float f;
    std::memcpy(&f, &i, sizeof f);
    return f;
#endif
}
NPT_HD NPT_INLINE int32_t float_to_int_bits(float f) {
#if defined(__CUDA_ARCH__)
    return __float_as_int(f);
#else
    int32_t i;
    std::memcpy(&i, &f, sizeof i);
    return i;
#endif
}

// `n` is the unit geometric normal on the side the new ray leaves towards.
NPT_HD NPT_INLINE Vec3 offset_ray_origin(Vec3 p, Vec3 n) {
    constexpr float k_origin = 1.0f / 32.0f;
    constexpr float k_float_scale = 1.0f / 65536.0f;
    constexpr float k_int_scale = 256.0f;
    Vec3 r;
    for (int a = 0; a < 3; ++a) {
        int32_t of = int32_t(k_int_scale * n[a]);
        float pi = int_bits_to_float(float_to_int_bits(p[a]) + (p[a] < 0.0f ? -of : of));
        r[a] = fabsf(p[a]) < k_origin ? p[a] + k_float_scale * n[a] : pi;
    }
    return r;
}

}  // namespace npt::render
