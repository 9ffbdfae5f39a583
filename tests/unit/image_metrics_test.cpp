// PSNR and SSIM: exact values where the maths gives them (identical images, dyadic errors), and SSIM against
// a direct double-precision implementation written here from the paper's definition (full 2D window, two-pass
// centred moments), so that the separable implementation is checked by a different route.
#include "core/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "test_support.h"

namespace npt {
namespace {

// A smooth gradient plus noise: local means, variances and covariances all vary over the image.
Image test_image(int w, int h, int channels, uint32_t seed, float scale = 0.8f) {
    Image img(w, h, channels);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> noise(0.0f, 0.3f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < channels; ++c) {
                const float smooth = 0.5f + 0.4f * std::sin(0.3f * float(x + 2 * c) + 0.2f * float(y));
                img.at(x, y)[c] = scale * (0.7f * smooth + noise(rng));
            }
    return img;
}

Image constant_image(int w, int h, float v, int channels = 3) {
    Image img(w, h, channels);
    std::fill(img.pixels.begin(), img.pixels.end(), v);
    return img;
}

// Wang et al. 2004, eq. 13, straight from the definition: for every valid window centre, the 2D Gaussian
// weights (sigma 1.5, 11x11, normalised), weighted means, then weighted centred second moments.
double reference_ssim(const Image& a, const Image& b) {
    constexpr int r = 5;
    double w[11][11];
    double wsum = 0;
    for (int i = 0; i < 11; ++i)
        for (int j = 0; j < 11; ++j) {
            w[i][j] = std::exp(-double((i - r) * (i - r) + (j - r) * (j - r)) / (2 * 1.5 * 1.5));
            wsum += w[i][j];
        }
    const double c1 = 0.0001, c2 = 0.0009;
    double total = 0;
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        int count = 0;
        for (int y = r; y < a.height - r; ++y)
            for (int x = r; x < a.width - r; ++x) {
                double mx = 0, my = 0;
                for (int i = 0; i < 11; ++i)
                    for (int j = 0; j < 11; ++j) {
                        mx += w[i][j] / wsum * a.at(x + j - r, y + i - r)[c];
                        my += w[i][j] / wsum * b.at(x + j - r, y + i - r)[c];
                    }
                double vx = 0, vy = 0, cxy = 0;
                for (int i = 0; i < 11; ++i)
                    for (int j = 0; j < 11; ++j) {
                        const double dx = a.at(x + j - r, y + i - r)[c] - mx;
                        const double dy = b.at(x + j - r, y + i - r)[c] - my;
                        vx += w[i][j] / wsum * dx * dx;
                        vy += w[i][j] / wsum * dy * dy;
                        cxy += w[i][j] / wsum * dx * dy;
                    }
                sum += (2 * mx * my + c1) * (2 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
                ++count;
            }
        total += sum / count;
    }
    return total / 3;
}

// Both implementations work in double on values in [0, 1]: sums of 121 terms differ by a few ulps, and the
// raw-moment form (E[x^2] - E[x]^2) loses at most ~1e-16 / variance relative; 1e-9 is far above both.
constexpr double k_tol = 1e-9;

TEST(ImageMetrics, IdenticalImages) {
    const Image a = test_image(32, 24, 3, 1);
    EXPECT_EQ(mean_squared_error(a, a), 0.0);
    EXPECT_EQ(psnr(a, a), std::numeric_limits<double>::infinity());
    EXPECT_NEAR(ssim(a, a), 1.0, 1e-12);
    // A constant image has zero variance everywhere: the C2 term alone keeps SSIM defined (and 1).
    const Image flat = constant_image(16, 16, 0.25f);
    EXPECT_NEAR(ssim(flat, flat), 1.0, 1e-12);
}

TEST(ImageMetrics, PsnrOfKnownMse) {
    // Dyadic values are exact in float, so the MSE is exact and PSNR only has log10's rounding.
    const Image a = constant_image(8, 6, 0.5f), b = constant_image(8, 6, 0.625f);
    EXPECT_EQ(mean_squared_error(a, b), 1.0 / 64.0);
    EXPECT_NEAR(psnr(a, b), 10.0 * std::log10(64.0), 1e-12);
    // Half the pixels differ by 0.25 in the green channel only: MSE = 0.0625 / 2 / 3 = 1/96.
    Image c = a;
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; x += 2) c.at(x, y)[1] += 0.25f;
    EXPECT_EQ(mean_squared_error(a, c), 1.0 / 96.0);
    EXPECT_NEAR(psnr(a, c), 10.0 * std::log10(96.0), 1e-12);
}

TEST(ImageMetrics, AlphaIsIgnored) {
    Image a = test_image(20, 20, 4, 2), b = test_image(20, 20, 4, 3);
    const double p = psnr(a, b), s = ssim(a, b);
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 20; ++x) b.at(x, y)[3] = 1.0f - a.at(x, y)[3];
    EXPECT_EQ(psnr(a, b), p);
    EXPECT_EQ(ssim(a, b), s);
}

TEST(ImageMetrics, SsimOfConstantOffsetMatchesReference) {
    // b = a + 0.1: the contrast-structure term is exactly 1, only the luminance term lowers SSIM.
    const Image a = test_image(37, 29, 3, 4);
    Image b = a;
    for (float& v : b.pixels) v += 0.1f;
    const double s = ssim(a, b), ref = reference_ssim(a, b);
    EXPECT_NEAR(s, ref, k_tol);
    EXPECT_LT(s, 1.0);
    EXPECT_GT(s, 0.9);  // luminance term at means ~0.5: 1 - 0.01 / (2 * 0.25 + 0.01) ~ 0.98
}

TEST(ImageMetrics, SsimOfUnrelatedImagesMatchesReference) {
    const Image a = test_image(23, 31, 3, 5), b = test_image(23, 31, 3, 6, 0.6f);
    EXPECT_NEAR(ssim(a, b), reference_ssim(a, b), k_tol);
    // The smallest image with a valid region: exactly one window.
    const Image c = test_image(11, 11, 3, 7), d = test_image(11, 11, 3, 8);
    EXPECT_NEAR(ssim(c, d), reference_ssim(c, d), k_tol);
}

TEST(ImageMetrics, Symmetric) {
    const Image a = test_image(30, 20, 3, 9), b = test_image(30, 20, 3, 10);
    EXPECT_EQ(psnr(a, b), psnr(b, a));
    EXPECT_EQ(ssim(a, b), ssim(b, a));
}

TEST(ImageMetrics, BadInputs) {
    const Image a(16, 16), b(16, 15), gray(16, 16, 1), small(10, 16);
    test::expect_error_message([&] { psnr(a, b); }, {"PSNR", "16x16 vs 16x15"});
    test::expect_error_message([&] { ssim(a, b); }, {"SSIM", "16x16 vs 16x15"});
    test::expect_error_message([&] { mean_squared_error(a, b); }, {"sizes differ"});
    test::expect_error_message([&] { psnr(a, gray); }, {"RGB"});
    test::expect_error_message([&] { ssim(small, small); }, {"SSIM", "10x16", "11x11"});
}

}  // namespace
}  // namespace npt
