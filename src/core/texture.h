// Texture lookup shared by CPU and GPU: bilinear filtering of linear RGBA texels with repeat wrapping.
// glTF uv convention: (0, 0) is the top-left of the image, v grows downwards.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt {

struct Rgba {
    float r = 0, g = 0, b = 0, a = 1;
    NPT_HD Rgb rgb() const { return {r, g, b}; }
};

struct TextureView {
    const float* rgba = nullptr;  // width * height * 4, row 0 at the top
    int width = 0;
    int height = 0;

    NPT_HD bool valid() const { return rgba != nullptr && width > 0 && height > 0; }

    NPT_HD Rgba texel(int x, int y) const {
        x %= width;
        y %= height;
        if (x < 0) x += width;
        if (y < 0) y += height;
        const float* p = rgba + (size_t(y) * size_t(width) + size_t(x)) * 4;
        return {p[0], p[1], p[2], p[3]};
    }

    // Bilinear, texel centres at half-integers, repeat wrap.
    NPT_HD Rgba sample(Vec2 uv) const {
        float fx = uv.x * float(width) - 0.5f, fy = uv.y * float(height) - 0.5f;
        if (!(fx == fx) || !(fy == fy) || fabsf(fx) > 1e8f || fabsf(fy) > 1e8f) return texel(0, 0);
        float x0f = floorf(fx), y0f = floorf(fy);
        float tx = fx - x0f, ty = fy - y0f;
        int x0 = int(x0f), y0 = int(y0f);
        Rgba a = texel(x0, y0), b = texel(x0 + 1, y0), c = texel(x0, y0 + 1), d = texel(x0 + 1, y0 + 1);
        auto mix = [&](float va, float vb, float vc, float vd) {
            return (va * (1 - tx) + vb * tx) * (1 - ty) + (vc * (1 - tx) + vd * tx) * ty;
        };
        return {mix(a.r, b.r, c.r, d.r), mix(a.g, b.g, c.g, d.g), mix(a.b, b.b, c.b, d.b), mix(a.a, b.a, c.a, d.a)};
    }
};

}  // namespace npt
