// The OptiX backend of `nerfpt render`: the CPU backend's image (the same integrator, samplers and scene data)
// traced by OptiX on the GPU. Launches a few samples per pixel at a time so that progress is reported and an
// interrupt stops the render between launches.
#pragma once

#include "render/renderer.h"

namespace npt::gpu {

// Throws npt::Error with a one-line reason when no GPU, no driver or no OptiX runtime can be used. With
// `denoised`, also runs the denoiser (albedo and normal guides) and puts its image there.
Image render_optix(const scene::Scene& scene, const render::RenderOptions& options,
                   const render::ProgressFn& progress, Image* denoised = nullptr);

}  // namespace npt::gpu
