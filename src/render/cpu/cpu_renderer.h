// The CPU backend: Embree for rays, TBB over 16x16 tiles, one RNG stream per pixel (so the image depends on
// the seed only, never on the thread count or the order tiles run in).
#pragma once

#include <memory>

#include "render/scene_data.h"

#include "render/renderer.h"
#include "render/sample_sums.h"
#include "scene/animation.h"

namespace npt::render::cpu {

class EmbreeScene;

// A scene prepared once (scene data, volumes' grids or models, Embree's BVH) for many renders at one resolution:
// the frames of a sequence. update() follows scene::pose_scene, touching only what moved. The scene must
// outlive it.
class CpuFrameRenderer {
  public:
    CpuFrameRenderer(const scene::Scene& scene, int width, int height);
    ~CpuFrameRenderer();
    CpuFrameRenderer(const CpuFrameRenderer&) = delete;
    CpuFrameRenderer& operator=(const CpuFrameRenderer&) = delete;
    void update(const scene::PoseChanges& changes);
    // options' width and height must be the prepared ones.
    Image render(const RenderOptions& options, const ProgressFn& progress, AovImages* aovs = nullptr);
    // The sums of samples [begin, end) of options.spp (render/sample_sums.h): a process's share of a render
    // split by sample; merged in sample order and resolved, the shares give render()'s image bit for bit.
    PartialFilm render_partial(const RenderOptions& options, uint32_t begin, uint32_t end,
                               const ProgressFn& progress = {});

  private:
    template <class PixelFn>
    void for_each_pixel(const RenderOptions& options, uint64_t samples_per_pixel, const ProgressFn& progress,
                        const PixelFn& pixel);

    const scene::Scene& m_scene;
    std::unique_ptr<SceneData> m_data;
    std::unique_ptr<EmbreeScene> m_embree;
    int m_width, m_height;
    uint64_t m_dropped = 0;  // NaN or infinite samples of the last render
};

// render::render's CPU half (renderer.h): RGB or, with options.transparent, RGBA; the AOVs into *aovs.
Image render_cpu(const scene::Scene& scene, const RenderOptions& options, const ProgressFn& progress,
                 AovImages* aovs = nullptr);

}  // namespace npt::render::cpu
