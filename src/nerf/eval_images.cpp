#include "nerf/eval_images.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/image_io.h"

namespace npt::nerf {

Image ground_truth_image(const Dataset& data, size_t index, Rgb background) {
    if (index >= data.cameras.size())
        throw Error("ground truth: frame " + std::to_string(index) + " is out of range (the data set has " +
                    std::to_string(data.cameras.size()) + " frames)");
    Image img(data.width, data.height, 3);
    const uint8_t* src = data.image(index);
    const float bg[3] = {background.x, background.y, background.z};
    for (size_t i = 0, n = size_t(data.width) * size_t(data.height); i < n; ++i) {
        const float a = float(src[4 * i + 3]) / 255.0f;
        for (size_t c = 0; c < 3; ++c)
            img.pixels[3 * i + c] = float(src[4 * i + c]) / 255.0f * a + bg[c] * (1.0f - a);
    }
    return img;
}

Image error_heat_map(const Image& a, const Image& b, float gain) {
    if (a.width != b.width || a.height != b.height || a.channels < 3 || b.channels < 3)
        throw Error("error heat map: image sizes differ (" + std::to_string(a.width) + "x" +
                    std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                    std::to_string(b.height) + ")");
    Image heat(a.width, a.height, 3);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const float* p = a.at(x, y);
            const float* q = b.at(x, y);
            const float e = (std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2])) / 3.0f;
            // NaN (a broken render) shows as full error, not as black.
            const float t = std::isnan(e) ? 1.0f : std::clamp(e * gain, 0.0f, 1.0f);
            float* h = heat.at(x, y);
            h[0] = std::clamp(3.0f * t, 0.0f, 1.0f);
            h[1] = std::clamp(3.0f * t - 1.0f, 0.0f, 1.0f);
            h[2] = std::clamp(3.0f * t - 2.0f, 0.0f, 1.0f);
        }
    return heat;
}

Image over_plate(const Image& render, Rgb background, const Image& plate) {
    if (render.channels != 4) throw Error("over_plate: the render has no alpha");
    if (render.width != plate.width || render.height != plate.height || plate.channels < 3)
        throw Error("over_plate: the render and the plate differ in size");
    Image out(render.width, render.height, 3);
    const size_t pixels = size_t(render.width) * size_t(render.height);
    for (size_t p = 0; p < pixels; ++p) {
        const float* r = &render.pixels[p * 4];
        const float* q = &plate.pixels[p * size_t(plate.channels)];
        for (int c = 0; c < 3; ++c)
            out.pixels[p * 3 + size_t(c)] = r[c] + (q[c] - background[c]) * (1.0f - r[3]);
    }
    return out;
}

Image comparison_strip(const Image& ground_truth, const Image& render) {
    constexpr float k_error_gain = 4.0f;  // typical NeRF errors are a few percent: x4 makes them visible
    const Image heat = error_heat_map(ground_truth, render, k_error_gain);
    const int w = ground_truth.width, h = ground_truth.height;
    Image strip(3 * w, h, 3);
    const Image* panels[3] = {&ground_truth, &render, &heat};
    for (int k = 0; k < 3; ++k)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) std::copy_n(panels[k]->at(x, y), 3, strip.at(k * w + x, y));
    return strip;
}

Image encoded_to_linear(const Image& encoded) {
    Image out(encoded.width, encoded.height, 3);
    for (int y = 0; y < encoded.height; ++y)
        for (int x = 0; x < encoded.width; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, y)[c] = srgb_to_linear(encoded.at(x, y)[c]);
    return out;
}

}  // namespace npt::nerf
