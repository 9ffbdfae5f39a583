// Tests of the piecewise-constant 2D distribution: the sampled histogram follows the weights (chi-square),
// the density integrates to 1, and sample() reports the density that pdf() gives at the same point.
#include "core/distribution_2d.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/rng.h"

namespace npt {
namespace {

// Upper quantile of chi-square with k degrees of freedom at normal deviate z (Wilson-Hilferty approximation,
// accurate to a few percent for k > 10, which is far finer than the gap between a right and a wrong sampler).
double chi2_quantile(int k, double z) {
    double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}

// 8 x 5 weights with a zero row, zero cells and a wide dynamic range.
std::vector<float> test_weights(int nu, int nv) {
    std::vector<float> f(size_t(nu) * size_t(nv));
    for (int v = 0; v < nv; ++v)
        for (int u = 0; u < nu; ++u)
            f[size_t(v * nu + u)] = v == 2 ? 0.0f : float((u * 7 + v * 3) % 5) * (1 + v);
    f[size_t(4 * nu + 7)] = 40.0f;
    return f;
}

TEST(Distribution2D, HistogramMatchesWeightsChiSquare) {
    const int nu = 8, nv = 5;
    std::vector<float> f = test_weights(nu, nv);
    Distribution2D dist(f, nu, nv);
    auto view = dist.view();
    double total = 0;
    for (float w : f) total += w;

    const int n = 200000;
    std::vector<int> count(f.size(), 0);
    Pcg32 rng(1, 2);
    for (int i = 0; i < n; ++i) {
        float pdf;
        Vec2 p = view.sample(rng.next_2d(), &pdf);
        ASSERT_GE(p.x, 0.0f);
        ASSERT_LT(p.x, 1.0f);
        ASSERT_GE(p.y, 0.0f);
        ASSERT_LT(p.y, 1.0f);
        ++count[size_t(int(p.y * nv) * nu + int(p.x * nu))];
    }
    double chi2 = 0;
    int dof = -1;
    for (size_t c = 0; c < f.size(); ++c) {
        double expected = n * f[c] / total;
        if (f[c] == 0.0f) {
            EXPECT_EQ(count[c], 0) << "a zero-weight cell was sampled: " << c;
            continue;
        }
        chi2 += (count[c] - expected) * (count[c] - expected) / expected;
        ++dof;
    }
    // z = 4.75: a correct sampler fails this about once in a million runs.
    EXPECT_LT(chi2, chi2_quantile(dof, 4.75)) << "dof " << dof;
}

TEST(Distribution2D, PdfIntegratesToOneAndMatchesSample) {
    const int nu = 8, nv = 5;
    Distribution2D dist(test_weights(nu, nv), nu, nv);
    auto view = dist.view();
    // The pdf is constant per cell, so a midpoint sum on a 4x finer grid is exact up to float rounding.
    double integral = 0;
    const int m = 4;
    for (int v = 0; v < nv * m; ++v)
        for (int u = 0; u < nu * m; ++u)
            integral += view.pdf({(u + 0.5f) / (nu * m), (v + 0.5f) / (nv * m)}) / double(nu * m * nv * m);
    EXPECT_NEAR(integral, 1.0, 1e-5);

    Pcg32 rng(3, 4);
    for (int i = 0; i < 20000; ++i) {
        float pdf;
        Vec2 p = view.sample(rng.next_2d(), &pdf);
        ASSERT_GT(pdf, 0.0f);
        ASSERT_EQ(pdf, view.pdf(p)) << "at " << p.x << ", " << p.y;
    }
    // The extreme sample value must stay inside the unit square and in a cell with weight.
    float pdf;
    Vec2 p = view.sample({0.99999994f, 0.99999994f}, &pdf);
    EXPECT_LT(p.x, 1.0f);
    EXPECT_LT(p.y, 1.0f);
    EXPECT_GT(pdf, 0.0f);
    EXPECT_EQ(pdf, view.pdf(p));
}

TEST(Distribution2D, RejectsBadInputAndHandlesAllZero) {
    EXPECT_THROW(Distribution2D({1.0f, 2.0f, 3.0f}, 2, 2), Error);
    EXPECT_THROW(Distribution2D({1.0f, -1.0f}, 2, 1), Error);
    EXPECT_THROW(Distribution2D({1.0f, std::nanf("")}, 2, 1), Error);
    EXPECT_THROW(Distribution2D({}, 0, 0), Error);
    Distribution2D zero({0.0f, 0.0f, 0.0f, 0.0f}, 2, 2);
    auto view = zero.view();
    EXPECT_FALSE(view.valid());
    float pdf = 1.0f;
    view.sample({0.5f, 0.5f}, &pdf);
    EXPECT_EQ(pdf, 0.0f);
    EXPECT_EQ(view.pdf({0.5f, 0.5f}), 0.0f);
}

}  // namespace
}  // namespace npt
