// The entry point every front end calls: render a loaded scene into a linear RGB(A) image and its AOVs.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/image.h"
#include "render/film.h"
#include "scene/scene.h"

namespace npt::render {

struct RenderOptions {
    int width = 0;  // 0: take the scene's setting
    int height = 0;
    int spp = 0;
    int max_depth = -1;  // -1: the scene's setting
    uint64_t seed = 0;
    int threads = 0;  // 0: all hardware threads
    std::string backend = "cpu";
    bool transparent = false;  // or the scene's setting: the image is RGBA, premultiplied, without the background
    uint32_t aovs = 0;         // AovBits: the layers render() writes into *aovs
};

// Upper bounds that keep a typo from allocating or running forever; checked by validate().
constexpr int k_max_resolution = 32768;
constexpr int k_max_spp = 1 << 20;
constexpr int k_max_depth = 1024;
constexpr long long k_max_pixels = 1LL << 27;  // 134 M pixels: 1.6 GB of float RGB

// Called from worker threads (serialised by the renderer) with the number of pixel-samples done so far.
using ProgressFn = std::function<void(uint64_t done, uint64_t total)>;

// Fills unset options from the scene and checks ranges; throws npt::Error naming the option.
RenderOptions resolve_options(const scene::Scene& scene, const RenderOptions& options);

// Renders with resolved options; the image has 3 channels, linear radiance, row 0 at the top, or with
// resolved.transparent 4: premultiplied RGBA, alpha the camera rays' coverage (render/first_hit.h). With `aovs`
// the layers of resolved.aovs go there (render/film.h).
Image render(const scene::Scene& scene, const RenderOptions& resolved, const ProgressFn& progress = {},
             AovImages* aovs = nullptr);

}  // namespace npt::render
