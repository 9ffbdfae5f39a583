// Per-image exposure and white balance for NeRF training (issue 25: a phone changes both while it films). The
// trainer multiplies image i's predicted colour by exp(g_i), one gain per channel, and learns g_i by Adam beside
// the network; the gains' mean over the images is held at 0 after every step, so the model itself renders the
// exposure of the average training image, which is what a held-out view of the same video has when its camera
// did not adjust. Off by default (training.exposure_per_image).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace npt::nerf {

struct ExposureState {
    std::vector<Rgb> log_gain;  // g_i per training image
    std::vector<Rgb> m, v;      // Adam's moments
    uint64_t step = 0;          // Adam steps taken
    bool empty() const { return log_gain.empty(); }
};

// Gains that start at 1 for `images` images.
ExposureState make_exposure_state(size_t images);

// exp(g) per channel.
Rgb exposure_gain(const ExposureState& s, size_t image);

// One Adam step with the per-image gradient d loss / d g (Huber's, summed over the image's rays this step);
// images without rays this step (zero gradient) keep their gain and moments. Then the mean of g over the images
// is subtracted. Throws npt::Error on a non-finite gradient.
void exposure_step(ExposureState& s, const std::vector<Rgb>& grad, float learning_rate);

// The smallest and largest gain over the images, per channel: what `nerfpt train` reports.
struct ExposureRange {
    Rgb lo, hi;
};
ExposureRange exposure_range(const ExposureState& s);

}  // namespace npt::nerf
