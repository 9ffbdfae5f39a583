// Image quality measures of the NeRF literature, PSNR and SSIM, for `nerfpt eval`: numbers that can be put
// beside published tables. Both take values as the images store them (for NeRF renders and ground truth: the
// sRGB-encoded values in [0, 1], not linear light) with a data range of 1, and use RGB (alpha is ignored).
#pragma once

#include "core/image.h"

namespace npt {

// Mean over pixels and the three RGB channels of (a - b)^2, in double precision.
double mean_squared_error(const Image& a, const Image& b);

// PSNR in dB for data range 1: -10 log10(MSE) with the MSE above. Identical images give +infinity (no cap:
// a capped value would look like a real measurement in a table); a mean over images then is +infinity too,
// and JSON writers store it as null.
double psnr(const Image& a, const Image& b);

// Smallest width and height SSIM accepts: one full window must fit.
constexpr int k_ssim_window = 11;

// SSIM as Wang et al. 2004 define it and as the NeRF papers compute it (mip-NeRF's and skimage's
// `structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1)`):
// an 11x11 Gaussian window with sigma 1.5 (normalised to sum 1), K1 = 0.01, K2 = 0.03, data range 1, local
// statistics computed per channel over the 'valid' region only (window centres at least 5 pixels inside,
// no padding), the SSIM map averaged over that region, then the three channel means averaged. Local
// variances are clamped at 0 against cancellation. Symmetric in a and b; 1 for identical images.
double ssim(const Image& a, const Image& b);

// All of the above throw npt::Error when the sizes differ or an image has fewer than 3 channels; ssim() also
// when a side is smaller than k_ssim_window. Non-finite pixels give NaN.

}  // namespace npt
