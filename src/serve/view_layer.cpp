#include "serve/view_layer.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/srgb.h"

namespace npt::serve {

namespace {
constexpr ViewLayer k_layers[] = {ViewLayer::beauty, ViewLayer::alpha, ViewLayer::albedo, ViewLayer::normal,
                                  ViewLayer::depth};
}  // namespace

const char* view_layer_name(ViewLayer layer) {
    switch (layer) {
        case ViewLayer::beauty:
            return "beauty";
        case ViewLayer::alpha:
            return "alpha";
        case ViewLayer::albedo:
            return "albedo";
        case ViewLayer::normal:
            return "normal";
        case ViewLayer::depth:
            return "depth";
    }
    return "beauty";
}

std::optional<ViewLayer> parse_view_layer(const std::string& name) {
    for (ViewLayer l : k_layers)
        if (name == view_layer_name(l)) return l;
    return std::nullopt;
}

render::RenderOptions view_options(render::RenderOptions options, ViewLayer layer) {
    options.aovs = 0;
    switch (layer) {
        case ViewLayer::beauty:
            break;
        case ViewLayer::alpha:
            options.transparent = true;
            break;
        case ViewLayer::albedo:
            options.aovs = render::k_aov_albedo;
            break;
        case ViewLayer::normal:
            options.aovs = render::k_aov_normal;
            break;
        case ViewLayer::depth:
            options.aovs = render::k_aov_depth;
            break;
    }
    return options;
}

Image view_image(ViewLayer layer, const Image& rendered, const render::AovImages& aovs, float depth_range) {
    const int w = rendered.width, h = rendered.height;
    Image out(w, h, 3);
    const size_t n = size_t(w) * size_t(h);
    // Display values v in [0, 1] go in as sRGB-decoded linear values, so that the tone map shows v.
    const auto put = [&](size_t i, float r, float g, float b) {
        float* p = out.pixels.data() + i * 3;
        p[0] = srgb_to_linear(std::clamp(r, 0.0f, 1.0f));
        p[1] = srgb_to_linear(std::clamp(g, 0.0f, 1.0f));
        p[2] = srgb_to_linear(std::clamp(b, 0.0f, 1.0f));
    };
    const auto need = [&](const Image& img, int channels, const char* what) {
        if (img.width != w || img.height != h || img.channels != channels)
            throw Error(std::string("viewer: the render has no ") + what + " layer of its size");
    };
    switch (layer) {
        case ViewLayer::beauty:
            throw Error("viewer: the beauty is shown as rendered");
        case ViewLayer::alpha:
            if (rendered.channels != 4) throw Error("viewer: the render has no alpha");
            for (size_t i = 0; i < n; ++i) {
                const float a = rendered.pixels.data()[i * 4 + 3];
                put(i, a, a, a);
            }
            break;
        case ViewLayer::albedo:
            need(aovs.albedo, 3, "albedo");
            std::copy(aovs.albedo.pixels.data(), aovs.albedo.pixels.data() + n * 3,
                      out.pixels.data());  // linear colour already
            break;
        case ViewLayer::normal:
            need(aovs.normal, 3, "normal");
            for (size_t i = 0; i < n; ++i) {
                const float* v = aovs.normal.pixels.data() + i * 3;
                if (v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f) continue;  // nothing met: black
                put(i, 0.5f + 0.5f * v[0], 0.5f + 0.5f * v[1], 0.5f + 0.5f * v[2]);
            }
            break;
        case ViewLayer::depth:
            need(aovs.depth, 1, "depth");
            for (size_t i = 0; i < n; ++i) {
                const float d = aovs.depth.pixels.data()[i];
                const float v = std::isfinite(d) && depth_range > 0.0f ? 1.0f - d / depth_range : 0.0f;
                put(i, v, v, v);
            }
            break;
    }
    return out;
}

}  // namespace npt::serve
