// OpenCV's radial/tangential lens distortion (k1, k2, p1, p2; COLMAP's OPENCV model, instant-ngp's
// transforms.json keys) on normalised image coordinates (x/z, y/z with y down), and its Newton inverse.
// NPT_HD and allocation-free so a GPU ray generator can share it; templated so tests can run it in double.
#pragma once

#include <math.h>

#include "core/platform.h"

namespace npt::nerf {

struct LensDistortion {
    float k1 = 0, k2 = 0, p1 = 0, p2 = 0;

    // Exact zeros only: callers skip the Newton iteration and must then match the pinhole result bit for bit.
    NPT_HD NPT_INLINE bool is_identity() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0; }
};

// Undistorted (x, y) -> distorted (xd, yd):
//   r2 = x^2 + y^2, radial = 1 + k1 r2 + k2 r2^2,
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2),  yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y.
template <typename T>
NPT_HD NPT_INLINE void distort(const LensDistortion& k, T x, T y, T* xd, T* yd) {
    const T k1 = T(k.k1), k2 = T(k.k2), p1 = T(k.p1), p2 = T(k.p2);
    const T r2 = x * x + y * y;
    const T radial = T(1) + r2 * (k1 + k2 * r2);
    *xd = x * radial + T(2) * p1 * x * y + p2 * (r2 + T(2) * x * x);
    *yd = y * radial + p1 * (r2 + T(2) * y * y) + T(2) * p2 * x * y;
}

// Distorted (xd, yd) -> undistorted (x, y) by Newton's method on distort(x, y) - (xd, yd) with the analytic
// 2x2 Jacobian, started at (xd, yd) (instant-ngp's iterative_camera_undistortion uses a numeric one and 100
// steps; the analytic one converges quadratically, so 10 are plenty for phone-like coefficients). Where the
// Jacobian is singular or a step leaves the finite numbers (far outside the lens's monotonic range) the last
// finite estimate is kept: a wrong ray for a pixel the lens never produced, never a NaN.
template <typename T>
NPT_HD NPT_INLINE void undistort(const LensDistortion& k, T xd, T yd, T* x_out, T* y_out) {
    constexpr int k_max_iterations = 10;
    // Squared step length below which we stop: about float rounding on coordinates of order 1.
    constexpr T k_tiny_step2 = T(1e-14);
    const T k1 = T(k.k1), k2 = T(k.k2), p1 = T(k.p1), p2 = T(k.p2);
    T x = xd, y = yd;
    for (int i = 0; i < k_max_iterations; ++i) {
        T fx, fy;
        distort(k, x, y, &fx, &fy);
        fx -= xd;
        fy -= yd;
        const T r2 = x * x + y * y;
        const T radial = T(1) + r2 * (k1 + k2 * r2);
        const T dradial = T(2) * (k1 + T(2) * k2 * r2);  // d radial / d(x or y), divided by x or y
        const T j00 = radial + dradial * x * x + T(2) * p1 * y + T(6) * p2 * x;
        const T j01 = dradial * x * y + T(2) * p1 * x + T(2) * p2 * y;  // the Jacobian is symmetric
        const T j11 = radial + dradial * y * y + T(6) * p1 * y + T(2) * p2 * x;
        const T det = j00 * j11 - j01 * j01;
        if (!(fabs(det) > T(1e-12))) break;  // also catches a NaN det
        const T sx = (j11 * fx - j01 * fy) / det, sy = (j00 * fy - j01 * fx) / det;
        const T nx = x - sx, ny = y - sy;
        if (!isfinite(nx) || !isfinite(ny)) break;
        x = nx;
        y = ny;
        if (sx * sx + sy * sy < k_tiny_step2) break;
    }
    *x_out = x;
    *y_out = y;
}

}  // namespace npt::nerf
