// Real spherical-harmonics encoding of a view direction up to degree 4 (bands l = 0..3, 16 values), the
// basis tiny-cuda-nn's SphericalHarmonics encoding uses for instant-ngp's colour network.
// Ordering: out[l*l + l + m], m = -l..l; Condon-Shortley phase included (so Y_1^{-1} = -0.4886 y).
// Input is a unit vector taken as is: tiny-cuda-nn expects directions mapped to [0,1]^3 and undoes that with
// 2d - 1 first; we skip the round trip. No backward pass: the direction is an input, not a trained parameter.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

constexpr int k_sh_deg4_dims = 16;

NPT_HD NPT_INLINE void sh_encode_deg4(Vec3 d, float* out) {
    const float x = d.x, y = d.y, z = d.z;
    const float xy = x * y, xz = x * z, yz = y * z;
    const float x2 = x * x, y2 = y * y, z2 = z * z;
    // l = 0
    out[0] = 0.28209479177387814f;
    // l = 1
    out[1] = -0.48860251190291987f * y;
    out[2] = 0.48860251190291987f * z;
    out[3] = -0.48860251190291987f * x;
    // l = 2
    out[4] = 1.0925484305920792f * xy;
    out[5] = -1.0925484305920792f * yz;
    out[6] = 0.94617469575755997f * z2 - 0.31539156525251999f;
    out[7] = -1.0925484305920792f * xz;
    out[8] = 0.54627421529603959f * (x2 - y2);
    // l = 3
    out[9] = 0.59004358992664352f * y * (y2 - 3.0f * x2);
    out[10] = 2.8906114426405538f * xy * z;
    out[11] = 0.45704579946446572f * y * (1.0f - 5.0f * z2);
    out[12] = 0.3731763325901154f * z * (5.0f * z2 - 3.0f);
    out[13] = 0.45704579946446572f * x * (1.0f - 5.0f * z2);
    out[14] = 1.4453057213202769f * z * (x2 - y2);
    out[15] = 0.59004358992664352f * x * (3.0f * y2 - x2);
}

}  // namespace npt::nerf
