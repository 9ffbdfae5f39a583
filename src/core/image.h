// A float image in memory (linear light), row 0 at the top. Reading and writing files is in core/image_io.h.
#pragma once

#include <vector>

#include "core/vec.h"

namespace npt {

struct Image {
    int width = 0;
    int height = 0;
    int channels = 3;  // 3 (RGB) or 4 (RGBA)
    std::vector<float> pixels;  // width * height * channels, row-major from the top-left

    Image() = default;
    Image(int w, int h, int c = 3) : width(w), height(h), channels(c), pixels(size_t(w) * size_t(h) * size_t(c), 0.0f) {}
    float* at(int x, int y) { return &pixels[(size_t(y) * size_t(width) + size_t(x)) * size_t(channels)]; }
    const float* at(int x, int y) const { return &pixels[(size_t(y) * size_t(width) + size_t(x)) * size_t(channels)]; }
    Rgb rgb(int x, int y) const {
        const float* p = at(x, y);
        return {p[0], p[1], p[2]};
    }
};

}  // namespace npt
