// SH degree-4 encoding (nerf/sh_encoding.h) against a float64 reference built from the textbook definition
// (associated Legendre functions with Condon-Shortley phase, real SH from sin/cos of m phi), and
// orthonormality of the 16 basis functions by a quadrature that is exact for them.
#include "nerf/sh_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace npt::nerf {
namespace {

constexpr double k_u = 1.0 / (1 << 24);  // unit roundoff of float
constexpr double k_pi_d = 3.14159265358979323846;

// P_l^m(x), m >= 0, with the (-1)^m Condon-Shortley phase (the usual recurrence in m, then in l).
double legendre_p(int l, int m, double x) {
    double pmm = 1.0;
    const double s = std::sqrt((1.0 - x) * (1.0 + x));
    for (int i = 1; i <= m; ++i) pmm *= -(2.0 * i - 1.0) * s;
    if (l == m) return pmm;
    double pmm1 = x * (2.0 * m + 1.0) * pmm;
    for (int ll = m + 2; ll <= l; ++ll) {
        const double p = (x * (2.0 * ll - 1.0) * pmm1 - (ll + m - 1.0) * pmm) / (ll - m);
        pmm = pmm1;
        pmm1 = p;
    }
    return pmm1;
}

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

// Real SH: Y_l^m = sqrt2 K cos(m phi) P_l^m (m > 0), sqrt2 K sin(|m| phi) P_l^|m| (m < 0), K P_l^0 (m = 0).
double real_sh(int l, int m, double x, double y, double z) {
    const int am = std::abs(m);
    const double k = std::sqrt((2.0 * l + 1.0) / (4.0 * k_pi_d) * factorial(l - am) / factorial(l + am));
    const double phi = std::atan2(y, x);
    const double p = legendre_p(l, am, z);
    if (m == 0) return k * p;
    return std::sqrt(2.0) * k * p * (m > 0 ? std::cos(m * phi) : std::sin(am * phi));
}

TEST(ShEncoding, MatchesTextbookFormulas) {
    // Spot values that anchor the sign convention independently of the recurrence.
    float out[k_sh_deg4_dims];
    sh_encode_deg4(Vec3(0.0f, 1.0f, 0.0f), out);
    EXPECT_NEAR(out[0], 0.28209479, 1e-7);
    EXPECT_NEAR(out[1], -0.48860251, 1e-7);  // Y_1^{-1} = -0.48860251 y

    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    for (int n = 0; n < 500; ++n) {
        double x = g(rng), y = g(rng), z = g(rng);
        const double len = std::sqrt(x * x + y * y + z * z);
        x /= len, y /= len, z /= len;
        sh_encode_deg4(Vec3(float(x), float(y), float(z)), out);
        for (int l = 0; l <= 3; ++l)
            for (int m = -l; m <= l; ++m) {
                // Rounding the direction to float moves it by <= u per component; |grad Y| <= ~9 for l <= 3,
                // and the float polynomial adds <= ~10 u * 3: 64 u bounds both.
                EXPECT_NEAR(out[l * l + l + m], real_sh(l, m, x, y, z), 64.0 * k_u)
                    << "l " << l << " m " << m << " dir " << x << " " << y << " " << z;
            }
    }
}

TEST(ShEncoding, BasisIsOrthonormal) {
    // Gauss-Legendre in cos(theta) (n nodes, exact to degree 2n-1) times the trapezoid rule in phi (2n
    // points, exact for trigonometric degree < 2n). Y_i Y_j has degree <= 6 in both, so n = 6 makes the
    // quadrature exact and the only error is the float evaluation: |Y| <= 1, each value off by <= ~16 u, so
    // |integral error| <= 4 pi * 2 * 16 u ~ 2.4e-5.
    const int n = 6;
    std::vector<double> nodes(n), weights(n);
    for (int i = 0; i < n; ++i) {
        double x = std::cos(k_pi_d * (i + 0.75) / (n + 0.5));
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; ++k) {
                const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            const double dp = n * (x * p1 - p0) / (x * x - 1.0);
            const double dx = p1 / dp;
            x -= dx;
            if (std::fabs(dx) < 1e-16) {
                weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
                break;
            }
            weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
        }
        nodes[i] = x;
    }
    double wsum = 0.0;
    for (double w : weights) wsum += w;
    ASSERT_NEAR(wsum, 2.0, 1e-12);

    double gram[k_sh_deg4_dims][k_sh_deg4_dims] = {};
    const int nphi = 2 * n;
    float y[k_sh_deg4_dims];
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < nphi; ++j) {
            const double z = nodes[i], r = std::sqrt(1.0 - z * z), phi = 2.0 * k_pi_d * (j + 0.5) / nphi;
            sh_encode_deg4(Vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)), y);
            const double w = weights[i] * 2.0 * k_pi_d / nphi;
            for (int a = 0; a < k_sh_deg4_dims; ++a)
                for (int b = 0; b < k_sh_deg4_dims; ++b) gram[a][b] += w * double(y[a]) * y[b];
        }
    const double tol = 4.0 * k_pi_d * 2.0 * 16.0 * k_u;
    for (int a = 0; a < k_sh_deg4_dims; ++a)
        for (int b = 0; b < k_sh_deg4_dims; ++b)
            EXPECT_NEAR(gram[a][b], a == b ? 1.0 : 0.0, tol) << a << " " << b;
}

}  // namespace
}  // namespace npt::nerf
