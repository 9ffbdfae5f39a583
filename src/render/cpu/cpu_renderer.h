// The CPU backend: Embree for rays, TBB over 16x16 tiles, one RNG stream per pixel (so the image depends on
// the seed only, never on the thread count or the order tiles run in).
#pragma once

#include "render/renderer.h"

namespace npt::render::cpu {

// render::render's CPU half (renderer.h): RGB or, with options.transparent, RGBA; the AOVs into *aovs.
Image render_cpu(const scene::Scene& scene, const RenderOptions& options, const ProgressFn& progress,
                 AovImages* aovs = nullptr);

}  // namespace npt::render::cpu
