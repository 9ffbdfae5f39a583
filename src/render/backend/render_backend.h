// Which renderer `nerfpt render` uses: the CPU (Embree + TBB) or OptiX on a GPU, and the call that renders
// with it. Front ends use this instead of render::render so that none of them needs CUDA or OptiX headers.
#pragma once

#include <memory>
#include <string>

#include "render/renderer.h"
#include "render/sample_sums.h"
#include "scene/animation.h"

namespace npt::render {

// True when this binary has the OptiX backend.
bool optix_backend_built();

// requested: "" or "auto" (optix when built and a GPU is usable, else cpu with *note saying why), "cpu", or
// "optix" (npt::Error naming the reason when it cannot be used: no silent fallback).
std::string choose_render_backend(const std::string& requested, std::string* note);

// A scene prepared for many renders at one resolution (frames of an animation or a viewer, benchmarks): the scene
// data, volumes and acceleration structures (and on OptiX the pipeline) are built once; update() follows
// scene::pose_scene and touches only what moved.
class SceneRenderer {
  public:
    virtual ~SceneRenderer() = default;
    // After scene::pose_scene moved the scene this renderer was prepared from.
    virtual void update(const scene::PoseChanges& changes) = 0;
    // Renders `resolved` (its width and height must be the prepared ones); see render_with_backend.
    virtual Image render(const RenderOptions& resolved, const ProgressFn& progress = {},
                         Image* denoised = nullptr, AovImages* aovs = nullptr) = 0;
    // The same render into a frame the renderer keeps (a viewer's or an animation's frames): OptiX downloads into
    // page-locked memory it reuses instead of a new image. The reference holds until the next call.
    // The sums of samples [begin, end) of resolved.spp (render/sample_sums.h): one MPI rank's share of a still.
    // The CPU's; other backends throw npt::Error.
    virtual PartialFilm render_partial(const RenderOptions& resolved, uint32_t begin, uint32_t end,
                                       const ProgressFn& progress = {});
    virtual const Image& render_frame(const RenderOptions& resolved) {
        m_frame = render(resolved);
        return m_frame;
    }
    // render() into `out`, whose storage is reused when it already has the frame's size and channels (a
    // sequence's frames cycle through a few images): no allocation per frame. OptiX downloads straight into it.
    virtual void render_into(const RenderOptions& resolved, Image& out, const ProgressFn& progress = {},
                             AovImages* aovs = nullptr) {
        out = render(resolved, progress, nullptr, aovs);
    }
    // Makes render_into's writes into `image` faster while the handle lives (OptiX: page-locked memory); nullptr
    // where that means nothing (the CPU) or cannot be had. `image` must keep its storage while the handle lives:
    // call it once render_into has sized the image.
    virtual std::shared_ptr<void> pin(Image& image) {
        (void)image;
        return nullptr;
    }

  private:
    Image m_frame;
};
std::unique_ptr<SceneRenderer> prepare_renderer(const scene::Scene& scene, const RenderOptions& resolved);

// Renders with resolved.backend ("cpu" or "optix"): RGB, or RGBA with resolved.transparent (render::render).
// With `denoised` (OptiX only: npt::Error otherwise), the denoiser's image goes there and the noisy one is
// returned. With `aovs`, the layers of resolved.aovs go there (render/film.h).
Image render_with_backend(const scene::Scene& scene, const RenderOptions& resolved, const ProgressFn& progress = {},
                          Image* denoised = nullptr, AovImages* aovs = nullptr);

}  // namespace npt::render
