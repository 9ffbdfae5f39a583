// The OptiX backend of `nerfpt render`: the CPU backend's image (the same integrator, samplers and scene data)
// traced by OptiX on the GPU. Launches a few samples per pixel at a time so that progress is reported and an
// interrupt stops the render between launches.
#pragma once

#include <memory>

#include "render/renderer.h"
#include "scene/animation.h"

namespace npt::gpu {

// A scene on the GPU, ready for many renders (frames) at one resolution: the scene data, acceleration
// structures and pipeline are built once, in the constructor. Throws npt::Error with a one-line reason when no
// GPU, no driver or no OptiX runtime can be used.
class OptixRenderer {
  public:
    OptixRenderer(const scene::Scene& scene, int width, int height);
    ~OptixRenderer();
    OptixRenderer(const OptixRenderer&) = delete;
    OptixRenderer& operator=(const OptixRenderer&) = delete;

    // options.spp samples per pixel from options.seed (width and height as constructed): RGB, or RGBA with
    // options.transparent. With `denoised`, also runs the denoiser (albedo and normal guides) and puts its image
    // there; with `aovs`, the layers of options.aovs go there (render/film.h).
    Image render(const render::RenderOptions& options, const render::ProgressFn& progress,
                 Image* denoised = nullptr, render::AovImages* aovs = nullptr);
    // The same render into the renderer's own page-locked frame (frames of a viewer or an animation): no image
    // allocated per frame and a download at the bus's speed. The reference holds until the next call.
    const Image& render_frame(const render::RenderOptions& options);
    // render() (no denoiser) into `out`, reusing its storage when it has the frame's size and channels.
    void render_into(const render::RenderOptions& options, Image& out, const render::ProgressFn& progress,
                     render::AovImages* aovs = nullptr);
    // Page-locks `image`'s storage (cudaHostRegister) until the returned handle goes, so that render_into's
    // download into it runs at the bus's speed; nullptr when the driver refuses (downloads work without). The
    // image must keep its storage (no resize, no free) while the handle lives.
    static std::shared_ptr<void> pin(Image& image);
    // After scene::pose_scene moved the scene this renderer was built from: the moved meshes' vertices are
    // uploaded and the acceleration structure rebuilt (only when a mesh moved), the lights, the volumes'
    // placements and the camera updated. Grids, models, textures and the pipeline are kept.
    void update(const scene::PoseChanges& changes);

  private:
    // render and render_into: into `out`, reused when it has the frame's size and channels.
    void render_to(const render::RenderOptions& options, Image& out, const render::ProgressFn& progress,
                   Image* denoised, render::AovImages* aovs);
    struct State;
    struct PinnedImage;
    std::unique_ptr<State> m;
};

// One render: construct, render, release.
Image render_optix(const scene::Scene& scene, const render::RenderOptions& options,
                   const render::ProgressFn& progress, Image* denoised = nullptr,
                   render::AovImages* aovs = nullptr);

}  // namespace npt::gpu
