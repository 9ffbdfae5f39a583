#include "materials/fresnel.h"

#include <gtest/gtest.h>

#include <cmath>

namespace npt::materials {
namespace {

// Float64 reference from Snell's law written with angles (a different route than the code's cosines).
double fresnel_reference(double cos_i, double n_i, double n_t) {
    double theta_i = std::acos(cos_i);
    double sin_t = n_i / n_t * std::sin(theta_i);
    if (sin_t >= 1.0) return 1.0;
    double theta_t = std::asin(sin_t);
    if (theta_i == 0.0) return std::pow((n_t - n_i) / (n_t + n_i), 2.0);
    double rs = std::sin(theta_i - theta_t) / std::sin(theta_i + theta_t);
    double rp = std::tan(theta_i - theta_t) / std::tan(theta_i + theta_t);
    return 0.5 * (rs * rs + rp * rp);
}

TEST(Fresnel, DielectricMatchesFloat64ReferenceBothSides) {
    for (double eta : {1.33, 1.5, 2.4}) {
        for (double c : {1.0, 0.9, 0.7, 0.5, 0.3, 0.1, 0.02}) {
            // Outside (cos > 0): light goes from n=1 into eta. Inside (cos < 0): from eta into 1, with TIR.
            double out = fresnel_reference(c, 1.0, eta);
            double in = fresnel_reference(c, eta, 1.0);
            // Float32 evaluation of a smooth formula: a few ulps of values <= 1, 2e-6 absolute.
            EXPECT_NEAR(fresnel_dielectric(float(c), float(eta)), out, 2e-6) << "eta " << eta << " cos " << c;
            EXPECT_NEAR(fresnel_dielectric(float(-c), float(eta)), in, 2e-6)
                << "inside, eta " << eta << " cos " << c;
        }
    }
    // Beyond the critical angle (sin > 1/1.5, cos < 0.745) from inside everything reflects.
    EXPECT_EQ(fresnel_dielectric(-0.5f, 1.5f), 1.0f);
    EXPECT_LT(fresnel_dielectric(-0.8f, 1.5f), 1.0f);
    EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-7);
}

TEST(Fresnel, RefractObeysSnellAndReportsTotalInternalReflection) {
    Vec3 n(0, 0, 1);
    float c = 0.6f, s = 0.8f;
    Vec3 wi(s, 0, c);
    Vec3 wt;
    float etap = 0;
    ASSERT_TRUE(refract(wi, n, 1.5f, &etap, &wt));
    EXPECT_FLOAT_EQ(etap, 1.5f);
    EXPECT_NEAR(length(wt), 1.0f, 1e-6f);
    EXPECT_NEAR(-wt.x, s / 1.5f, 1e-6f);  // tangential part flips side and shrinks by 1/eta
    EXPECT_LT(wt.z, 0.0f);
    // From inside at sin 0.8 > 1/1.5: total internal reflection.
    EXPECT_FALSE(refract(Vec3(s, 0, -c), n, 1.5f, &etap, &wt));
    ASSERT_TRUE(refract(Vec3(0.5f, 0, -std::sqrt(0.75f)), n, 1.5f, &etap, &wt));
    EXPECT_FLOAT_EQ(etap, 1.0f / 1.5f);
    EXPECT_NEAR(-wt.x, 0.75f, 1e-6f);
}

TEST(Fresnel, SchlickAverageMatchesQuadrature) {
    Rgb f0(0.04f, 0.5f, 0.9f);
    double acc[3] = {0, 0, 0};
    const int n = 100000;  // midpoint rule of a degree-6 polynomial: error ~1e-10
    for (int i = 0; i < n; ++i) {
        float mu = (i + 0.5f) / n;
        Rgb f = fresnel_schlick(f0, mu);
        for (int c = 0; c < 3; ++c) acc[c] += 2.0 * f[c] * mu / n;
    }
    Rgb avg = fresnel_schlick_average(f0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(avg[c], acc[c], 1e-5);  // float accumulation of the integrand
}

}  // namespace
}  // namespace npt::materials
