// OpenCV lens distortion: undistort inverts distort over a phone's field of view for realistic coefficients
// (float, as ray generation runs it, and double), the Jacobian-based Newton steps converge where the lens is
// monotonic, and inputs far outside it give finite numbers instead of NaN.
#include "nerf/lens_distortion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace npt::nerf {
namespace {

// Coefficient sets a phone video gives: both signs of barrel/pincushion, small tangential terms, and the
// values COLMAP's OPENCV model estimated on a real phone clip (k1 0.03, k2 -0.05, tangential ~0).
std::vector<LensDistortion> phone_lenses() {
    return {{-0.1f, 0.02f, 1e-3f, -1e-3f},      {0.1f, -0.05f, -1e-3f, 2e-3f}, {0.03f, -0.05f, 0.0f, 0.0f},
            {0.0317f, -0.0498f, 4e-4f, -6e-4f}, {-0.05f, 0.0f, 0.0f, 0.0f},    {0.0f, 0.0f, 2e-3f, 1e-3f}};
}

// Normalised coordinates covering a 16:9 phone frame at a ~70 degree horizontal field of view (x up to
// tan(35 deg) ~ 0.7, y up to 0.4), corners included.
template <typename Fn>
void for_each_grid_point(Fn&& fn) {
    constexpr int n = 21;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) fn(-0.7 + 1.4 * i / (n - 1), -0.4 + 0.8 * j / (n - 1));
}

// Round trips in both directions. `tol` is a few rounding errors of T on coordinates of order 1 (Newton
// converges quadratically, so what is left after the stop is rounding, not truncation).
template <typename T>
void check_round_trips(T tol) {
    for (const LensDistortion& k : phone_lenses()) {
        double moved = 0;
        for_each_grid_point([&](double gx, double gy) {
            const T x = T(gx), y = T(gy);
            T xd, yd, ux, uy;
            distort(k, x, y, &xd, &yd);
            moved = std::fmax(moved, std::hypot(double(xd - x), double(yd - y)));
            undistort(k, xd, yd, &ux, &uy);
            EXPECT_NEAR(ux, x, tol) << "k1 " << k.k1 << " at (" << gx << ", " << gy << ")";
            EXPECT_NEAR(uy, y, tol) << "k1 " << k.k1 << " at (" << gx << ", " << gy << ")";
            // The direction ray generation uses: a distorted pixel back through the lens.
            undistort(k, x, y, &ux, &uy);
            distort(k, ux, uy, &xd, &yd);
            EXPECT_NEAR(xd, x, tol) << "k1 " << k.k1 << " at (" << gx << ", " << gy << ")";
            EXPECT_NEAR(yd, y, tol) << "k1 " << k.k1 << " at (" << gx << ", " << gy << ")";
        });
        // Not a vacuous test: at the corners every lens moves points by far more than the tolerance.
        EXPECT_GT(moved, 1e-3) << "k1 " << k.k1;
    }
}

TEST(LensDistortion, UndistortInvertsDistortFloat) { check_round_trips<float>(1e-6f); }

TEST(LensDistortion, UndistortInvertsDistortDouble) { check_round_trips<double>(1e-12); }

TEST(LensDistortion, DistortMatchesTheOpenCvFormula) {
    // Hand-evaluated at (0.3, -0.2): r2 = 0.13, radial = 1 + 0.1*0.13 - 0.05*0.0169 = 1.012155,
    // xd = 0.3*radial + 2*0.01*0.3*(-0.2) + 0.02*(0.13 + 0.18) = 0.3086465,
    // yd = -0.2*radial + 0.01*(0.13 + 0.08) + 2*0.02*0.3*(-0.2) = -0.202731.
    const LensDistortion k{0.1f, -0.05f, 0.01f, 0.02f};
    double xd, yd;
    distort(k, 0.3, -0.2, &xd, &yd);
    const double radial = 1 + double(k.k1) * 0.13 + double(k.k2) * 0.0169;
    EXPECT_NEAR(xd, 0.3 * radial + 2 * double(k.p1) * 0.3 * -0.2 + double(k.p2) * 0.31, 1e-15);
    EXPECT_NEAR(yd, -0.2 * radial + double(k.p1) * 0.21 + 2 * double(k.p2) * 0.3 * -0.2, 1e-15);
    EXPECT_NEAR(xd, 0.3086465, 1e-6);  // the numbers above, rounded: guards against a shared typo
    EXPECT_NEAR(yd, -0.2027310, 1e-6);
}

TEST(LensDistortion, IdentityIsExactAndDetected) {
    EXPECT_TRUE(LensDistortion{}.is_identity());
    EXPECT_FALSE((LensDistortion{0, 0, 0, 1e-9f}.is_identity()));
    float x, y;
    undistort(LensDistortion{}, 0.37f, -0.21f, &x, &y);
    EXPECT_EQ(x, 0.37f);
    EXPECT_EQ(y, -0.21f);
}

TEST(LensDistortion, FarOutsideTheLensStaysFinite) {
    // Strong barrel distortion folds back beyond r ~ 0.8; points there have no preimage, and Newton may meet
    // a singular Jacobian or run away. The result must still be a number.
    const LensDistortion k{-0.5f, 0.0f, 0.0f, 0.0f};
    for (float v : {0.5f, 0.8165f, 1.0f, 3.0f, 100.0f}) {
        float x, y;
        undistort(k, v, v, &x, &y);
        EXPECT_TRUE(std::isfinite(x) && std::isfinite(y)) << v;
    }
}

}  // namespace
}  // namespace npt::nerf
