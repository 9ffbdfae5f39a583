#include "nerf/image_exposure.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace npt::nerf {

namespace {
// Adam for the gains with fixed betas (the defaults of optimizer.*, not the config's: a config changing them leaves
// these alone); a gain moves at most ~learning_rate per step. The update is adam.cpp's adam_update written
// again for 3 floats per image: see the note in docs/benchmarks.md (per-image exposure) on reusing Adam.
constexpr double k_beta1 = 0.9, k_beta2 = 0.99;
constexpr float k_epsilon = 1e-10f;
}  // namespace

ExposureState make_exposure_state(size_t images) {
    ExposureState s;
    s.log_gain.assign(images, Rgb(0.0f));
    s.m.assign(images, Rgb(0.0f));
    s.v.assign(images, Rgb(0.0f));
    return s;
}

Rgb exposure_gain(const ExposureState& s, size_t image) {
    const Rgb& g = s.log_gain[image];
    return {std::exp(g.x), std::exp(g.y), std::exp(g.z)};
}

void exposure_step(ExposureState& s, const std::vector<Rgb>& grad, float learning_rate) {
    if (grad.size() != s.log_gain.size())
        throw Error("exposure gradient has " + std::to_string(grad.size()) + " images, the state " +
                    std::to_string(s.log_gain.size()));
    for (size_t i = 0; i < grad.size(); ++i)
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(grad[i][c]))
                throw Error("exposure gradient of image " + std::to_string(i) + " is NaN or Inf at step " +
                            std::to_string(s.step));
    ++s.step;
    const double t = double(s.step);
    const float c1 = float(1.0 / (1.0 - std::pow(k_beta1, t))), c2 = float(1.0 / (1.0 - std::pow(k_beta2, t)));
    Rgb mean(0.0f);
    for (size_t i = 0; i < grad.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const float g = grad[i][c];
            if (g == 0.0f) continue;  // no ray of this image this step
            float& m = s.m[i][c];
            float& v = s.v[i][c];
            m = float(k_beta1) * m + float(1.0 - k_beta1) * g;
            v = float(k_beta2) * v + float(1.0 - k_beta2) * g * g;
            s.log_gain[i][c] -= learning_rate * (m * c1) / (std::sqrt(v * c2) + k_epsilon);
        }
        mean = mean + s.log_gain[i];
    }
    mean = mean / float(std::max<size_t>(grad.size(), 1));
    for (Rgb& g : s.log_gain) g = g - mean;
}

ExposureRange exposure_range(const ExposureState& s) {
    ExposureRange r{Rgb(1.0f), Rgb(1.0f)};
    for (size_t i = 0; i < s.log_gain.size(); ++i) {
        const Rgb g = exposure_gain(s, i);
        for (int c = 0; c < 3; ++c) {
            r.lo[c] = i == 0 ? g[c] : std::min(r.lo[c], g[c]);
            r.hi[c] = i == 0 ? g[c] : std::max(r.hi[c], g[c]);
        }
    }
    return r;
}

}  // namespace npt::nerf
