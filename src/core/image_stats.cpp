#include "core/image_stats.h"

#include <cmath>

#include "core/error.h"

namespace npt {

namespace {

void check_same_size(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height || a.channels < 3 || b.channels < 3)
        throw Error("image comparison: sizes differ (" + std::to_string(a.width) + "x" +
                    std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                    std::to_string(b.height) + ")");
}

}  // namespace

ImageComparison compare_images(const Image& test, const Image& ref) {
    check_same_size(test, ref);
    ImageComparison c;
    const size_t n = size_t(test.width) * size_t(test.height);
    double se = 0;
    for (int y = 0; y < test.height; ++y)
        for (int x = 0; x < test.width; ++x)
            for (int k = 0; k < 3; ++k) {
                double t = test.at(x, y)[k], r = ref.at(x, y)[k];
                c.mean_test[size_t(k)] += t;
                c.mean_ref[size_t(k)] += r;
                se += (t - r) * (t - r) / (r * r + 0.01);
            }
    for (size_t k = 0; k < 3; ++k) {
        c.mean_test[k] /= double(n);
        c.mean_ref[k] /= double(n);
        c.mean_rel_err[k] = (c.mean_test[k] - c.mean_ref[k]) / c.mean_ref[k];
    }
    c.rel_mse = se / double(3 * n);
    return c;
}

NoiseEstimate estimate_noise(const Image& a, const Image& b, const Image& ref) {
    check_same_size(a, ref);
    check_same_size(b, ref);
    NoiseEstimate e;
    const size_t n = size_t(a.width) * size_t(a.height);
    double sum_d = 0, sum_d2 = 0, sum_exp = 0;
    std::array<double, 3> var_sum{};
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int k = 0; k < 3; ++k) {
                double va = a.at(x, y)[k], vb = b.at(x, y)[k], r = ref.at(x, y)[k];
                double w = 1.0 / (r * r + 0.01);
                double mean = 0.5 * (va + vb);
                double var = 0.25 * (va - vb) * (va - vb);  // unbiased variance of the mean of two samples
                double d = (mean - r) * (mean - r) * w - var * w;
                sum_d += d;
                sum_d2 += d * d;
                sum_exp += var * w;
                var_sum[size_t(k)] += var;
            }
    double m = double(3 * n);
    e.rel_mse_expected = sum_exp / m;
    e.rel_mse_excess = sum_d / m;
    e.rel_mse_excess_stderr = std::sqrt(std::max(0.0, sum_d2 / m - e.rel_mse_excess * e.rel_mse_excess) / m);
    for (size_t k = 0; k < 3; ++k) e.mean_stderr[k] = std::sqrt(var_sum[k]) / double(n);
    return e;
}

Image average(const Image& a, const Image& b) {
    check_same_size(a, b);
    Image r(a.width, a.height, a.channels);
    for (size_t i = 0; i < r.pixels.size(); ++i) r.pixels[i] = 0.5f * (a.pixels[i] + b.pixels[i]);
    return r;
}

}  // namespace npt
