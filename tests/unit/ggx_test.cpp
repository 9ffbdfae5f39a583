#include "materials/ggx.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"

namespace npt::materials {
namespace {

double lambda64(double cos_t, double alpha) {
    double c2 = cos_t * cos_t;
    return 0.5 * (-1.0 + std::sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2));
}

// Independent float64 reference for the albedo table: E(mu) = integral over the half vector m of
// D(m) G2(wo, wi) |wo.m| / mu  (dwi = 4 |wo.m| dwm), midpoint rule in (theta_m, phi_m) -- not the
// visible-normal parameterisation the generator uses.
double albedo_reference(double mu, double alpha, int n_theta, int n_phi) {
    double so = std::sqrt(1.0 - mu * mu);
    double lo = lambda64(mu, alpha);
    double sum = 0.0;
    for (int i = 0; i < n_theta; ++i) {
        double tm = (i + 0.5) / n_theta * 0.5 * M_PI;
        double cm = std::cos(tm), sm = std::sin(tm);
        double t = cm * cm * (alpha * alpha - 1.0) + 1.0;
        double d = alpha * alpha / (M_PI * t * t);
        for (int j = 0; j < n_phi; ++j) {
            double pm = (j + 0.5) / n_phi * 2.0 * M_PI;
            double dot_om = so * sm * std::cos(pm) + mu * cm;
            if (dot_om <= 0.0) continue;
            double wiz = 2.0 * dot_om * cm - mu;
            if (wiz <= 0.0) continue;
            double g2 = 1.0 / (1.0 + lo + lambda64(wiz, alpha));
            sum += d * g2 * dot_om / mu * sm;  // sin(theta_m) is the solid-angle Jacobian
        }
    }
    return sum * (0.5 * M_PI / n_theta) * (2.0 * M_PI / n_phi);
}

TEST(Ggx, AlbedoTableMatchesIndependentQuadrature) {
    // Grid nodes: row j has r = j/31, column i has mu = (i/31)^2.
    struct Node {
        int j, i;
    };
    for (Node n : {Node{10, 31}, Node{10, 12}, Node{20, 20}, Node{31, 31}, Node{31, 8}, Node{25, 5}}) {
        double r = n.j / 31.0, x = n.i / 31.0;
        double alpha = r * r, mu = x * x;
        double fine = albedo_reference(mu, alpha, 2400, 400);
        double coarse = albedo_reference(mu, alpha, 1200, 200);
        // Tolerance: the quadrature's own error (estimated by halving the step) plus the table's float
        // rounding and the generator's quadrature error (< 1e-5 at 384^2 points on a smooth integrand).
        double tol = 4.0 * std::fabs(fine - coarse) + 2e-5;
        EXPECT_NEAR(ggx_albedo_entry(n.j, n.i), fine, tol) << "r " << r << " mu " << mu;
        EXPECT_NEAR(ggx_albedo(float(alpha), float(mu)), fine, tol);  // lookup hits the node exactly
    }
    // A wrong table (e.g. separable Smith G instead of height-correlated) differs by > 1e-2 at r = 1, mu =
    // 0.25.
}

TEST(Ggx, AlbedoAverageIsCosineWeightedMeanOfTheLookup) {
    for (float r : {0.2f, 0.45f, 0.7f, 1.0f}) {
        float alpha = r * r;
        double acc = 0.0;
        const int n = 20000;  // midpoint rule of a piecewise-smooth function: error < 1e-6
        for (int i = 0; i < n; ++i) {
            float mu = (i + 0.5f) / n;
            acc += 2.0 * ggx_albedo(alpha, mu) * mu / n;
        }
        // Rows are exact; between rows both are linear in the row weight. 2e-5: float table rounding.
        EXPECT_NEAR(ggx_albedo_average(alpha), acc, 2e-5) << "r " << r;
    }
}

TEST(Ggx, VisibleNormalPdfIntegratesToOne) {
    Pcg32 rng(5, 1);
    for (float alpha : {0.3f, 1.0f}) {
        for (float cz : {0.9f, 0.3f, -0.5f}) {
            Vec3 w(std::sqrt(1 - cz * cz), 0.0f, cz);
            Vec3 wv = cz > 0 ? w : -w;  // facets are visible from w, or from -w for w inside
            const int n = 200000;
            double sum = 0, sum2 = 0;
            for (int i = 0; i < n; ++i) {
                Vec3 m = sample_cosine_hemisphere(rng.next_2d());
                double v = (dot(m, wv) > 0 && m.z > 0)
                               ? ggx_pdf_visible(alpha, w, m) / cosine_hemisphere_pdf(m.z)
                               : 0.0;
                sum += v;
                sum2 += v * v;
            }
            double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
            EXPECT_NEAR(mean, 1.0, 4.0 * se) << "alpha " << alpha << " cz " << cz;  // 4 standard errors, 2e5
        }
    }
}

TEST(Ggx, VisibleNormalSamplesFaceTheViewer) {
    Pcg32 rng(6, 2);
    for (float cz : {0.9f, 0.1f, -0.6f}) {
        Vec3 w(std::sqrt(1 - cz * cz), 0.0f, cz);
        for (int i = 0; i < 10000; ++i) {
            Vec3 m = ggx_sample_visible(0.5f, w, rng.next_2d());
            ASSERT_GE(m.z, 0.0f);
            ASSERT_GT(dot(m, cz > 0 ? w : -w), -1e-5f);
        }
    }
}

TEST(Ggx, ProjectedAreaOfNormalsIsOne) {
    // integral D(m) cos(theta_m) dm = 1 (the microsurface projects onto the macro surface).
    for (float alpha : {0.1f, 0.5f, 1.0f}) {
        const int n = 200000;  // midpoint rule in cos^2 theta, where D is smooth: error << 1e-4
        double acc = 0.0;
        for (int i = 0; i < n; ++i) {
            double c2 = (i + 0.5) / n, c = std::sqrt(c2);
            Vec3 m(float(std::sqrt(1 - c2)), 0.0f, float(c));
            acc += ggx_d(alpha, m) * c * (2.0 * M_PI) * (0.5 / c) / n;  // dOmega = 2 pi dc, dc = dc2 / (2c)
        }
        EXPECT_NEAR(acc, 1.0, 1e-4) << "alpha " << alpha;
    }
}

}  // namespace
}  // namespace npt::materials
