#include "core/image_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"

namespace npt {

namespace {

constexpr double k_ssim_sigma = 1.5;
constexpr double k_ssim_c1 = 0.01 * 0.01;  // (K1 * data range)^2
constexpr double k_ssim_c2 = 0.03 * 0.03;  // (K2 * data range)^2

void check_pair(const Image& a, const Image& b, const char* what) {
    const auto size = [](const Image& i) { return std::to_string(i.width) + "x" + std::to_string(i.height); };
    if (a.width != b.width || a.height != b.height)
        throw Error(std::string(what) + ": image sizes differ (" + size(a) + " vs " + size(b) + ")");
    if (a.channels < 3 || b.channels < 3) throw Error(std::string(what) + ": images need RGB channels");
}

std::array<double, k_ssim_window> gaussian_window() {
    std::array<double, k_ssim_window> w{};
    double sum = 0;
    for (int i = 0; i < k_ssim_window; ++i) {
        const double d = double(i - k_ssim_window / 2) / k_ssim_sigma;
        w[size_t(i)] = std::exp(-0.5 * d * d);
        sum += w[size_t(i)];
    }
    for (double& v : w) v /= sum;
    return w;
}

// Mean SSIM of one channel over the valid region. The Gaussian is separable: filter the five local moments
// along rows, then along columns, so a window costs 22 instead of 121 multiply-adds.
double ssim_channel(const Image& a, const Image& b, int c, const std::array<double, k_ssim_window>& w) {
    const int width = a.width, height = a.height;
    const int vw = width - k_ssim_window + 1, vh = height - k_ssim_window + 1;
    constexpr int k_moments = 5;  // x, y, x^2, y^2, xy
    std::vector<double> rows(size_t(k_moments) * size_t(height) * size_t(vw), 0.0);
    const auto row_at = [&](int m, int y, int x) -> double& {
        return rows[(size_t(m) * size_t(height) + size_t(y)) * size_t(vw) + size_t(x)];
    };
    std::vector<double> line(size_t(k_moments) * size_t(width));
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const double p = a.at(x, y)[c], q = b.at(x, y)[c];
            const double v[k_moments] = {p, q, p * p, q * q, p * q};
            for (int m = 0; m < k_moments; ++m) line[size_t(m) * size_t(width) + size_t(x)] = v[m];
        }
        for (int m = 0; m < k_moments; ++m) {
            const double* src = &line[size_t(m) * size_t(width)];
            for (int x = 0; x < vw; ++x) {
                double s = 0;
                for (int k = 0; k < k_ssim_window; ++k) s += w[size_t(k)] * src[x + k];
                row_at(m, y, x) = s;
            }
        }
    }
    double sum = 0;
    for (int y = 0; y < vh; ++y)
        for (int x = 0; x < vw; ++x) {
            double mom[k_moments] = {};
            for (int m = 0; m < k_moments; ++m)
                for (int k = 0; k < k_ssim_window; ++k) mom[m] += w[size_t(k)] * row_at(m, y + k, x);
            const double mx = mom[0], my = mom[1];
            const double vx = std::max(0.0, mom[2] - mx * mx), vy = std::max(0.0, mom[3] - my * my);
            const double cxy = mom[4] - mx * my;
            sum += (2 * mx * my + k_ssim_c1) * (2 * cxy + k_ssim_c2) /
                   ((mx * mx + my * my + k_ssim_c1) * (vx + vy + k_ssim_c2));
        }
    return sum / (double(vw) * double(vh));
}

}  // namespace

double mean_squared_error(const Image& a, const Image& b) {
    check_pair(a, b, "mean squared error");
    double se = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int k = 0; k < 3; ++k) {
                const double d = double(a.at(x, y)[k]) - double(b.at(x, y)[k]);
                se += d * d;
            }
    const double n = 3.0 * double(a.width) * double(a.height);
    return n > 0 ? se / n : 0.0;
}

double psnr(const Image& a, const Image& b) {
    check_pair(a, b, "PSNR");
    const double mse = mean_squared_error(a, b);
    if (mse == 0) return std::numeric_limits<double>::infinity();
    return -10.0 * std::log10(mse);
}

double ssim(const Image& a, const Image& b) {
    check_pair(a, b, "SSIM");
    if (a.width < k_ssim_window || a.height < k_ssim_window)
        throw Error("SSIM: image is " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                    ", needs at least " + std::to_string(k_ssim_window) + "x" +
                    std::to_string(k_ssim_window));
    const auto w = gaussian_window();
    double sum = 0;
    for (int c = 0; c < 3; ++c) sum += ssim_channel(a, b, c, w);
    return sum / 3.0;
}

}  // namespace npt
