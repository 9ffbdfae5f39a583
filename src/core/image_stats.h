// Image comparison measures used by the reference tests and the benchmarks, with the noise estimate that
// makes their tolerances honest: two independent half renders a, b give the per-pixel variance of their mean.
#pragma once

#include <array>

#include "core/image.h"

namespace npt {

struct ImageComparison {
    std::array<double, 3> mean_test{};  // image mean per channel
    std::array<double, 3> mean_ref{};
    std::array<double, 3> mean_rel_err{};  // (mean_test - mean_ref) / mean_ref
    double rel_mse = 0;                    // mean over pixels and channels of (x - r)^2 / (r^2 + 0.01)
};

// `test` and `ref` must have the same size (throws npt::Error otherwise); uses the first 3 channels.
ImageComparison compare_images(const Image& test, const Image& ref);

// Noise of a render made as the average of two independent halves a and b, measured against `ref`:
struct NoiseEstimate {
    double rel_mse_expected = 0;       // mean((a-b)^2/4 / (r^2+0.01)): the relMSE that noise alone explains
    double rel_mse_excess = 0;         // measured relMSE of (a+b)/2 minus the expected one
    double rel_mse_excess_stderr = 0;  // standard error of that excess over pixels
    std::array<double, 3> mean_stderr{};  // standard error of the image mean per channel
};
NoiseEstimate estimate_noise(const Image& half_a, const Image& half_b, const Image& ref);

Image average(const Image& a, const Image& b);

}  // namespace npt
